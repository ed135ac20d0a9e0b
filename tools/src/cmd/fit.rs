//! `beamfield fit`: EM for the beam model's intrinsics on a CARMEN log, z* ray cast through a
//! blob ([`crate::beam_fit`]); the fitted intrinsics under their AMCL names, the trace and the
//! time taken.

use crate::beam_fit::{amcl_pairs, fit_log, stop_name, FitError, FitOptions};
use crate::input::carmen::{CarmenLog, ReadOptions};
use clap::Args;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt;
use std::path::PathBuf;
use std::time::Instant;

/// `beamfield fit`: EM for the beam model's intrinsics on a log.
///
/// Casts z* once per beam from the logged laser poses through the blob (as the device would),
/// then runs EM over the (z, z*) pairs starting from AMCL's defaults. Prints the fitted
/// intrinsics under their AMCL parameter names, the trace (mean log-likelihood per beam after
/// each M-step, nats), why EM stopped and the time taken. Progress goes to stderr.
#[derive(Args, Debug)]
pub struct FitArgs {
    /// The distance-field blob of the map (`beamfield field build`).
    #[arg(long)]
    pub field: PathBuf,
    /// The CARMEN log (FLASER lines with corrected poses).
    #[arg(long)]
    pub log: PathBuf,
    /// The fit's options.
    #[command(flatten)]
    pub options: FitOptions,
}

/// What `beamfield fit` found.
#[derive(Debug, Serialize)]
pub struct FitCmdReport {
    /// The fitted intrinsics by AMCL name.
    pub intrinsics: BTreeMap<&'static str, f32>,
    /// Why EM stopped.
    pub stop: String,
    /// M-steps.
    pub iterations: u32,
    /// Passes over the data.
    pub passes: u32,
    /// Mean log-likelihood per beam after 0, 1, … M-steps, nats.
    pub trace_nats_per_beam: Vec<f64>,
    /// Trace entries dropped.
    pub trace_dropped: usize,
    /// The largest decrease between consecutive trace entries.
    pub trace_largest_decrease: f64,
    /// Scans used.
    pub scans: usize,
    /// (z, z*) pairs.
    pub readings_with_z_star: usize,
    /// Readings EM used.
    pub readings_used: u64,
    /// Invalid readings.
    pub readings_invalid: u64,
    /// Readings no component explains.
    pub readings_unexplained: u64,
    /// Time to read the log, seconds.
    pub read_s: f64,
    /// Time to cast z*, seconds.
    pub cast_s: f64,
    /// Time EM took, seconds.
    pub em_s: f64,
    /// The intrinsics in AMCL's order.
    #[serde(skip)]
    pub amcl_order: [(&'static str, f32); 7],
}

/// Runs `beamfield fit`.
///
/// # Errors
/// [`FitError`].
pub fn run(args: &FitArgs) -> Result<FitCmdReport, FitError> {
    let bytes = crate::input::limits::read_regular_file(
        &args.field,
        crate::input::limits::MAX_FIELD_FILE_BYTES,
        "field file",
    )
    .map_err(FitError::Read)?;
    let view = crate::input::field_file::parse_field_file(&bytes)
        .map_err(|e| FitError::Blob(args.field.clone(), e))?;
    let t_read = Instant::now();
    let log = CarmenLog::read_path(
        &args.log,
        ReadOptions {
            max_range_m: args.options.max_range,
            skip_bad_lines: false,
        },
    )
    .map_err(FitError::Log)?;
    let read_s = t_read.elapsed().as_secs_f64();
    let progress = crate::progress::Progress::new("casting z*: scan");
    let r = fit_log(view, &log, &args.options, |done, total| {
        progress.update(done, total, "")
    })?;
    let pairs = amcl_pairs(&r.fit.intrinsics);
    Ok(FitCmdReport {
        intrinsics: pairs.iter().copied().collect(),
        stop: stop_name(r.fit.stop),
        iterations: r.fit.iterations,
        passes: r.fit.passes,
        trace_largest_decrease: r.largest_decrease(),
        trace_dropped: r.fit.trace_dropped,
        scans: r.scans,
        readings_with_z_star: r.pairs,
        readings_used: r.fit.counts.used,
        readings_invalid: r.fit.counts.invalid,
        readings_unexplained: r.fit.counts.unexplained,
        read_s,
        cast_s: r.cast_s,
        em_s: r.em_s,
        trace_nats_per_beam: r.trace,
        amcl_order: pairs,
    })
}

impl fmt::Display for FitCmdReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "fitted beam-model intrinsics (AMCL names):")?;
        for (k, v) in self.amcl_order {
            writeln!(f, "  {k:<20} {v:.6}")?;
        }
        writeln!(
            f,
            "stopped: {} after {} iterations ({} passes)",
            self.stop, self.iterations, self.passes
        )?;
        writeln!(
            f,
            "data: {} scans, {} pairs, {} used, {} invalid, {} unexplained",
            self.scans,
            self.readings_with_z_star,
            self.readings_used,
            self.readings_invalid,
            self.readings_unexplained
        )?;
        writeln!(f, "trace (mean log-likelihood per beam, nats):")?;
        for (t, l) in self.trace_nats_per_beam.iter().enumerate() {
            writeln!(f, "  {t:>4} {l:.9}")?;
        }
        let decrease = self.trace_largest_decrease;
        writeln!(
            f,
            "trace never decreases: {} (largest decrease {decrease:.3e})",
            decrease <= 0.0
        )?;
        write!(
            f,
            "time: read log {:.3} s, cast z* {:.3} s, EM {:.3} s",
            self.read_s, self.cast_s, self.em_s
        )
    }
}
