//! `beamfield score`: the likelihood field on one scan of a CARMEN log, at one pose, optionally
//! over a local pose grid (`--grid`) and drawn over the field (`--overlay`).

mod grid;
mod overlay;

use crate::cmd::scored_log::{load, parse_pose, scan_of, usage, ModelArgs, ScoreCmdError};
use beamfield::field::LikelihoodField;
use beamfield::{Pose, SensorModel, Tempered};
use clap::Args;
use serde::Serialize;
use std::fmt;
use std::path::PathBuf;

/// `beamfield score`: log-likelihood of one scan of a log at a pose.
#[derive(Args, Debug)]
pub struct ScoreArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Index of the scan in the log (0-based, FLASER lines in file order).
    #[arg(long)]
    pub scan: usize,
    /// Laser pose "X,Y,THETA" (metres, metres, radians); default: the logged pose.
    #[arg(long, allow_hyphen_values = true)]
    pub pose: Option<String>,
    /// Tempering κ (the log-likelihood is divided by it).
    #[arg(long, default_value_t = 1.0)]
    pub kappa: f32,
    /// Also score an x–y grid at the pose's θ and a θ profile, writing PREFIX.csv,
    /// PREFIX-xy.png and PREFIX-theta.png.
    #[arg(long, value_name = "PREFIX")]
    pub grid: Option<PathBuf>,
    /// Grid half-width in x and y, metres.
    #[arg(long = "grid-half", default_value_t = 0.2)]
    pub grid_half: f64,
    /// Grid step in x and y, metres.
    #[arg(long = "grid-step", default_value_t = 0.005)]
    pub grid_step: f64,
    /// θ profile half-width, degrees (step 0.25°).
    #[arg(long = "grid-half-deg", default_value_t = 10.0)]
    pub grid_half_deg: f64,
    /// Write a PNG of the scan's endpoints over the field around the pose: at the pose (blue)
    /// and at the best pose of the x–y–θ grid that --grid-half, --grid-step and
    /// --grid-half-deg span (θ in 0.25° steps; green), with the offset between them in the
    /// title. The best pose is also printed.
    #[arg(long, value_name = "PNG")]
    pub overlay: Option<PathBuf>,
    /// Half-width of the --overlay picture's window, metres.
    #[arg(long = "overlay-half", default_value_t = 6.0)]
    pub overlay_half: f64,
    /// Centre "X,Y" of the --overlay picture's window (metres, map frame); default: the pose.
    #[arg(
        long = "overlay-center",
        allow_hyphen_values = true,
        value_name = "X,Y"
    )]
    pub overlay_center: Option<String>,
}

/// The best pose of the x–y–θ grid, as reported.
#[derive(Debug, Serialize)]
pub struct BestGridPose {
    /// The pose (x m, y m, θ rad).
    pub pose_m_m_rad: [f32; 3],
    /// Its offset from the scored pose (x m, y m, θ rad).
    pub offset_m_m_rad: [f64; 3],
    /// Its log-likelihood, nats.
    pub log_likelihood_nats: f64,
    /// Poses in the grid.
    pub grid_poses: usize,
}

/// What `beamfield score` found.
#[derive(Debug, Serialize)]
pub struct ScoreReport {
    /// The scan's index.
    pub scan: usize,
    /// The pose scored (x m, y m, θ rad).
    pub pose_m_m_rad: [f32; 3],
    /// The logged pose (x m, y m, θ rad).
    pub logged_pose_m_m_rad: [f32; 3],
    /// Tempering κ.
    pub kappa: f32,
    /// Log-likelihood of the scan, nats (divided by κ).
    pub log_likelihood_nats: f32,
    /// Beams scored.
    pub beams_scored: u16,
    /// Beams skipped as max-range readings.
    pub beams_skipped_max_range: u16,
    /// Beams skipped as invalid.
    pub beams_skipped_invalid: u16,
    /// Beams without a layout entry.
    pub beams_unpaired: u16,
    /// The best pose of the grid (`--overlay`).
    pub best_grid_pose: Option<BestGridPose>,
    /// Files written.
    pub files: Vec<String>,
}

fn triple(p: &Pose) -> [f32; 3] {
    [p.x_m, p.y_m, p.theta_rad]
}

/// Runs `beamfield score`.
///
/// # Errors
/// [`ScoreCmdError`] for unreadable inputs, bad options or a failed plot.
pub fn run(a: &ScoreArgs) -> Result<ScoreReport, ScoreCmdError> {
    let l = load(&a.model)?;
    let lf = LikelihoodField::new(
        crate::input::field_file::parse_field_file(&l.blob).map_err(ScoreCmdError::Blob)?,
        l.params,
    );
    let model = Tempered::new(lf, a.kappa, 1).map_err(|e| usage(format!("--kappa: {e}")))?;
    let (scan, logged) = scan_of(&l.log, a.scan)?;
    let pose = match &a.pose {
        Some(t) => parse_pose(t).map_err(usage)?,
        None => logged,
    };
    let s = model.score(&l.layout, &scan, &pose);
    let mut files = Vec::new();
    if let Some(prefix) = &a.grid {
        files = grid::write_grid(a, &model, &l.layout, &scan, &pose, prefix)?;
    }
    let mut best = None;
    if let Some(path) = &a.overlay {
        let center = overlay::overlay_center(a, &pose)?;
        let b = grid::best_grid_pose(a, &model, &l.layout, &scan, &pose)?;
        overlay::write_overlay(a, &l, &scan, &pose, center, &b, path)?;
        files.push(path.display().to_string());
        best = Some(BestGridPose {
            pose_m_m_rad: triple(&b.pose),
            offset_m_m_rad: [b.offset.0, b.offset.1, b.offset.2],
            log_likelihood_nats: b.log_likelihood,
            grid_poses: b.poses,
        });
    }
    Ok(ScoreReport {
        scan: a.scan,
        pose_m_m_rad: triple(&pose),
        logged_pose_m_m_rad: triple(&logged),
        kappa: a.kappa,
        log_likelihood_nats: s.log_likelihood,
        beams_scored: s.scored,
        beams_skipped_max_range: s.max_range,
        beams_skipped_invalid: s.invalid,
        beams_unpaired: s.unpaired,
        best_grid_pose: best,
        files,
    })
}

impl fmt::Display for ScoreReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [x, y, t] = self.pose_m_m_rad;
        writeln!(
            f,
            "scan {} at ({x:.3} m, {y:.3} m, {t:.4} rad), κ = {}: log-likelihood {:.3} nats",
            self.scan, self.kappa, self.log_likelihood_nats
        )?;
        write!(
            f,
            "beams: {} scored, {} max-range skipped, {} invalid, {} unpaired",
            self.beams_scored,
            self.beams_skipped_max_range,
            self.beams_skipped_invalid,
            self.beams_unpaired
        )?;
        if let Some(b) = &self.best_grid_pose {
            let [dx, dy, dt] = b.offset_m_m_rad;
            let [bx, by, bt] = b.pose_m_m_rad;
            write!(
                f,
                "\nbest of {} grid poses: ({bx:.3} m, {by:.3} m, {bt:.4} rad), {:.1} cm ({:+.1}, {:+.1}) and {:+.2}° from the pose; log-likelihood {:.3} nats ({:+.3})",
                b.grid_poses,
                (dx * dx + dy * dy).sqrt() * 100.0,
                dx * 100.0,
                dy * 100.0,
                dt.to_degrees(),
                b.log_likelihood_nats,
                b.log_likelihood_nats - f64::from(self.log_likelihood_nats)
            )?;
        }
        for file in &self.files {
            write!(f, "\nwrote {file}")?;
        }
        Ok(())
    }
}
