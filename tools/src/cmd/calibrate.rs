//! `beamfield calibrate`: the smallest tempering κ whose credible sets over a local pose grid
//! hold the logged poses at the requested rate (docs/models.md#tempering; the maths is
//! [`crate::calibrate`]), and a coverage-against-κ PNG.

use crate::calibrate::{calibrate, Calibration};
use crate::cmd::scored_log::{load, scan_of, usage, ModelArgs, ScoreCmdError};
use crate::draw::plot::{line_chart, LineChart, Series};
use crate::pose_grid::{argmax, posterior_sd, score_grid, GridSpec};
use beamfield::field::LikelihoodField;
use clap::Args;
use serde::Serialize;
use std::fmt;
use std::path::{Path, PathBuf};

/// Most scores `calibrate` keeps (scans × grid poses, one f64 each): 2²⁵, 256 MiB. The
/// default grid (41 × 41 × 41 poses) over the default 60 scans is 4.1 M.
pub const MAX_CALIBRATE_SCORES: u64 = 1 << 25;

/// `beamfield calibrate`: the smallest κ whose credible sets hold the logged poses.
#[derive(Args, Debug)]
pub struct CalibrateArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Requested coverage of the credible sets (their level).
    #[arg(long, default_value_t = 0.95)]
    pub coverage: f64,
    /// Number of scans, spread evenly over the log.
    #[arg(long, default_value_t = 60)]
    pub scans: usize,
    /// Grid half-width in x and y, metres.
    #[arg(long = "half-xy", default_value_t = 0.08)]
    pub half_xy: f64,
    /// Grid step in x and y, metres.
    #[arg(long = "step-xy", default_value_t = 0.004)]
    pub step_xy: f64,
    /// Grid half-width in θ, degrees.
    #[arg(long = "half-deg", default_value_t = 2.0)]
    pub half_deg: f64,
    /// Grid step in θ, degrees.
    #[arg(long = "step-deg", default_value_t = 0.1)]
    pub step_deg: f64,
    /// Write a PNG of coverage against κ.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

/// Runs `beamfield calibrate`; progress goes to stderr.
///
/// # Errors
/// [`ScoreCmdError`] for unreadable inputs, bad options or a failed plot.
pub fn run(a: &CalibrateArgs) -> Result<CalibrateReport, ScoreCmdError> {
    if !(a.coverage > 0.0 && a.coverage < 1.0) {
        return Err(usage("--coverage must be in (0, 1)"));
    }
    if a.scans == 0 {
        return Err(usage("--scans must be at least 1"));
    }
    let spec = GridSpec {
        half_xy_m: a.half_xy,
        step_xy_m: a.step_xy,
        half_theta_rad: a.half_deg.to_radians(),
        step_theta_rad: a.step_deg.to_radians(),
    };
    let ok = |h: f64, s: f64| s > 0.0 && h >= s && h / s <= 200.0;
    if !(ok(a.half_xy, a.step_xy) && ok(a.half_deg, a.step_deg)) {
        return Err(usage(
            "grid: steps must be > 0 and at most the half-widths, ≤ 200 steps per side",
        ));
    }
    let l = load(&a.model)?;
    let n = a.scans.min(l.log.scans.len());
    let scores = (n as u64).saturating_mul(spec.len() as u64);
    if scores > MAX_CALIBRATE_SCORES {
        return Err(usage(format!(
            "{n} scans of {} grid poses = {scores} scores, over the limit of \
             {MAX_CALIBRATE_SCORES} (fewer --scans or a coarser grid)",
            spec.len()
        )));
    }
    let lf = LikelihoodField::new(
        crate::input::field_file::parse_field_file(&l.blob).map_err(ScoreCmdError::Blob)?,
        l.params,
    );
    let total = l.log.scans.len();
    if total == 0 {
        return Err(usage("the log has no scans"));
    }
    let n = a.scans.min(total);
    let mut grids = Vec::with_capacity(n);
    let mut sd_sum = (0.0, 0.0, 0.0);
    let mut peak_err = Vec::with_capacity(n);
    let progress = crate::progress::Progress::new("calibrate: scan");
    for j in 0..n {
        let i = j * total / n;
        let (scan, pose) = scan_of(&l.log, i)?;
        let g = score_grid(&lf, &l.layout, &scan, &pose, &spec);
        let sd = posterior_sd(&g, &spec, 1.0);
        sd_sum = (sd_sum.0 + sd.0, sd_sum.1 + sd.1, sd_sum.2 + sd.2);
        if let Some(b) = argmax(&g.log_likelihood) {
            let (dx, dy, _) = spec.offset(b);
            peak_err.push((dx * dx + dy * dy).sqrt());
        }
        grids.push(g);
        progress.update(j + 1, n, &format!(" ({} poses each)", spec.len()));
    }
    let cal = calibrate(&grids, a.coverage);
    let nf = n as f64;
    let sd_k1 = (sd_sum.0 / nf, sd_sum.1 / nf, sd_sum.2 / nf);
    let sd_at = |k: f64| {
        let s = grids
            .iter()
            .map(|g| posterior_sd(g, &spec, k))
            .fold((0.0, 0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
        (s.0 / nf, s.1 / nf, s.2 / nf)
    };
    let sd_kappa = cal.kappa.map(sd_at);
    peak_err.sort_by(f64::total_cmp);
    let median_peak = peak_err.get(peak_err.len() / 2).copied().unwrap_or(0.0);
    if let Some(path) = &a.output {
        plot_curve(path, &cal)?;
    }
    Ok(CalibrateReport {
        calibration: cal,
        grid: spec,
        mean_posterior_sd_at_kappa_1: [sd_k1.0, sd_k1.1, sd_k1.2],
        mean_posterior_sd_at_kappa: sd_kappa.map(|s| [s.0, s.1, s.2]),
        median_peak_distance_m: median_peak,
        scans: n,
        log_scans: total,
        half_xy: a.half_xy,
        step_xy: a.step_xy,
        half_deg: a.half_deg,
        step_deg: a.step_deg,
        coverage: a.coverage,
        output: a.output.as_ref().map(|p| p.display().to_string()),
    })
}

/// What `beamfield calibrate` found.
#[derive(Debug, Serialize)]
pub struct CalibrateReport {
    /// κ, the coverage curve and the coverages.
    pub calibration: Calibration,
    /// The pose grid.
    pub grid: GridSpec,
    /// Mean posterior standard deviations at κ = 1 (x m, y m, θ rad).
    pub mean_posterior_sd_at_kappa_1: [f64; 3],
    /// Mean posterior standard deviations at κ, if one was found.
    pub mean_posterior_sd_at_kappa: Option<[f64; 3]>,
    /// Median distance of the grid's best pose from the logged one, metres.
    pub median_peak_distance_m: f64,
    /// Scans scored.
    #[serde(skip)]
    pub scans: usize,
    /// Scans in the log.
    #[serde(skip)]
    pub log_scans: usize,
    /// `--half-xy`, metres.
    #[serde(skip)]
    pub half_xy: f64,
    /// `--step-xy`, metres.
    #[serde(skip)]
    pub step_xy: f64,
    /// `--half-deg`.
    #[serde(skip)]
    pub half_deg: f64,
    /// `--step-deg`.
    #[serde(skip)]
    pub step_deg: f64,
    /// The requested coverage.
    #[serde(skip)]
    pub coverage: f64,
    /// The PNG written (`--output`).
    #[serde(skip)]
    pub output: Option<String>,
}

impl fmt::Display for CalibrateReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (n, cal) = (self.scans, &self.calibration);
        let [s0, s1, s2] = self.mean_posterior_sd_at_kappa_1;
        writeln!(
            f,
            "{n} scans of {}; grid ±{:.2} m / {:.3} m in x and y, ±{}° / {}° in θ ({} poses)",
            self.log_scans,
            self.half_xy,
            self.step_xy,
            self.half_deg,
            self.step_deg,
            self.grid.len()
        )?;
        writeln!(
            f,
            "coverage of the {:.0} % credible set at κ = 1: {:.3}",
            self.coverage * 100.0,
            cal.coverage_at_1
        )?;
        match (cal.kappa, cal.coverage_at_kappa) {
            (Some(k), Some(c)) => writeln!(
                f,
                "κ = {k:.3}: coverage {c:.3} over {n} scans (the smallest κ that reaches it is \
                 within {} % below)",
                cal.relative_precision * 100.0
            )?,
            _ => writeln!(
                f,
                "no κ ≤ {} reaches the requested coverage over {n} scans",
                crate::calibrate::KAPPA_MAX
            )?,
        }
        write!(
            f,
            "mean posterior sd at κ = 1: x {:.1} mm, y {:.1} mm, θ {:.2}° ({:.1}, {:.1}, {:.1} grid cells)",
            s0 * 1e3,
            s1 * 1e3,
            s2.to_degrees(),
            s0 / self.step_xy,
            s1 / self.step_xy,
            s2.to_degrees() / self.step_deg
        )?;
        if let (Some(k), Some(s)) = (cal.kappa, self.mean_posterior_sd_at_kappa) {
            write!(
                f,
                "\nmean posterior sd at κ = {k:.3}: x {:.1} mm, y {:.1} mm, θ {:.2}°",
                s[0] * 1e3,
                s[1] * 1e3,
                s[2].to_degrees()
            )?;
        }
        write!(
            f,
            "\nmedian distance of the grid's best pose from the logged one: {:.1} cm",
            self.median_peak_distance_m * 100.0
        )?;
        if let Some(p) = &self.output {
            write!(f, "\nwrote {p}")?;
        }
        Ok(())
    }
}

fn plot_curve(path: &Path, cal: &Calibration) -> Result<(), ScoreCmdError> {
    let mut v_lines = Vec::new();
    if let Some(k) = cal.kappa {
        v_lines.push((k, format!("κ = {k:.3}")));
    }
    line_chart(
        path,
        &LineChart {
            title: "coverage of the credible set against tempering κ",
            x_label: "κ",
            y_label: "fraction of logged poses inside",
            x_log: true,
            h_lines: vec![(cal.level, format!("requested {:.2}", cal.level))],
            v_lines,
            series: vec![Series {
                name: format!("{} scans", cal.scans),
                points: cal.curve.clone(),
            }],
        },
    )
    .map_err(|e| ScoreCmdError::Plot(e.0))
}
