//! `beamfield log info`: a summary of a CARMEN laser log (scans, beams, the max-range value,
//! range and pose extents, other messages, malformed lines).

use crate::input::carmen::{CarmenLog, LogError, LogStats, MaxRange, ReadOptions};
use clap::{Args, Subcommand};
use serde::{Serialize, Serializer};
use std::fmt;
use std::path::{Path, PathBuf};

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

/// Reads a CARMEN log, saying so on stderr.
///
/// # Errors
/// The [`LogError`].
pub fn read_log(path: &Path, options: ReadOptions) -> Result<CarmenLog, LogError> {
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

/// The max-range value of a log and where it came from, as JSON.
pub fn max_range_json(m: &MaxRange) -> serde_json::Value {
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

/// Runs a `log` subcommand.
///
/// # Errors
/// The [`LogError`].
pub fn run_log(command: &LogCommand) -> Result<LogInfoReport, LogError> {
    match command {
        LogCommand::Info(args) => run(args),
    }
}

/// Runs `beamfield log info`.
///
/// # Errors
/// The [`LogError`].
pub fn run(args: &LogInfoArgs) -> Result<LogInfoReport, LogError> {
    let log = read_log(
        &args.log,
        ReadOptions {
            max_range_m: args.max_range,
            skip_bad_lines: true,
        },
    )?;
    Ok(LogInfoReport {
        path: args.log.clone(),
        stats: log.stats(),
        log,
    })
}

/// What `log info` found.
#[derive(Debug)]
pub struct LogInfoReport {
    /// The log file.
    pub path: PathBuf,
    /// Its statistics.
    pub stats: LogStats,
    /// The log read.
    pub log: CarmenLog,
}

impl Serialize for LogInfoReport {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let log = &self.log;
        serde_json::json!({
            "log": self.path,
            "stats": self.stats,
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
        .serialize(s)
    }
}

impl fmt::Display for LogInfoReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (log, s) = (&self.log, &self.stats);
        let mut first = true;
        // One line per call, separated by newlines (the last without one: main ends it).
        let mut line = |f: &mut fmt::Formatter<'_>, text: fmt::Arguments<'_>| {
            if !std::mem::take(&mut first) {
                f.write_str("\n")?;
            }
            f.write_fmt(text)
        };
        macro_rules! w {
            ($($t:tt)*) => { line(f, format_args!($($t)*))? };
        }
        w!("log: {}", self.path.display());
        match s.beams {
            Some(n) => w!(
                "scans: {} FLASER of {n} beams (beam i at −90° + i·{}°)",
                s.scans,
                crate::input::carmen::carmen_beam_step_rad(n).to_degrees()
            ),
            None => w!("scans: 0"),
        }
        let share = |k: usize| 100.0 * k as f64 / s.readings.max(1) as f64;
        match &log.max_range {
            MaxRange::Given(v) => w!(
                "max range: {v} m (given): {} readings ({:.2} %)",
                s.max_range_readings,
                share(s.max_range_readings)
            ),
            MaxRange::Detected(d) => w!(
                "max range: {} m (detected): {} readings ({:.2} %){}",
                d.value_m,
                d.count,
                share(d.count),
                d.runner_up.map_or(String::new(), |(v, c)| format!(
                    "; next most repeated value ≥ half of it: {v} m × {c}"
                ))
            ),
            MaxRange::NotFound => {
                w!("max range: not detected (no value dominates the top of the range histogram); pass --max-range")
            }
        }
        if s.readings > 0 {
            w!(
                "ranges: {} … {} m below the max range; {} above it, {} invalid",
                s.min_range_m,
                s.max_valid_range_m,
                s.above_max_range_readings,
                s.invalid_readings
            );
        }
        if let Some(b) = s.pose_extent {
            w!(
            "laser poses: x {:.2} … {:.2} m, y {:.2} … {:.2} m, θ {:.3} … {:.3} rad (as written)",
            b.x_min, b.x_max, b.y_min, b.y_max, s.theta_min_rad, s.theta_max_rad
        );
        }
        w!("timestamps stepping back: {}", s.timestamp_steps_back);
        let others: Vec<String> = log
            .skipped
            .iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect();
        w!(
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
        w!("params: {}", params.join(", "));
        w!("bad lines: {}", log.bad_line_count);
        for e in log.bad_lines.iter().take(20) {
            w!("  {e}");
        }
        if log.bad_line_count > 20 {
            w!(
                "  … and {} more (use --json for the first {})",
                log.bad_line_count - 20,
                crate::input::carmen::MAX_BAD_LINES_KEPT
            );
        }
        Ok(())
    }
}
