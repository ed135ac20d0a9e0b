//! One run of the localizer over a loaded log, and its metrics.

use crate::cmd::scored_log::MAX_BEAMS;
use beamfield::field::{FieldView, FreeSpace, LikelihoodField, LikelihoodParams};
use beamfield::mcl::{
    AdaptiveNoise, Kld, Mcl, MclConfig, MclError, OdometryNoise, OdometryStep, Particles, Quality,
    QualityThresholds, Resetting, SplitMix64, Unexplained,
};
use beamfield::{wrap_angle, BeamLayout, Pose, Reading, Scan, Tempered};
use std::io::IsTerminal;

use super::{synthesize_odometry, TrackInput};
use super::{
    usage, Init, TrackError, Weighting, CONVERGED_DEG, CONVERGED_M, CONVERGED_SCANS,
    INIT_SIGMA_THETA_RAD, INIT_SIGMA_XY_M, KIDNAP_MIN_M, KIDNAP_SEED_XOR, LOST_M,
    MAX_TRACK_PARTICLES,
};

/// The options of one run.
#[derive(Clone, Copy, Debug)]
pub struct RunOptions {
    /// Particles.
    pub particles: usize,
    /// κ.
    pub kappa: f32,
    /// Beam stride.
    pub stride: usize,
    /// odom_alpha1..4.
    pub alphas: [f32; 4],
    /// Seed.
    pub seed: u64,
    /// Initial cloud.
    pub init: Init,
    /// Scan at which the robot is kidnapped.
    pub kidnap: Option<usize>,
    /// Weighting.
    pub weighting: Weighting,
    /// (recovery_alpha_slow, recovery_alpha_fast).
    pub recovery: (f32, f32),
    /// Inject recovery particles only while the filter has not settled (see `Settled`).
    pub recovery_while_unsettled: bool,
    /// The retry (drop in nats per beam, scale of the step's spread); None: off.
    pub retry: Option<(f32, f32)>,
    /// ESS fraction below which the set is resampled.
    pub resample_ess: f32,
    /// Scans to run (at most the log's).
    pub scans: usize,
    /// Beams the map cannot explain left out of each update (distance in metres, largest
    /// share); None: off (`MclConfig::with_unexplained`, product weighting only).
    pub unexplained: Option<(f32, f32)>,
    /// Expansion and free-space resetting and the settle guard driven by the quality signal
    /// (`MclConfig::with_resetting(Some(Resetting::DEFAULT))`); needs the free space.
    pub resetting: bool,
    /// With `resetting`: the most free-space candidates scored per update
    /// (`Resetting::candidates_per_update`; 0 scores all at the update that starts the reset).
    pub reset_per_update: u32,
    /// The quality signal's clutter allowance (`QualityThresholds::clutter_share`; 0: off).
    pub clutter_share: f32,
    /// The quality signal's Lost on readings through mapped walls
    /// (`QualityThresholds::lost_through`; 1: off).
    pub lost_through: f32,
    /// The adaptive motion noise (target, rate, smallest and largest variance scale,
    /// `MclConfig::with_adaptive_noise`); None: off.
    pub adaptive_noise: Option<[f32; 4]>,
    /// KLD sampling between these particle counts (nav2's `pf_err` 0.05, `pf_z` 0.99, bins
    /// 0.5 m and 10°; `MclConfig::with_kld`), starting from `particles`; None: a fixed count.
    pub kld: Option<(u16, u16)>,
    /// The likelihood's σ_hit following the predicted cloud's spread, (gain, largest σ in
    /// metres): σ² = σ_hit² + gain · (var x + var y) / 2 of the particles before each update;
    /// None: the fixed σ_hit.
    pub adaptive_sigma: Option<(f32, f32)>,
    /// κ while the quality signal does not report `Tracking` (None: `kappa` always).
    pub kappa_uncertain: Option<f32>,
    /// Update the filter only once the odometry has moved this far since the last update
    /// (metres, radians: AMCL's `update_min_d`, `update_min_a`); in between, the estimate is
    /// the last one moved by the odometry. `(0, 0)` updates at every scan.
    pub update_min: (f32, f32),
}

/// One update of a run, as `--json` reports it: where the filter put the robot, how sure it
/// said it was, and (at scans with a truth) how far off it was.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct ScanRecord {
    /// The scan (0-based FLASER index of the log).
    pub scan: usize,
    /// The estimate: x, y (metres), heading (radians).
    pub pose: [f32; 3],
    /// The reported covariance (`Update::covariance`): xx, xy, yy (m²), θθ (rad²).
    pub covariance: [f32; 4],
    /// The particles' covariance (`Estimate::covariance`): xx, xy, yy (m²), θθ (rad²).
    pub particle_covariance: [f32; 4],
    /// The effective sample size of the weights the estimate came from.
    pub ess: f32,
    /// The quality signal's state: `tracking`, `uncertain` or `lost`.
    pub quality: &'static str,
    /// The scan's share of beams the map explains at the estimate, clutter set aside (0 to 1,
    /// the quality signal's input; NaN, as null, when the update was skipped).
    pub explained: f32,
    /// How the scan fits the map at the estimate, shares of its beams: explained, short of a
    /// mapped wall and not explained, through a mapped wall (`beamfield::mcl::ScanFit`).
    pub fit: [f32; 3],
    /// The likelihood per beam, `ln w_avg / beams` (nats).
    pub ln_beam: f32,
    /// The estimate's spread (metres, radians) and concentration (0 to 1), as the quality
    /// signal saw them.
    pub spread: [f32; 3],
    /// Expansion resetting widened the cloud at this update.
    pub expanded: bool,
    /// This update's resampling was a free-space reset.
    pub reset: bool,
    /// The update was skipped (empty scan) or discarded (all particles impossible).
    pub skipped: bool,
    /// The truth at this scan: x, y (metres), heading (radians); `None` where there is none.
    pub truth: Option<[f32; 3]>,
    /// Translation error against the truth, metres (`None` where there is no truth).
    pub error_m: Option<f64>,
    /// Heading error against the truth, degrees (`None` where there is no truth).
    pub heading_error_deg: Option<f64>,
}

/// The name of a quality state in reports.
pub fn quality_name(q: Quality) -> &'static str {
    match q {
        Quality::Tracking => "tracking",
        Quality::Uncertain => "uncertain",
        Quality::Lost => "lost",
    }
}

/// The outcome of one run.
#[derive(Clone, Debug)]
pub struct RunResult {
    /// The first scan run (0, or the first reference scan).
    pub start: usize,
    /// The estimate after each scan run (scans `start..`).
    pub estimates: Vec<Pose>,
    /// The scans at which the errors below were measured (every scan run, or the reference
    /// scans), in order.
    pub scored: Vec<usize>,
    /// Translation error per scored scan, metres.
    pub trans_err_m: Vec<f64>,
    /// Heading error per scored scan, degrees.
    pub heading_err_deg: Vec<f64>,
    /// Every update of the run (scans `start..`).
    pub per_scan: Vec<ScanRecord>,
    /// Scans whose update was skipped (empty scan) or discarded (all particles impossible).
    pub skipped: usize,
    /// Resamplings.
    pub resamplings: usize,
    /// Random particles injected by recovery, in total.
    pub injected: u64,
    /// Updates at which the retry moved and reweighted the set.
    pub retries: usize,
    /// The odometry noise's variance scale after each scan (`Mcl::noise_scale`; 1 without the
    /// adaptive motion noise).
    pub noise_scales: Vec<f32>,
    /// The particles in use after each scan.
    pub particles_in_use: Vec<usize>,
    /// Free-space resets (`--resetting`).
    pub resets: usize,
}

/// The quality table of a run: its updates at the scored scans, by the state the quality
/// signal reported and by whether the estimate was within [`LOST_M`] of the truth.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct QualityTable {
    /// `Tracking` while within [`LOST_M`].
    pub tracking_within: usize,
    /// `Tracking` while more than [`LOST_M`] off.
    pub tracking_off: usize,
    /// `Uncertain` while within.
    pub uncertain_within: usize,
    /// `Uncertain` while off.
    pub uncertain_off: usize,
    /// `Lost` while within (a false alarm).
    pub lost_within: usize,
    /// `Lost` while off.
    pub lost_off: usize,
}

/// Summary figures of a run.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Metrics {
    /// Translation RMSE over the scans, metres.
    pub trans_rmse_m: f64,
    /// Heading RMSE, degrees.
    pub heading_rmse_deg: f64,
    /// Largest translation error, metres.
    pub max_trans_m: f64,
    /// Fraction of scans within 10 cm and 2°.
    pub within_10cm_2deg: f64,
    /// The estimate was once more than 0.5 m off.
    pub lost: bool,
    /// First scan from which the estimate stays within 20 cm / 5° for 20 scans (counted from
    /// the start, or from the kidnapping).
    pub converged_after: Option<usize>,
    /// The run converged and was later more than 0.5 m off (at a scan after the 20 that
    /// made it converge).
    pub lost_after_convergence: bool,
    /// Scans at which the errors were measured.
    pub scored_scans: usize,
    /// The quality table over the scored scans.
    pub quality: QualityTable,
}

impl RunResult {
    /// The summary over the scored scans (the RMSE and fractions over all of them; convergence
    /// counted in scored scans from the first at or after scan `from`).
    pub fn metrics(&self, from: usize) -> Metrics {
        let from = self.scored.partition_point(|&s| s < from);
        let n = self.trans_err_m.len().max(1) as f64;
        let trans_rmse_m = (self.trans_err_m.iter().map(|e| e * e).sum::<f64>() / n).sqrt();
        let heading_rmse_deg = (self.heading_err_deg.iter().map(|e| e * e).sum::<f64>() / n).sqrt();
        let max_trans_m = self.trans_err_m.iter().copied().fold(0.0, f64::max);
        let ok: Vec<bool> = self
            .trans_err_m
            .iter()
            .zip(&self.heading_err_deg)
            .map(|(&t, &h)| t <= 0.10 && h <= 2.0)
            .collect();
        let within = ok.iter().filter(|&&b| b).count() as f64 / n;
        let close: Vec<bool> = self
            .trans_err_m
            .iter()
            .zip(&self.heading_err_deg)
            .map(|(&t, &h)| t <= CONVERGED_M && h <= CONVERGED_DEG)
            .collect();
        let mut converged_after = None;
        let mut streak = 0usize;
        for (k, &c) in close.iter().enumerate().skip(from) {
            streak = if c { streak + 1 } else { 0 };
            if streak == CONVERGED_SCANS {
                converged_after = Some(k + 1 - CONVERGED_SCANS - from);
                break;
            }
        }
        let lost_after_convergence = converged_after.is_some_and(|c| {
            self.trans_err_m
                .iter()
                .skip(from + c + CONVERGED_SCANS)
                .any(|&e| e > LOST_M)
        });
        let mut quality = QualityTable::default();
        for (&scan, &e) in self.scored.iter().zip(&self.trans_err_m) {
            let Some(rec) = scan
                .checked_sub(self.start)
                .and_then(|i| self.per_scan.get(i))
            else {
                continue;
            };
            let off = e > LOST_M;
            let slot = match (rec.quality, off) {
                ("tracking", false) => &mut quality.tracking_within,
                ("tracking", true) => &mut quality.tracking_off,
                ("lost", false) => &mut quality.lost_within,
                ("lost", true) => &mut quality.lost_off,
                (_, false) => &mut quality.uncertain_within,
                (_, true) => &mut quality.uncertain_off,
            };
            *slot += 1;
        }
        Metrics {
            scored_scans: self.scored.len(),
            quality,
            lost_after_convergence,
            trans_rmse_m,
            heading_rmse_deg,
            max_trans_m,
            within_10cm_2deg: within,
            lost: max_trans_m > LOST_M,
            converged_after,
        }
    }
}

/// AMCL's `likelihood_field` weight of `scan` at `pose`: `ln(1 + Σ p_k³)`.
fn amcl_cube(
    view: &FieldView<'_>,
    params: &LikelihoodParams,
    layout: &BeamLayout<MAX_BEAMS>,
    scan: &Scan<MAX_BEAMS>,
    stride: usize,
    pose: &Pose,
) -> f32 {
    let (s, c) = (pose.theta_rad.sin(), pose.theta_rad.cos());
    let denom = 2.0 * params.sigma_hit_m() * params.sigma_hit_m();
    let rand = params.z_rand() / params.max_range_m();
    let mut p = 1.0f32;
    for (beam, &r) in layout.beams().iter().zip(scan.ranges_m()).step_by(stride) {
        if !matches!(
            Reading::classify(r, params.max_range_m()),
            Reading::Range(_)
        ) {
            continue;
        }
        let (bx, by) = (beam.cos * c - beam.sin * s, beam.sin * c + beam.cos * s);
        let d = view.distance_m(pose.x_m + r * bx, pose.y_m + r * by);
        let pz = params.z_hit() * (-d * d / denom).exp() + rand;
        p += pz * pz * pz;
    }
    p.ln()
}

/// Runs the filter over the log once.
///
/// # Errors
/// [`TrackError::Usage`] for bad options (global initialization or recovery without free
/// space, too many particles), [`TrackError::Filter`].
pub fn run_once(input: &TrackInput, o: &RunOptions) -> Result<RunResult, TrackError> {
    let (view, free) = input.views()?;
    if o.particles == 0 || o.particles > MAX_TRACK_PARTICLES {
        return Err(usage(format!(
            "--particles {}: must be 1 ..= {MAX_TRACK_PARTICLES}",
            o.particles
        )));
    }
    if (o.init == Init::Global || o.kidnap.is_some()) && free.is_none() {
        return Err(usage(
            "--init global and --kidnap need a field built with --free-space",
        ));
    }
    let recovery_on = o.recovery.0 > 0.0 || o.recovery.1 > 0.0;
    if recovery_on && free.is_none() {
        // Recovery draws its random particles from the free space: without it, none.
        return Err(usage(
            "--recovery injects particles drawn from the free space: it needs a field built with --free-space",
        ));
    }
    if o.resetting && free.is_none() {
        return Err(usage(
            "--resetting renews the cloud from the free space when lost: it needs a field built with --free-space",
        ));
    }
    if o.recovery_while_unsettled && !recovery_on {
        return Err(usage(
            "--recovery-while-unsettled only limits --recovery, which is off",
        ));
    }
    let noise = OdometryNoise::new(o.alphas[0], o.alphas[1], o.alphas[2], o.alphas[3])
        .map_err(|e| usage(format!("--odom-noise: {e}")))?;
    let config = MclConfig::new(noise, o.resample_ess, o.recovery.0, o.recovery.1)
        .map_err(|e| usage(format!("--recovery / --resample-ess: {e}")))?;
    let config = match o.retry {
        Some((drop, scale)) => config
            .with_retry(drop, scale)
            .map_err(|e| usage(format!("--retry: {e}")))?,
        None => config,
    };
    let config = config
        .with_quality(QualityThresholds {
            clutter_share: o.clutter_share,
            lost_through: o.lost_through,
            ..QualityThresholds::DEFAULT
        })
        .map_err(|e| usage(format!("--clutter-share or --lost-through: {e}")))?
        .with_unexplained(o.unexplained.map(|(distance_m, max_share)| Unexplained {
            distance_m,
            max_share,
        }))
        .map_err(|e| usage(format!("--unexplained: {e}")))?
        .with_resetting(o.resetting.then_some(Resetting {
            candidates_per_update: o.reset_per_update,
            ..Resetting::DEFAULT
        }))
        .map_err(|e| usage(format!("--resetting: {e}")))?
        .with_adaptive_noise(
            o.adaptive_noise
                .map(|[target, rate, min_scale, max_scale]| AdaptiveNoise {
                    target,
                    rate,
                    min_scale,
                    max_scale,
                }),
        )
        .map_err(|e| usage(format!("--adaptive-noise: {e}")))?
        .with_kld(o.kld.map(|(min, max)| Kld {
            min,
            max,
            ..Kld::NAV2
        }))
        .map_err(|e| usage(format!("--kld: {e}")))?;
    let lf = LikelihoodField::new(view, input.params);
    let mut model = Tempered::new(lf, o.kappa, o.stride)
        .map_err(|e| usage(format!("--kappa / --stride: {e}")))?;
    let mut store: Box<Particles<MAX_TRACK_PARTICLES>> = Box::default();
    let mut mcl = Mcl::new(&mut store, config).map_err(TrackError::Filter)?;
    let mut rng = SplitMix64::new(o.seed);
    let mut kidnap_rng = SplitMix64::new(o.seed ^ KIDNAP_SEED_XOR);
    let n = o.scans.min(input.scans.len());
    // With a reference, the run starts at its first pose (the truth is unknown before it).
    let (start, first) = match input.first_truth().and_then(|k| Some((k, input.truth(k)?))) {
        Some((k, p)) if k < n => (k, p),
        _ => {
            return Err(usage(format!(
                "no reference pose within the {n} scans run: nothing to start from or score against"
            )))
        }
    };
    if let Some(k) = o.kidnap {
        if k <= start || input.truth(k).is_none() {
            return Err(usage(format!(
                "--kidnap {k}: must be a scan after the first with a reference pose ({start}), and have one"
            )));
        }
    }
    match (o.init, &free) {
        (Init::Global, Some(f)) => mcl.init_uniform(o.particles, f, &mut rng),
        _ => mcl.init_gaussian(
            o.particles,
            &first,
            INIT_SIGMA_XY_M,
            INIT_SIGMA_THETA_RAD,
            &mut rng,
        ),
    }
    .map_err(TrackError::Filter)?;
    let mut out = RunResult {
        start,
        estimates: Vec::with_capacity(n - start),
        scored: Vec::new(),
        trans_err_m: Vec::new(),
        heading_err_deg: Vec::new(),
        per_scan: Vec::with_capacity(n - start),
        skipped: 0,
        resamplings: 0,
        injected: 0,
        retries: 0,
        noise_scales: Vec::with_capacity(n),
        particles_in_use: Vec::with_capacity(n),
        resets: 0,
    };
    let progress = std::io::stderr().is_terminal();
    let odom = match &input.odometry {
        Some(recorded) => recorded.get(..n).unwrap_or(recorded).to_vec(),
        None => synthesize_odometry(&noise, input.logged.get(..n).unwrap_or(&[]), o.seed)?,
    };
    if odom.len() < n {
        return Err(usage(format!(
            "the odometry has {} poses for {n} scans",
            odom.len()
        )));
    }
    let mut settled = Settled::default();
    let mut seen = OdometryStep::STILL;
    // The odometry of the last update: the filter's steps run from there.
    let mut last = start;
    for k in start..n {
        let truth = input.truth(k);
        let mut carried = None;
        if k > start {
            seen = OdometryStep::between(&odom[last], &odom[k])
                .map_err(|e| usage(format!("odometry {k}: {e}")))?;
            let moved = seen.trans_m() >= o.update_min.0
                || wrap_angle(seen.rot1_rad() + seen.rot2_rad()).abs() >= o.update_min.1;
            // The scan of a kidnapping is always weighed.
            if !moved && o.kidnap != Some(k) {
                // No update: the last estimate carried by the odometry since, as AMCL's
                // map → odom transform carries it.
                carried = Some(seen.apply(&mcl.estimate().pose));
            } else {
                last = k;
                mcl.predict(&seen, &mut rng);
            }
        }
        // While settled, no free space: no random particles (the averages still follow).
        let free_now = if o.recovery_while_unsettled && settled.done() {
            None
        } else {
            free.as_ref()
        };
        if o.kidnap == Some(k) {
            if let (Some(f), Some(t)) = (&free, &truth) {
                kidnap(&mut mcl, f, t, &mut kidnap_rng);
            }
        }
        let scan = &Scan::<MAX_BEAMS>::from_ranges(&input.scans[k])
            .map_err(|e| usage(format!("scan {k}: {e}")))?;
        if let Some(k_unc) = o.kappa_uncertain {
            let kappa = if mcl.quality().state == Quality::Tracking {
                o.kappa
            } else {
                k_unc
            };
            if kappa != model.kappa() {
                model = Tempered::new(LikelihoodField::new(view, input.params), kappa, o.stride)
                    .map_err(|e| usage(format!("--kappa-uncertain: {e}")))?;
            }
        }
        if let Some((gain, max_sigma)) = o.adaptive_sigma {
            let base = input.params;
            let spread = cloud_xy_variance(mcl.poses(), mcl.weights());
            let sigma = (base.sigma_hit_m().powi(2) + gain * spread)
                .sqrt()
                .clamp(base.sigma_hit_m(), max_sigma.max(base.sigma_hit_m()));
            let params =
                LikelihoodParams::new(base.z_hit(), base.z_rand(), sigma, base.max_range_m())
                    .map_err(|e| usage(format!("--adaptive-sigma: {e}")))?;
            model = Tempered::new(LikelihoodField::new(view, params), o.kappa, o.stride)
                .map_err(|e| usage(format!("--kappa / --stride: {e}")))?;
        }
        let result = match o.weighting {
            _ if carried.is_some() => Err(MclError::EmptyScan),
            Weighting::Product => {
                let prepared = model.prepare(&input.layout, scan);
                mcl.update_prepared(&prepared, free_now, &mut rng)
            }
            Weighting::AmclCube => {
                if scan.is_empty() {
                    Err(MclError::EmptyScan)
                } else {
                    mcl.update_with(
                        |p| amcl_cube(&view, &input.params, &input.layout, scan, o.stride, p),
                        free_now,
                        &mut rng,
                    )
                }
            }
        };
        let (update, skipped) = match result {
            Ok(u) => {
                out.resamplings += usize::from(u.resampled);
                out.injected += u64::from(u.injected);
                out.retries += usize::from(u.retried);
                out.resets += usize::from(u.reset);
                settled.observe(&u.estimate, &seen);
                (Some(u), false)
            }
            Err(MclError::EmptyScan) if carried.is_some() => (None, false),
            Err(MclError::EmptyScan | MclError::AllImpossible) => {
                out.skipped += 1;
                (None, true)
            }
            Err(e) => return Err(TrackError::Filter(e)),
        };
        out.noise_scales.push(mcl.noise_scale());
        out.particles_in_use.push(mcl.len());
        let estimate = update.map_or_else(|| *mcl.estimate(), |u| u.estimate);
        let quality = update.map_or_else(|| *mcl.quality(), |u| u.quality);
        let est = carried.unwrap_or(estimate.pose);
        let errors = truth.map(|truth| {
            let dx = f64::from(est.x_m - truth.x_m);
            let dy = f64::from(est.y_m - truth.y_m);
            let head = f64::from(wrap_angle(est.theta_rad - truth.theta_rad))
                .abs()
                .to_degrees();
            (dx.hypot(dy), head)
        });
        if let Some((e, h)) = errors {
            out.scored.push(k);
            out.trans_err_m.push(e);
            out.heading_err_deg.push(h);
        }
        let c = &estimate.covariance;
        let r = update.map_or_else(|| *mcl.reported_covariance(), |u| u.covariance);
        out.per_scan.push(ScanRecord {
            scan: k,
            pose: [est.x_m, est.y_m, est.theta_rad],
            covariance: [r[0][0], r[0][1], r[1][1], r[2][2]],
            particle_covariance: [c[0][0], c[0][1], c[1][1], c[2][2]],
            ess: estimate.ess,
            quality: quality_name(quality.state),
            explained: quality.explained,
            fit: [
                quality.fit.explained,
                quality.fit.short,
                quality.fit.through,
            ],
            ln_beam: quality.ln_beam,
            spread: [quality.spread_m, quality.spread_rad, quality.concentration],
            expanded: update.is_some_and(|u| u.expanded),
            reset: update.is_some_and(|u| u.reset),
            skipped,
            truth: truth.map(|t| [t.x_m, t.y_m, t.theta_rad]),
            error_m: errors.map(|e| e.0),
            heading_error_deg: errors.map(|e| e.1),
        });
        out.estimates.push(est);
        if progress && (k % 50 == 0 || k + 1 == n) {
            eprint!("\rseed {}: scan {}/{n}", o.seed, k + 1);
            if k + 1 == n {
                eprintln!();
            }
        }
    }
    Ok(out)
}

/// The filter's own test of having settled, for `--recovery-while-unsettled`. Settled: for
/// [`Settled::SCANS`] updates in a row, each estimate lies within [`Settled::MOVE_M`] and
/// [`Settled::MOVE_RAD`] of the previous one moved by the odometry step, and the estimate's
/// standard deviations are at most [`Settled::SPREAD_M`] and [`Settled::SPREAD_RAD`]. Settled
/// ends after [`Settled::MISSES`] updates in a row that break the first test: a single jump
/// (often a random particle winning for a scan, the hijacking this guards against) does not
/// end it. Uses nothing but the filter's output and the odometry.
#[derive(Default)]
struct Settled {
    previous: Option<Pose>,
    streak: usize,
    misses: usize,
    settled: bool,
}

impl Settled {
    const SPREAD_M: f32 = 0.15;
    const SPREAD_RAD: f32 = 0.1;
    const MOVE_M: f32 = 0.15;
    const MOVE_RAD: f32 = 0.1;
    const SCANS: usize = 20;
    const MISSES: usize = 5;

    fn observe(&mut self, e: &beamfield::mcl::Estimate, step: &OdometryStep) {
        let c = &e.covariance;
        let tight =
            c[0][0].max(c[1][1]).sqrt() <= Self::SPREAD_M && c[2][2].sqrt() <= Self::SPREAD_RAD;
        let consistent = self.previous.is_some_and(|prev| {
            let moved = step.apply(&prev);
            (moved.x_m - e.pose.x_m).hypot(moved.y_m - e.pose.y_m) <= Self::MOVE_M
                && wrap_angle(moved.theta_rad - e.pose.theta_rad).abs() <= Self::MOVE_RAD
        });
        self.previous = Some(e.pose);
        if tight && consistent {
            self.streak += 1;
            self.misses = 0;
        } else {
            self.streak = 0;
            self.misses += 1;
        }
        if self.streak >= Self::SCANS {
            self.settled = true;
        } else if self.misses >= Self::MISSES {
            self.settled = false;
        }
    }

    fn done(&self) -> bool {
        self.settled
    }
}

/// Moves the whole cloud rigidly so that the truth lands on a free pose at least
/// [`KIDNAP_MIN_M`] away: from the filter's side, the robot was carried off. The weights and
/// recovery averages are kept (only the poses move).
fn kidnap<const N: usize>(
    mcl: &mut Mcl<'_, N>,
    free: &FreeSpace<'_>,
    truth: &Pose,
    kidnap_rng: &mut SplitMix64,
) {
    let mut wrong = free.sample_pose(kidnap_rng);
    for _ in 0..10_000 {
        if (wrong.x_m - truth.x_m).hypot(wrong.y_m - truth.y_m) >= KIDNAP_MIN_M {
            break;
        }
        wrong = free.sample_pose(kidnap_rng);
    }
    // p' = wrong ⊕ (truth⁻¹ ⊕ p), in f64.
    let (tx, ty, tt) = (
        f64::from(truth.x_m),
        f64::from(truth.y_m),
        f64::from(truth.theta_rad),
    );
    let (wx, wy, wt) = (
        f64::from(wrong.x_m),
        f64::from(wrong.y_m),
        f64::from(wrong.theta_rad),
    );
    let turn = wt - tt;
    let (s, c) = turn.sin_cos();
    mcl.move_particles(|p| {
        let (dx, dy) = (f64::from(p.x_m) - tx, f64::from(p.y_m) - ty);
        Pose::new(
            (wx + c * dx - s * dy) as f32,
            (wy + s * dx + c * dy) as f32,
            (f64::from(p.theta_rad) + turn) as f32,
        )
    });
}

/// The weighted mean of the x and y variances of a particle set (m²); 0 for an empty set.
fn cloud_xy_variance(poses: &[Pose], weights: &[f32]) -> f32 {
    let (mut sw, mut sx, mut sy) = (0.0f64, 0.0f64, 0.0f64);
    for (p, &w) in poses.iter().zip(weights) {
        let w = f64::from(w);
        sw += w;
        sx += w * f64::from(p.x_m);
        sy += w * f64::from(p.y_m);
    }
    if sw <= 0.0 {
        return 0.0;
    }
    let (mx, my) = (sx / sw, sy / sw);
    let mut v = 0.0f64;
    for (p, &w) in poses.iter().zip(weights) {
        let (dx, dy) = (f64::from(p.x_m) - mx, f64::from(p.y_m) - my);
        v += f64::from(w) * (dx * dx + dy * dy);
    }
    (v / sw / 2.0) as f32
}
