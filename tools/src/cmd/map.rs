//! `beamfield map from-log`: a ROS map_server map (YAML + PGM, optionally a PNG) built from a
//! CARMEN laser log with known poses ([`crate::mapping`]).

use super::log::{max_range_json, read_log};
use crate::draw::map_picture::write_png;
use crate::input::carmen::{LogError, MaxRange, ReadOptions};
use crate::mapping::{
    build_from_log, write_map_server, MapIoError, MappingError, MappingOptions, MappingStats,
    FREE_THRESH, OCCUPIED_THRESH,
};
use crate::progress::Progress;
use clap::{Args, Subcommand};
use serde::{Serialize, Serializer};
use std::fmt;
use std::path::PathBuf;

/// `beamfield map …`
#[derive(Subcommand, Debug)]
pub enum MapCommand {
    /// Build a ROS map_server map (YAML + P5 PGM) from a CARMEN laser log with known poses.
    ///
    /// Every FLASER scan is projected from its logged (laser) pose, beam i at −90° + i·180°/n
    /// (180°/(n − 1) for an odd n: 181 or 361 beams span −90° … +90°) counter-clockwise. End points are occupied evidence; the cells each beam crosses before
    /// its end point are free evidence (exact grid traversal); max-range readings clear space
    /// only up to --max-range-free. Log-odds: +0.847 per hit, −0.405 per pass, clamped to
    /// [−2, 3.5]. Cells are written trinary with map_server's defaults: 0 occupied (p > 0.65),
    /// 254 free (p < 0.196), 205 unknown. The PGM is written beside the YAML with the same stem.
    /// See docs/carmen-mapping.md.
    FromLog(FromLogArgs),
}

/// Arguments of `beamfield map from-log`.
#[derive(Args, Debug)]
pub struct FromLogArgs {
    /// The CARMEN log (old format, FLASER lines with poses).
    pub log: PathBuf,
    /// Output YAML file; the PGM is written beside it (MAP.yaml → MAP.pgm).
    #[arg(short, long, value_name = "MAP.yaml")]
    pub output: PathBuf,
    /// Cell side in metres.
    #[arg(long, default_value_t = 0.05, value_name = "R")]
    pub resolution: f64,
    /// The log's max-range ("no return") value in metres. Default: detected from the ranges
    /// (the most repeated value at the top of the range histogram; 81.83 in the Intel log).
    #[arg(long, value_name = "M")]
    pub max_range: Option<f32>,
    /// How far a max-range reading clears space, metres; 0 gives max-range readings no weight.
    #[arg(long, default_value_t = 8.0, value_name = "M")]
    pub max_range_free: f64,
    /// Margin around the data's extent, metres.
    #[arg(long, default_value_t = 1.0, value_name = "M")]
    pub margin: f64,
    /// Also write a PNG picture (free white, occupied black, unknown grey, trajectory red).
    #[arg(long, value_name = "PATH")]
    pub png: Option<PathBuf>,
    /// Skip malformed lines (they are counted and reported) instead of stopping at the first.
    #[arg(long)]
    pub skip_bad_lines: bool,
    /// Refuse a map of more cells than this (the builder needs about 13 bytes per cell; the
    /// Intel map is 0.78 M cells); at most 268,435,456.
    #[arg(long = "max-cells", default_value_t = crate::input::map::DEFAULT_MAX_CELLS,
          value_parser = clap::value_parser!(u64).range(1..=crate::mapping::MAX_CELLS))]
    pub max_cells: u64,
}

/// Why `map from-log` failed.
#[derive(Debug)]
#[non_exhaustive]
pub enum FromLogError {
    /// A bad option, or a log without a max-range value or scans (the message says which).
    Usage(String),
    /// The log could not be read.
    Log(LogError),
    /// The map could not be built.
    Mapping(MappingError),
    /// The map or its picture could not be written.
    Write(MapIoError),
}

impl fmt::Display for FromLogError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Usage(m) => f.write_str(m),
            Self::Log(e) => write!(f, "{e}"),
            Self::Mapping(e) => write!(f, "{e}"),
            Self::Write(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for FromLogError {}

fn fail(message: impl Into<String>) -> FromLogError {
    FromLogError::Usage(message.into())
}

/// Runs a `map` subcommand.
///
/// # Errors
/// [`FromLogError`].
pub fn run_map(command: &MapCommand) -> Result<FromLogReport, FromLogError> {
    match command {
        MapCommand::FromLog(args) => run(args),
    }
}

/// Runs `beamfield map from-log`; skipped lines and progress go to stderr.
///
/// # Errors
/// [`FromLogError`]: bad options, an unreadable log, no max-range value, no scan, a failed
/// write.
pub fn run(args: &FromLogArgs) -> Result<FromLogReport, FromLogError> {
    if !(args.resolution.is_finite() && args.resolution > 0.0) {
        return Err(fail("--resolution must be a finite number of metres > 0"));
    }
    if !(args.margin.is_finite() && args.margin >= 0.0) {
        return Err(fail("--margin must be a finite number of metres ≥ 0"));
    }
    if !(args.max_range_free.is_finite() && args.max_range_free >= 0.0) {
        return Err(fail(
            "--max-range-free must be a finite number of metres ≥ 0",
        ));
    }
    let log = match read_log(
        &args.log,
        ReadOptions {
            max_range_m: args.max_range,
            skip_bad_lines: args.skip_bad_lines,
        },
    ) {
        Ok(log) => log,
        Err(e) => return Err(FromLogError::Log(e)),
    };
    for bad in &log.bad_lines {
        eprintln!("skipped {bad}");
    }
    if log.bad_line_count > log.bad_lines.len() {
        eprintln!(
            "skipped {} more malformed lines",
            log.bad_line_count - log.bad_lines.len()
        );
    }
    let Some(max_range_m) = log.max_range.value_m() else {
        return Err(fail(format!(
            "{}: no max-range value could be detected (no single value dominates the top of the \
             range histogram); give it with --max-range M",
            args.log.display()
        )));
    };
    if log.scans.is_empty() {
        return Err(fail(format!(
            "{}: no FLASER scan in the log",
            args.log.display()
        )));
    }
    let mut options = MappingOptions::new(max_range_m);
    options.resolution_m = args.resolution;
    options.margin_m = args.margin;
    options.max_cells = args.max_cells;
    options.max_range_free_m = (args.max_range_free > 0.0).then_some(args.max_range_free);
    let progress = Progress::new("mapping");
    let built = build_from_log(&log, &options, |done, total| {
        progress.update(done, total, " scans");
    });
    let (log_odds, stats) = match built {
        Ok(b) => b,
        Err(e) => return Err(FromLogError::Mapping(e)),
    };
    let grid = log_odds.to_occupancy(OCCUPIED_THRESH, FREE_THRESH);
    let written = match write_map_server(&grid, &args.output) {
        Ok(w) => w,
        Err(e) => return Err(FromLogError::Write(e)),
    };
    if let Some(png) = &args.png {
        let trajectory: Vec<(f64, f64)> = log
            .scans
            .iter()
            .map(|s| (s.pose_f64.x_m, s.pose_f64.y_m))
            .collect();
        if let Err(e) = write_png(&grid, &trajectory, png) {
            return Err(FromLogError::Write(e));
        }
    }
    let g = grid.geometry();
    let (occupied, free, unknown) = grid.counts();
    Ok(FromLogReport {
        yaml: written.yaml,
        pgm: written.pgm,
        png: args.png.clone(),
        width: g.width,
        height: g.height,
        resolution_m: g.resolution_m,
        origin_m: [g.origin_x_m, g.origin_y_m],
        occupied,
        free,
        unknown,
        max_range: max_range_json(&log.max_range),
        max_range_m,
        max_range_given: matches!(log.max_range, MaxRange::Given(_)),
        max_range_free_m: options.max_range_free_m,
        readings: stats,
        bad_lines: log.bad_lines.iter().map(ToString::to_string).collect(),
        bad_lines_total: log.bad_line_count,
    })
}

/// What `map from-log` wrote.
#[derive(Debug)]
pub struct FromLogReport {
    /// The YAML file.
    pub yaml: PathBuf,
    /// The PGM file.
    pub pgm: PathBuf,
    /// The PNG picture (`--png`).
    pub png: Option<PathBuf>,
    /// Grid width, cells.
    pub width: usize,
    /// Grid height, cells.
    pub height: usize,
    /// Cell side, metres.
    pub resolution_m: f64,
    /// Map origin (x, y), metres.
    pub origin_m: [f64; 2],
    /// Occupied cells.
    pub occupied: usize,
    /// Free cells.
    pub free: usize,
    /// Unknown cells.
    pub unknown: usize,
    /// The max-range value and where it came from, as JSON.
    pub max_range: serde_json::Value,
    /// The max-range value, metres.
    pub max_range_m: f32,
    /// It was given (`--max-range`) rather than detected.
    pub max_range_given: bool,
    /// How far max-range readings clear space, metres.
    pub max_range_free_m: Option<f64>,
    /// Hits, max-range and invalid readings.
    pub readings: MappingStats,
    /// The malformed lines kept (skipped with `--skip-bad-lines`).
    pub bad_lines: Vec<String>,
    /// Malformed lines in all.
    pub bad_lines_total: usize,
}

impl Serialize for FromLogReport {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let Self {
            yaml,
            pgm,
            png,
            width,
            height,
            resolution_m,
            origin_m,
            occupied,
            free,
            unknown,
            max_range,
            max_range_free_m,
            readings,
            bad_lines,
            bad_lines_total,
            ..
        } = self;
        serde_json::json!({
            "yaml": yaml,
            "pgm": pgm,
            "png": png,
            "width": width,
            "height": height,
            "resolution_m": resolution_m,
            "origin_m": origin_m,
            "cells": { "occupied": occupied, "free": free, "unknown": unknown },
            "max_range": max_range,
            "max_range_free_m": max_range_free_m,
            "readings": readings,
            "bad_lines": bad_lines,
            "bad_lines_total": bad_lines_total,
        })
        .serialize(s)
    }
}

impl fmt::Display for FromLogReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.readings;
        write!(
            f,
            "wrote {} and {}: {} × {} cells of {} m, origin ({}, {}) m",
            self.yaml.display(),
            self.pgm.display(),
            self.width,
            self.height,
            self.resolution_m,
            self.origin_m[0],
            self.origin_m[1]
        )?;
        write!(
            f,
            "\ncells: {} occupied, {} free, {} unknown",
            self.occupied, self.free, self.unknown
        )?;
        write!(
            f,
            "\n{} scans: {} hits, {} max-range readings (max range {} m, {}), {} invalid",
            r.scans,
            r.hits,
            r.max_range,
            self.max_range_m,
            if self.max_range_given {
                "given"
            } else {
                "detected"
            },
            r.invalid
        )?;
        if let Some(png) = &self.png {
            write!(f, "\npicture: {}", png.display())?;
        }
        if self.bad_lines_total > 0 {
            write!(f, "\n{} malformed lines skipped", self.bad_lines_total)?;
        }
        Ok(())
    }
}
