//! What `beamfield track` reports over its seeds ([`TrackReport`]), as text and JSON.

use crate::track::{Metrics, RunOptions, ScanRecord};
use serde::Serialize;
use std::fmt;

/// One seed's run, as reported.
#[derive(Debug, Serialize)]
pub struct SeedRun {
    /// The seed.
    pub seed: u64,
    /// Its summary figures.
    pub metrics: Metrics,
    /// Scans skipped or discarded.
    pub skipped: usize,
    /// Resamplings.
    pub resamplings: usize,
    /// Recovery particles injected.
    pub injected: u64,
    /// Retries.
    pub retries: usize,
    /// The odometry noise's variance scale (1 without `--adaptive-noise`): mean and largest
    /// over the scans.
    pub noise_scale_mean_max: [f32; 2],
    /// The particles in use: mean and largest over the scans.
    pub particles_mean_max: [f32; 2],
    /// Free-space resets.
    pub resets: usize,
    /// Every update: the estimate, its covariance and quality state, the error where the
    /// truth is known.
    pub per_scan: Vec<ScanRecord>,
}

/// What `beamfield track` found over its seeds.
#[derive(Debug, Serialize)]
pub struct TrackReport {
    /// Scans run.
    pub scans: usize,
    /// Particles.
    pub particles: usize,
    /// κ.
    pub kappa: f32,
    /// Beam stride.
    pub stride: usize,
    /// odom_alpha1..4.
    pub odom_alphas: [f32; 4],
    /// `logged` or `global`.
    pub init: String,
    /// The weighting (`Product` or `AmclCube`).
    pub weighting: String,
    /// Recovery rates (slow, fast).
    pub recovery: [f32; 2],
    /// Recovery only while unsettled.
    pub recovery_while_unsettled: bool,
    /// Resetting driven by the quality signal (`--resetting`).
    pub resetting: bool,
    /// The retry (drop, scale).
    pub retry: Option<[f32; 2]>,
    /// The kidnapping's scan.
    pub kidnap: Option<usize>,
    /// The adaptive motion noise (target, rate, smallest and largest scale), when on.
    pub adaptive_noise: Option<[f32; 4]>,
    /// KLD sampling's fewest and most particles, when on.
    pub kld: Option<[u16; 2]>,
    /// The σ_hit that follows the cloud's spread (gain, largest σ in metres), if on.
    pub adaptive_sigma: Option<[f32; 2]>,
    /// κ while the quality signal does not report Tracking (`--kappa-uncertain`), if given.
    pub kappa_uncertain: Option<f32>,
    /// The update gate (`--update-min`): metres, radians; 0, 0 updates at every scan.
    pub update_min: [f32; 2],
    /// Every seed's run.
    pub runs: Vec<SeedRun>,
    /// Translation RMSE over the seeds, cm: min, median, max.
    pub trans_rmse_cm_min_med_max: [f64; 3],
    /// Heading RMSE, degrees: min, median, max.
    pub heading_rmse_deg_min_med_max: [f64; 3],
    /// Largest translation error, metres: min, median, max.
    pub max_trans_m_min_med_max: [f64; 3],
    /// Share of scans within 10 cm and 2°, %: min, median, max.
    pub within_10cm_2deg_pct_min_med_max: [f64; 3],
    /// Runs that were lost.
    pub lost_runs: usize,
    /// Runs lost after converging.
    pub lost_after_convergence_runs: usize,
    /// Runs that converged.
    pub converged_runs: usize,
    /// Scans to convergence over the runs that converged: min, median, max.
    pub converged_after_min_med_max: Option<[f64; 3]>,
    /// The options of the first seed's run.
    #[serde(skip)]
    pub options: RunOptions,
    /// The picture written (`--output`).
    #[serde(skip)]
    pub output: Option<String>,
    /// Where the odometry came from.
    pub odometry: String,
    /// Where the errors were measured: `every scan` (the logged poses) or `reference` (the
    /// reference scans of `--reference` only).
    pub scored: String,
    /// Which odometry, in one word: `synthetic` (the filter's own noise model), `recorded` (a
    /// file or a bag), `wheels-mild`, `wheels-strong`, `wheels-typical` (the wheel model).
    pub odometry_model: String,
    /// What the bag gave, for a run on a bag.
    pub bag: Option<crate::track::BagSummary>,
}

impl TrackReport {
    /// A line saying that runs were lost (their largest error against the reference passed
    /// 0.5 m), and which seeds; `None` when none was.
    pub fn lost_line(&self) -> Option<String> {
        if self.lost_runs == 0 {
            return None;
        }
        let seeds: Vec<String> = self
            .runs
            .iter()
            .filter(|r| r.metrics.lost)
            .map(|r| r.seed.to_string())
            .collect();
        Some(format!(
            "LOST: {} of {} runs lost the robot (largest error over 0.5 m against the {}; {} {})",
            self.lost_runs,
            self.runs.len(),
            if self.bag.is_some() {
                "reference topic"
            } else {
                "logged poses"
            },
            if seeds.len() == 1 { "seed" } else { "seeds" },
            seeds.join(", ")
        ))
    }
}

impl fmt::Display for TrackReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let o = &self.options;
        let (rmse, head, maxe, within) = (
            self.trans_rmse_cm_min_med_max,
            self.heading_rmse_deg_min_med_max,
            self.max_trans_m_min_med_max,
            self.within_10cm_2deg_pct_min_med_max,
        );
        let (lost, lost_after, n) = (
            self.lost_runs,
            self.lost_after_convergence_runs,
            self.runs.len(),
        );
        writeln!(
            f,
            "{} scans, {} particles, κ {}, stride {}, odom_alpha {:?}, init {:?}, weighting {:?}, \
             recovery {:?}{}{}{}",
            o.scans,
            o.particles,
            o.kappa,
            o.stride,
            o.alphas,
            o.init,
            o.weighting,
            o.recovery,
            if o.recovery_while_unsettled {
                " while unsettled"
            } else {
                ""
            },
            o.retry
                .map(|(d, k)| format!(", retry {d} nats below the level, {k}× the step's spread"))
                .unwrap_or_default(),
            o.kidnap
                .map(|k| format!(", kidnapped at scan {k}"))
                .unwrap_or_default()
        )?;
        if let Some(k) = o.kappa_uncertain {
            writeln!(f, "κ {k} while the quality signal does not report Tracking")?;
        }
        if let Some((gain, max)) = o.adaptive_sigma {
            writeln!(
                f,
                "σ_hit follows the cloud: σ² = σ_hit² + {gain} × (var x + var y) / 2, at most {max} m"
            )?;
        }
        if let Some((lo, hi)) = o.kld {
            writeln!(
                f,
                "KLD sampling: {lo} ..= {hi} particles (pf_err 0.05, pf_z 0.99, bins 0.5 m / 10°)"
            )?;
        }
        if let Some([t, r, lo, hi]) = o.adaptive_noise {
            writeln!(
                f,
                "adaptive motion noise: on (target {t}, rate {r}, variance scale {lo} ..= {hi})"
            )?;
        }
        if o.update_min != (0.0, 0.0) {
            writeln!(
                f,
                "update gate: the filter updates once the odometry has moved {} m or turned {} rad",
                o.update_min.0, o.update_min.1
            )?;
        }
        if o.resetting {
            writeln!(
                f,
                "resetting: on (expansion, best-of-candidates free-space reset, settle guard)"
            )?;
        }
        writeln!(f, "odometry: {}", self.odometry)?;
        if let Some(b) = &self.bag {
            writeln!(
                f,
                "bag: {} scans used, {} beams from {:.2}° every {:.3}°, max range {} m; laser mount ({}, {}, {:.2}°) {}",
                b.scans_used,
                b.beams,
                b.angle_min_rad.to_degrees(),
                b.angle_increment_rad.to_degrees(),
                b.range_max_m,
                b.mount[0],
                b.mount[1],
                b.mount[2].to_degrees(),
                if b.mount_from_tf {
                    format!("of {} on {} from /tf_static", b.scan_frame, b.base_frame)
                } else {
                    format!("(the scans are in the base frame {})", b.base_frame)
                }
            )?;
            if b.rebinned > 0 {
                writeln!(
                    f,
                    "bag: {} scans binned onto that layout (nearest beam within half a step)",
                    b.rebinned
                )?;
            }
            for (why, n) in &b.skipped {
                writeln!(f, "bag: skipped {n}: {why}")?;
            }
        }
        if let Some(r) = self.runs.first() {
            writeln!(
                f,
                "scored at {} scans ({}), from scan {}",
                r.metrics.scored_scans,
                self.scored,
                r.per_scan.first().map_or(0, |s| s.scan)
            )?;
        }
        for r in &self.runs {
            let m = &r.metrics;
            let q = &m.quality;
            writeln!(
                f,
                "seed {}: quality at the scored scans (within / beyond {} m): tracking {} / {}, \
                 uncertain {} / {}, lost {} / {}; {} resets",
                r.seed,
                crate::track::LOST_M,
                q.tracking_within,
                q.tracking_off,
                q.uncertain_within,
                q.uncertain_off,
                q.lost_within,
                q.lost_off,
                r.resets,
            )?;
            writeln!(
                f,
                "seed {}: trans RMSE {:.2} cm, heading RMSE {:.2}°, max {:.3} m, within 10 cm/2° \
                 {:.1} %, {}{}{}; {} resamplings, {} injected, {} retries, {} skipped{}",
                r.seed,
                m.trans_rmse_m * 100.0,
                m.heading_rmse_deg,
                m.max_trans_m,
                m.within_10cm_2deg * 100.0,
                if m.lost { "LOST" } else { "not lost" },
                m.converged_after
                    .map(|c| format!(", converged after {c} scans"))
                    .unwrap_or_else(|| ", never converged".into()),
                if m.lost_after_convergence {
                    ", LOST after converging"
                } else {
                    ""
                },
                r.resamplings,
                r.injected,
                r.retries,
                r.skipped,
                if o.adaptive_noise.is_some() {
                    let [mean, max] = r.noise_scale_mean_max;
                    format!("; noise scale mean {mean:.2}, max {max:.2}")
                } else {
                    String::new()
                } + &if o.kld.is_some() {
                    let [mean, max] = r.particles_mean_max;
                    format!("; particles mean {mean:.0}, max {max:.0}")
                } else {
                    String::new()
                },
            )?;
        }
        write!(
            f,
            "over {n} seeds (min / median / max): trans RMSE {:.2} / {:.2} / {:.2} cm; heading RMSE \
             {:.2} / {:.2} / {:.2}°; max error {:.3} / {:.3} / {:.3} m; within 10 cm/2° {:.1} / \
             {:.1} / {:.1} %; lost (> 0.5 m) in {lost} of {n}; converged (20 cm/5° for 20 scans) in \
             {} of {n}",
            rmse[0],
            rmse[1],
            rmse[2],
            head[0],
            head[1],
            head[2],
            maxe[0],
            maxe[1],
            maxe[2],
            within[0],
            within[1],
            within[2],
            self.converged_runs,
        )?;
        if let Some(c) = self.converged_after_min_med_max {
            write!(
                f,
                ", after {:.0} / {:.0} / {:.0} scans; lost after converging in {lost_after} of {}",
                c[0], c[1], c[2], self.converged_runs
            )?;
        }
        if let Some(p) = &self.output {
            write!(f, "\nwrote {p}")?;
        }
        Ok(())
    }
}
