//! The `beamfield map from-log` and `beamfield log info` commands.

use crate::input::carmen::{CarmenLog, LogError, LogStats, MaxRange, ReadOptions};
use crate::mapping::{
    build_from_log, write_map_server, write_png, MappingOptions, FREE_THRESH, OCCUPIED_THRESH,
};
use crate::progress::Progress;
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// `beamfield map …`
#[derive(Subcommand, Debug)]
pub enum MapCommand {
    /// Build a ROS map_server map (YAML + P5 PGM) from a CARMEN laser log with known poses.
    ///
    /// Every FLASER scan is projected from its logged (laser) pose, beam i at −90° + i·180°/n
    /// counter-clockwise. End points are occupied evidence; the cells each beam crosses before
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

/// `beamfield log …`
#[derive(Subcommand, Debug)]
pub enum LogCommand {
    /// Summarize a CARMEN laser log: scans, beams, the max-range value (detected or given),
    /// range and pose extents, timestamps that step back, other message types and malformed
    /// lines (which are listed, not fatal).
    Info(LogInfoArgs),
}

/// Arguments of `beamfield log info`.
#[derive(Args, Debug)]
pub struct LogInfoArgs {
    /// The CARMEN log.
    pub log: PathBuf,
    /// The max-range value in metres, instead of detecting it.
    #[arg(long, value_name = "M")]
    pub max_range: Option<f32>,
}

fn fail(message: impl std::fmt::Display) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::FAILURE
}

fn read_log(path: &Path, options: ReadOptions) -> Result<CarmenLog, LogError> {
    crate::progress::note(&format!("reading {} …", path.display()));
    CarmenLog::read_path(path, options)
}

/// An f32 as the f64 with the same shortest decimal text.
fn j32(v: f32) -> serde_json::Value {
    v.to_string()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .map_or(serde_json::Value::Null, serde_json::Value::from)
}

fn max_range_json(m: &MaxRange) -> serde_json::Value {
    match m {
        MaxRange::Given(v) => serde_json::json!({ "value_m": j32(*v), "source": "given" }),
        MaxRange::Detected(d) => serde_json::json!({
            "value_m": j32(d.value_m),
            "source": "detected",
            "count": d.count,
            "runner_up": d.runner_up.map(|(v, c)| serde_json::json!({ "value_m": j32(v), "count": c })),
        }),
        MaxRange::NotFound => serde_json::json!({ "value_m": null, "source": "not found" }),
    }
}

/// Runs a `map` subcommand.
pub fn run_map(command: MapCommand, json: bool) -> ExitCode {
    match command {
        MapCommand::FromLog(args) => map_from_log(&args, json),
    }
}

fn map_from_log(args: &FromLogArgs, json: bool) -> ExitCode {
    if !(args.resolution.is_finite() && args.resolution > 0.0) {
        return fail("--resolution must be a finite number of metres > 0");
    }
    if !(args.margin.is_finite() && args.margin >= 0.0) {
        return fail("--margin must be a finite number of metres ≥ 0");
    }
    if !(args.max_range_free.is_finite() && args.max_range_free >= 0.0) {
        return fail("--max-range-free must be a finite number of metres ≥ 0");
    }
    let log = match read_log(
        &args.log,
        ReadOptions {
            max_range_m: args.max_range,
            skip_bad_lines: args.skip_bad_lines,
        },
    ) {
        Ok(log) => log,
        Err(e) => return fail(e),
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
        return fail(format!(
            "{}: no max-range value could be detected (no single value dominates the top of the \
             range histogram); give it with --max-range M",
            args.log.display()
        ));
    };
    if log.scans.is_empty() {
        return fail(format!("{}: no FLASER scan in the log", args.log.display()));
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
        Err(e) => return fail(e),
    };
    let grid = log_odds.to_occupancy(OCCUPIED_THRESH, FREE_THRESH);
    let written = match write_map_server(&grid, &args.output) {
        Ok(w) => w,
        Err(e) => return fail(e),
    };
    if let Some(png) = &args.png {
        let trajectory: Vec<(f64, f64)> = log
            .scans
            .iter()
            .map(|s| (s.pose_f64.x_m, s.pose_f64.y_m))
            .collect();
        if let Err(e) = write_png(&grid, &trajectory, png) {
            return fail(e);
        }
    }
    let g = grid.geometry();
    let (occupied, free, unknown) = grid.counts();
    if json {
        println!(
            "{}",
            serde_json::json!({
                "yaml": written.yaml,
                "pgm": written.pgm,
                "png": args.png,
                "width": g.width,
                "height": g.height,
                "resolution_m": g.resolution_m,
                "origin_m": [g.origin_x_m, g.origin_y_m],
                "cells": { "occupied": occupied, "free": free, "unknown": unknown },
                "max_range": max_range_json(&log.max_range),
                "max_range_free_m": options.max_range_free_m,
                "readings": stats,
                "bad_lines": log.bad_lines.iter().map(ToString::to_string).collect::<Vec<_>>(),
                "bad_lines_total": log.bad_line_count,
            })
        );
    } else {
        println!(
            "wrote {} and {}: {} × {} cells of {} m, origin ({}, {}) m",
            written.yaml.display(),
            written.pgm.display(),
            g.width,
            g.height,
            g.resolution_m,
            g.origin_x_m,
            g.origin_y_m
        );
        println!("cells: {occupied} occupied, {free} free, {unknown} unknown");
        println!(
            "{} scans: {} hits, {} max-range readings (max range {max_range_m} m, {}), {} invalid",
            stats.scans,
            stats.hits,
            stats.max_range,
            match log.max_range {
                MaxRange::Given(_) => "given",
                _ => "detected",
            },
            stats.invalid
        );
        if let Some(png) = &args.png {
            println!("picture: {}", png.display());
        }
        if log.bad_line_count > 0 {
            println!("{} malformed lines skipped", log.bad_line_count);
        }
    }
    ExitCode::SUCCESS
}

/// Runs a `log` subcommand.
pub fn run_log(command: LogCommand, json: bool) -> ExitCode {
    match command {
        LogCommand::Info(args) => log_info(&args, json),
    }
}

fn log_info(args: &LogInfoArgs, json: bool) -> ExitCode {
    let log = match read_log(
        &args.log,
        ReadOptions {
            max_range_m: args.max_range,
            skip_bad_lines: true,
        },
    ) {
        Ok(log) => log,
        Err(e) => return fail(e),
    };
    let stats = log.stats();
    if json {
        println!(
            "{}",
            serde_json::json!({
                "log": args.log,
                "stats": stats,
                "max_range": max_range_json(&log.max_range),
                "frontlaser_offset_m": log.frontlaser_offset_m,
                "params": log.params,
                "other_messages": log.skipped,
                "comments": log.comments,
                "blank_lines": log.blank_lines,
                "bad_lines": log.bad_lines.iter().map(|e| serde_json::json!({
                    "line": e.line, "error": e.to_string(),
                })).collect::<Vec<_>>(),
                "bad_lines_total": log.bad_line_count,
            })
        );
    } else {
        print_info(&args.log, &log, &stats);
    }
    ExitCode::SUCCESS
}

fn print_info(path: &Path, log: &CarmenLog, s: &LogStats) {
    println!("log: {}", path.display());
    match s.beams {
        Some(n) => println!(
            "scans: {} FLASER of {n} beams (beam i at −90° + i·{}°)",
            s.scans,
            180.0 / n as f64
        ),
        None => println!("scans: 0"),
    }
    let share = |k: usize| 100.0 * k as f64 / s.readings.max(1) as f64;
    match &log.max_range {
        MaxRange::Given(v) => println!(
            "max range: {v} m (given): {} readings ({:.2} %)",
            s.max_range_readings,
            share(s.max_range_readings)
        ),
        MaxRange::Detected(d) => println!(
            "max range: {} m (detected): {} readings ({:.2} %){}",
            d.value_m,
            d.count,
            share(d.count),
            d.runner_up.map_or(String::new(), |(v, c)| format!(
                "; next most repeated value ≥ half of it: {v} m × {c}"
            ))
        ),
        MaxRange::NotFound => {
            println!("max range: not detected (no value dominates the top of the range histogram); pass --max-range")
        }
    }
    if s.readings > 0 {
        println!(
            "ranges: {} … {} m below the max range; {} above it, {} invalid",
            s.min_range_m, s.max_valid_range_m, s.above_max_range_readings, s.invalid_readings
        );
    }
    if let Some(b) = s.pose_extent {
        println!(
            "laser poses: x {:.2} … {:.2} m, y {:.2} … {:.2} m, θ {:.3} … {:.3} rad (as written)",
            b.x_min, b.x_max, b.y_min, b.y_max, s.theta_min_rad, s.theta_max_rad
        );
    }
    println!("timestamps stepping back: {}", s.timestamp_steps_back);
    let others: Vec<String> = log
        .skipped
        .iter()
        .map(|(k, v)| format!("{k} {v}"))
        .collect();
    println!(
        "other messages (skipped): {}; comments {}; blank lines {}",
        if others.is_empty() {
            "none".to_string()
        } else {
            others.join(", ")
        },
        log.comments,
        log.blank_lines
    );
    let params: Vec<String> = log.params.iter().map(|(k, v)| format!("{k}={v}")).collect();
    println!("params: {}", params.join(", "));
    println!("bad lines: {}", log.bad_line_count);
    for e in log.bad_lines.iter().take(20) {
        println!("  {e}");
    }
    if log.bad_line_count > 20 {
        println!(
            "  … and {} more (use --json for the first {})",
            log.bad_line_count - 20,
            crate::input::carmen::MAX_BAD_LINES_KEPT
        );
    }
}
