//! `beamfield field …`: build a distance-field blob from a map, query it, render it.

use crate::map::{load_map_limited, MapError, Occupancy, OccupancyMap};
use beamfield::field::{
    edt_scratch_len, emit_blob_from_squared_cells, squared_edt, BlobError, EdtError, EdtScratch,
    FieldHeader, FieldView, DEFAULT_MAX_DIST_M, EDT_INFINITY,
};
use clap::{Args, Subcommand};
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

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
    /// Euclidean distance transform; distances are stored as one byte per cell, in steps of
    /// d_max/255 and clamped at d_max. The format is described in docs/blob-format.md.
    Build {
        /// The map's YAML file (map_server format: image, resolution, origin, negate,
        /// occupied_thresh, free_thresh).
        map: PathBuf,
        /// Where to write the blob.
        #[arg(short, long)]
        output: PathBuf,
        /// Clamp distance d_max in metres (AMCL's laser_likelihood_max_dist).
        #[arg(long = "max-dist", default_value_t = DEFAULT_MAX_DIST_M)]
        max_dist: f32,
        /// Refuse a map image with more cells than this, checked from the image header before
        /// decoding (the build needs about 10 bytes per cell at its peak).
        #[arg(long = "max-cells", default_value_t = crate::map::DEFAULT_MAX_CELLS)]
        max_cells: u64,
    },
    /// Look up distances: "x,y" lines on stdin, "x,y,distance_m" on stdout.
    ///
    /// Reads "x,y" lines (metres, map frame) on stdin and prints
    /// "x,y,distance_m" (or one JSON object per line with --json). Points off the map are
    /// charged the extra distance to the map's edge. Bad lines are reported on stderr with
    /// their line number and skipped; the exit status is then 1.
    Query {
        /// The blob.
        blob: PathBuf,
    },
    /// Draw the field as a PNG a person can read.
    ///
    /// North up: occupied cells red, distance as grey from black
    /// (0 m) to white (d_max), with a darker contour every 0.25 m.
    Render {
        /// The blob.
        blob: PathBuf,
        /// Where to write the PNG.
        #[arg(short, long)]
        output: PathBuf,
    },
}

/// Anything that can go wrong in a `field` command.
#[derive(Debug)]
pub enum FieldCmdError {
    /// Loading the map.
    Map(MapError),
    /// A file could not be read or written.
    Io(PathBuf, std::io::Error),
    /// The blob is invalid, or could not be written.
    Blob(PathBuf, BlobError),
    /// The distance transform refused the grid.
    Edt(EdtError),
    /// `--max-dist` not finite or ≤ 0.
    BadMaxDist(f32),
    /// The map cannot be represented in a blob (size or f32 origin).
    Header(BlobError),
    /// Writing the PNG failed.
    Png(PathBuf, String),
    /// Some query lines were malformed (count).
    BadLines(usize),
}

impl std::fmt::Display for FieldCmdError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Map(e) => write!(f, "{e}"),
            Self::Io(p, e) => write!(f, "{}: {e}", p.display()),
            Self::Blob(p, e) => write!(f, "{}: {e}", p.display()),
            Self::Edt(e) => write!(f, "distance transform: {e}"),
            Self::BadMaxDist(d) => write!(f, "--max-dist {d}: must be finite and > 0"),
            Self::Header(e) => write!(f, "map cannot be stored as a blob: {e}"),
            Self::Png(p, e) => write!(f, "{}: {e}", p.display()),
            Self::BadLines(n) => write!(f, "{n} malformed input line(s)"),
        }
    }
}

impl std::error::Error for FieldCmdError {}

/// The transform's input for `map`: 0 on occupied cells (the seeds), [`EDT_INFINITY`] on free
/// and unknown ones, row-major from the lowest y.
pub fn edt_seeds(map: &OccupancyMap) -> Vec<u32> {
    map.cells
        .iter()
        .map(|c| {
            if *c == Occupancy::Occupied {
                0
            } else {
                EDT_INFINITY
            }
        })
        .collect()
}

/// Exact squared distances (cell units) of a map's cells to the nearest occupied cell, row 0 =
/// lowest y; [`EDT_INFINITY`] everywhere when nothing is occupied.
///
/// # Errors
/// [`FieldCmdError::Edt`] when the map is larger than the transform accepts.
pub fn squared_distances(map: &OccupancyMap) -> Result<Vec<u32>, FieldCmdError> {
    let (w, h) = (map.width as usize, map.height as usize);
    let mut grid = edt_seeds(map);
    let n = edt_scratch_len(w, h);
    let (mut sites, mut bounds, mut heights) = (vec![0u32; n], vec![0i64; n], vec![0u32; n]);
    squared_edt(
        &mut grid,
        w,
        h,
        EdtScratch {
            sites: &mut sites,
            bounds: &mut bounds,
            heights: &mut heights,
        },
    )
    .map_err(FieldCmdError::Edt)?;
    Ok(grid)
}

/// The blob header for a map (resolution and origin rounded to f32).
pub fn header_for(map: &OccupancyMap, max_dist_m: f32) -> FieldHeader {
    FieldHeader {
        width: map.width,
        height: map.height,
        cell_size_m: map.resolution_m as f32,
        origin_x_m: map.origin_x_m as f32,
        origin_y_m: map.origin_y_m as f32,
        max_dist_m,
    }
}

/// Builds a blob for a loaded map.
///
/// # Errors
/// [`FieldCmdError::BadMaxDist`], [`FieldCmdError::Edt`], [`FieldCmdError::Header`].
pub fn build_blob(map: &OccupancyMap, max_dist_m: f32) -> Result<Vec<u8>, FieldCmdError> {
    if !(max_dist_m.is_finite() && max_dist_m > 0.0) {
        return Err(FieldCmdError::BadMaxDist(max_dist_m));
    }
    let header = header_for(map, max_dist_m);
    let len = header.required_len().map_err(FieldCmdError::Header)?;
    let sq = squared_distances(map)?;
    let mut out = vec![0u8; len];
    emit_blob_from_squared_cells(&header, &sq, &mut out).map_err(FieldCmdError::Header)?;
    Ok(out)
}

/// What `field query` did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct QueryReport {
    /// Lines answered.
    pub answered: usize,
    /// Malformed lines reported.
    pub bad: usize,
}

/// Answers "x,y" lines from `input` on `out`; reports malformed lines (1-based line numbers)
/// on `err`. Blank lines and lines starting with `#` are ignored.
///
/// # Errors
/// I/O errors of the streams.
pub fn run_query(
    view: &FieldView<'_>,
    input: impl BufRead,
    mut out: impl Write,
    mut err: impl Write,
    json: bool,
) -> std::io::Result<QueryReport> {
    let mut report = QueryReport::default();
    for (i, line) in input.lines().enumerate() {
        let line = line?;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        match parse_xy(t) {
            Ok((x, y)) => {
                let d = view.distance_m(x, y);
                if json {
                    writeln!(
                        out,
                        "{}",
                        serde_json::json!({ "x": x, "y": y, "distance_m": d })
                    )?;
                } else {
                    writeln!(out, "{x},{y},{d}")?;
                }
                report.answered += 1;
            }
            Err(why) => {
                report.bad += 1;
                if json {
                    writeln!(
                        err,
                        "{}",
                        serde_json::json!({ "line": i + 1, "error": why, "text": t })
                    )?;
                } else {
                    writeln!(err, "line {}: {why}: {t:?}", i + 1)?;
                }
            }
        }
    }
    Ok(report)
}

fn parse_xy(t: &str) -> Result<(f32, f32), &'static str> {
    let mut it = t.split(',');
    let (Some(a), Some(b), None) = (it.next(), it.next(), it.next()) else {
        return Err("expected two comma-separated numbers x,y");
    };
    let x: f32 = a.trim().parse().map_err(|_| "x is not a number")?;
    let y: f32 = b.trim().parse().map_err(|_| "y is not a number")?;
    if !(x.is_finite() && y.is_finite()) {
        return Err("x and y must be finite");
    }
    Ok((x, y))
}

/// Renders a view as an RGB image, north up (see the `render` command's help).
pub fn render(view: &FieldView<'_>) -> image::RgbImage {
    let (w, h) = (view.width(), view.height());
    let step = view.step_m();
    let contour = 0.25f32;
    image::RgbImage::from_fn(w, h, |x, row| {
        let iy = h - 1 - row;
        let code = view.code(x, iy).unwrap_or(255);
        if code == 0 {
            return image::Rgb([200, 0, 0]);
        }
        let d = f32::from(code) * step;
        let mut g = (f32::from(code) / 255.0).sqrt() * 235.0 + 20.0;
        // A contour where the distance crosses a multiple of 0.25 m between this cell and
        // the one below it.
        let below = view
            .code(x, iy.saturating_sub(1))
            .map_or(d, |c| f32::from(c) * step);
        let left = view
            .code(x.saturating_sub(1), iy)
            .map_or(d, |c| f32::from(c) * step);
        let k = (d / contour).floor();
        if code < 255 && ((below / contour).floor() != k || (left / contour).floor() != k) {
            g *= 0.6;
        }
        let g = g as u8;
        image::Rgb([g, g, g])
    })
}

fn read_blob(path: &Path) -> Result<Vec<u8>, FieldCmdError> {
    std::fs::read(path).map_err(|e| FieldCmdError::Io(path.to_path_buf(), e))
}

/// Runs a `field` subcommand; prints a summary (JSON with `json`).
///
/// # Errors
/// [`FieldCmdError`], with the file concerned.
pub fn run(args: FieldArgs, json: bool) -> Result<(), FieldCmdError> {
    match args.command {
        FieldCommand::Build {
            map,
            output,
            max_dist,
            max_cells,
        } => {
            let t0 = Instant::now();
            let m = load_map_limited(&map, max_cells).map_err(FieldCmdError::Map)?;
            let t1 = Instant::now();
            let blob = build_blob(&m, max_dist)?;
            let t2 = Instant::now();
            std::fs::write(&output, &blob).map_err(|e| FieldCmdError::Io(output.clone(), e))?;
            let cells = u64::from(m.width) * u64::from(m.height);
            if json {
                println!(
                    "{}",
                    serde_json::json!({
                        "output": output.display().to_string(),
                        "width": m.width, "height": m.height,
                        "resolution_m": m.resolution_m,
                        "origin_m": [m.origin_x_m, m.origin_y_m],
                        "occupied_cells": m.occupied_count(),
                        "max_dist_m": max_dist,
                        "bytes": blob.len(),
                        "bytes_per_cell": blob.len() as f64 / cells as f64,
                        "load_ms": (t1 - t0).as_secs_f64() * 1e3,
                        "build_ms": (t2 - t1).as_secs_f64() * 1e3,
                    })
                );
            } else {
                println!(
                    "{}: {} × {} cells of {} m, origin ({}, {}), {} occupied, d_max {} m \
                     (step {:.4} m); {} bytes ({:.4} bytes/cell); load {:.1} ms, transform+encode {:.1} ms",
                    output.display(),
                    m.width,
                    m.height,
                    m.resolution_m,
                    m.origin_x_m,
                    m.origin_y_m,
                    m.occupied_count(),
                    max_dist,
                    max_dist / 255.0,
                    blob.len(),
                    blob.len() as f64 / cells as f64,
                    (t1 - t0).as_secs_f64() * 1e3,
                    (t2 - t1).as_secs_f64() * 1e3,
                );
            }
            Ok(())
        }
        FieldCommand::Query { blob } => {
            let bytes = read_blob(&blob)?;
            let view = FieldView::parse(&bytes).map_err(|e| FieldCmdError::Blob(blob, e))?;
            let stdin = std::io::stdin();
            let report = run_query(
                &view,
                stdin.lock(),
                std::io::stdout().lock(),
                std::io::stderr().lock(),
                json,
            )
            .map_err(|e| FieldCmdError::Io(PathBuf::from("<stdio>"), e))?;
            if report.bad > 0 {
                Err(FieldCmdError::BadLines(report.bad))
            } else {
                Ok(())
            }
        }
        FieldCommand::Render { blob, output } => {
            let bytes = read_blob(&blob)?;
            let view = FieldView::parse(&bytes).map_err(|e| FieldCmdError::Blob(blob, e))?;
            let img = render(&view);
            img.save_with_format(&output, image::ImageFormat::Png)
                .map_err(|e| FieldCmdError::Png(output.clone(), e.to_string()))?;
            if json {
                println!(
                    "{}",
                    serde_json::json!({ "output": output.display().to_string(),
                        "width": view.width(), "height": view.height() })
                );
            } else {
                println!(
                    "{}: {} × {} px",
                    output.display(),
                    view.width(),
                    view.height()
                );
            }
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xy_parsing_table() {
        let ok = [("1,2", (1.0, 2.0)), (" -3.5 , 4e-1 ", (-3.5, 0.4))];
        for (s, want) in ok {
            assert_eq!(parse_xy(s), Ok(want), "{s}");
        }
        for bad in ["1", "1,2,3", "a,2", "1,", "nan,1", "inf,0"] {
            assert!(parse_xy(bad).is_err(), "{bad}");
        }
    }
}
