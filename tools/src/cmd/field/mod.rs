//! `beamfield field …`: distance-field blobs (the likelihood field's map, for flash): build one
//! from a map, re-encode it, score a scan against map variants, describe it, query it, render
//! it. One module per subcommand; [`FieldReport`] is what any of them reports.

pub mod build;
pub mod encode;
pub mod info;
pub mod query;
pub mod render;
pub mod score_variants;

pub use crate::blob::FieldError;
use clap::{Args, Subcommand};
use serde::Serialize;
use std::fmt;

/// `beamfield field`: distance-field blobs (the likelihood field's map, for flash).
#[derive(Args, Debug)]
pub struct FieldArgs {
    #[command(subcommand)]
    command: FieldCommand,
}

#[derive(Subcommand, Debug)]
enum FieldCommand {
    /// Build a blob from a ROS map_server map (YAML + PGM/PNG).
    ///
    /// Occupied cells seed an exact
    /// Euclidean distance transform; distances are coded as one byte per cell, in steps of
    /// d_max/255 and clamped at d_max, and stored raw (default) or in deduplicated tiles
    /// (--encoding tiled: the same codes, a quarter to a half of the bytes). The format is
    /// described in docs/blob-format.md.
    Build(build::BuildArgs),
    /// Rewrite a blob in another encoding (same header, same codes, so the same scores).
    Encode(encode::EncodeArgs),
    /// Score one scan of a log against each state of a map (doors open or closed) and say
    /// which explains it.
    ///
    /// Builds one distance field per --variant map (one exact transform each), scores the
    /// scan at the logged pose (or --pose) against each, prints the log-likelihoods and names
    /// the variant that beats every other by more than --margin nats. The likelihood field
    /// only looks at where beams end: a door changes the scores only if the scan's endpoints
    /// land on or near it (docs/blob-format.md, map variants).
    ScoreVariants(score_variants::ScoreVariantsArgs),
    /// Describe a blob: grid, encoding, bytes and bytes per cell (and tiles for a tiled blob).
    Info(info::InfoArgs),
    /// Look up distances: "x,y" lines on stdin, "x,y,distance_m" on stdout.
    ///
    /// Reads "x,y" lines (metres, map frame) on stdin and prints
    /// "x,y,distance_m" (or one JSON object per line with --json). Points off the map are
    /// charged the extra distance to the map's edge. Bad lines are reported on stderr with
    /// their line number and skipped; the exit status is then 1.
    Query(query::QueryArgs),
    /// Draw the field as a PNG a person can read.
    ///
    /// North up, with a title, axes in metres (map frame), a scale bar and a key: occupied
    /// cells red, distance as grey from black (0 m) to white (d_max), with a darker contour
    /// every 0.25 m.
    Render(render::RenderArgs),
}

/// What a `field` subcommand reports.
#[derive(Debug, Serialize)]
#[serde(untagged)]
pub enum FieldReport {
    /// `field build`.
    Build(build::BuildReport),
    /// `field encode`.
    Encode(encode::EncodeReport),
    /// `field score-variants`.
    ScoreVariants(score_variants::ScoreVariantsReport),
    /// `field info`.
    Info(info::InfoReport),
    /// `field query`: its answers were written line by line as the lines were read.
    Query(query::QueryReport),
    /// `field render`.
    Render(render::RenderReport),
}

impl FieldReport {
    /// The report was already written as the command ran (`field query`), so nothing is left
    /// to print.
    pub fn streamed(&self) -> bool {
        matches!(self, Self::Query(_))
    }
}

impl fmt::Display for FieldReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Build(r) => r.fmt(f),
            Self::Encode(r) => r.fmt(f),
            Self::ScoreVariants(r) => r.fmt(f),
            Self::Info(r) => r.fmt(f),
            Self::Query(_) => Ok(()),
            Self::Render(r) => r.fmt(f),
        }
    }
}

/// Runs a `field` subcommand (`json`: `field query` answers in JSON lines).
///
/// # Errors
/// [`FieldError`], with the file concerned.
pub fn run(args: FieldArgs, json: bool) -> Result<FieldReport, FieldError> {
    Ok(match args.command {
        FieldCommand::Build(a) => FieldReport::Build(build::run(&a)?),
        FieldCommand::Encode(a) => FieldReport::Encode(encode::run(&a)?),
        FieldCommand::ScoreVariants(a) => FieldReport::ScoreVariants(
            score_variants::run(&a).map_err(|e| FieldError::ScoreVariants(Box::new(e)))?,
        ),
        FieldCommand::Info(a) => FieldReport::Info(info::run(&a)?),
        FieldCommand::Query(a) => FieldReport::Query(query::run(&a, json)?),
        FieldCommand::Render(a) => FieldReport::Render(render::run(&a)?),
    })
}
