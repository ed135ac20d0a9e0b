//! What the on-device track computes, shared word for word by the firmware
//! (`src/bin/track.rs`) and the host's recomputation of it (`cargo xtask track` runs this module
//! with the same crate on the PC and requires every printed bit pattern to match).
//!
//! The run is `beamfield track`'s default run over the first [`TrackScan`]s of the Intel log
//! (`firmware/assets/track.rs`): particles drawn around the first logged pose (σ 5 cm, 2°),
//! then per scan the odometry step between consecutive synthesized odometry poses
//! ([`Mcl::predict`]) and the tempered likelihood field's update ([`Mcl::update_prepared`]),
//! resampling below half the particles' effective sample size, no recovery. The filter's
//! generator is [`SplitMix64`] seeded with the asset's `SEED` (the odometry in the asset was
//! drawn from `SEED ^ 0x6F64_6F6D_6574_7279`, as `beamfield track` does).
//!
//! Only `core` and `beamfield`: it compiles for the Cortex-M and the host alike.

use beamfield::mcl::{
    Estimate, Mcl, MclConfig, MclError, OdometryNoise, OdometryStep, Particles, SplitMix64, Update,
};
use beamfield::{math, wrap_angle, Pose, Scan};

// `cargo xtask` includes this plan and `lidar_plan.rs`, each with its own copy of the setup.
#[allow(clippy::duplicate_mod)]
#[path = "intel_setup.rs"]
mod intel_setup;
pub use intel_setup::BEAMS;
/// Particles (18 bytes each of RAM: 9,000 bytes of [`Particles`]).
pub const PARTICLES: usize = 500;
/// Tempering κ: `beamfield calibrate`'s value on this log (`beamfield track`'s default).
pub const KAPPA: f32 = 8.25;
/// σ_hit of the likelihood field, metres (`beamfield track`'s default).
pub const SIGMA_HIT_M: f32 = 0.05;
/// z_hit (AMCL's default).
pub const Z_HIT: f32 = 0.95;
/// z_rand (AMCL's default).
pub const Z_RAND: f32 = 0.05;
/// Resample when the effective sample size falls below this fraction of the particles.
pub const RESAMPLE_ESS: f32 = 0.5;
/// Spread of the initial cloud around the first logged pose, metres.
pub const INIT_SIGMA_XY_M: f32 = 0.05;
/// Spread of the initial cloud around the first logged pose, radians (2°).
pub const INIT_SIGMA_THETA_RAD: f32 = 0.035;

/// One real scan of the log: its logged (corrected) laser pose, the truth, and the synthesized
/// odometry pose the filter sees.
pub struct TrackScan {
    /// Index of the FLASER line in the log (0-based).
    pub log_index: u32,
    /// Logged laser pose `[x_m, y_m, theta_rad]`: the truth the estimate is measured against.
    pub logged: [f32; 3],
    /// Synthesized odometry pose `[x_m, y_m, theta_rad]` (the first is the first logged pose).
    pub odom: [f32; 3],
    /// The ranges, metres (the log's max-range value means "no return").
    pub ranges_m: [f32; BEAMS],
}

/// What one update reports.
#[derive(Clone, Copy)]
pub struct Step {
    /// Index into the scans.
    pub k: usize,
    /// The update's outcome (the estimate kept from before when it was skipped).
    pub update: Result<Update, MclError>,
    /// The estimate after the update.
    pub estimate: Estimate,
    /// Translation error against the logged pose, metres.
    pub trans_err_m: f64,
    /// Absolute heading error, degrees.
    pub heading_err_deg: f64,
    /// FNV-1a over the bit patterns of every particle's pose and weight after the update.
    pub particles_hash: u32,
}

/// The end of a run.
#[derive(Clone, Copy)]
pub struct Summary {
    /// Updates run.
    pub updates: usize,
    /// Translation RMSE over the updates, metres.
    pub trans_rmse_m: f64,
    /// Heading RMSE, degrees.
    pub heading_rmse_deg: f64,
    /// The last update's errors (metres, degrees).
    pub final_err: (f64, f64),
    /// Largest translation error, metres.
    pub max_trans_m: f64,
    /// Resamplings.
    pub resamplings: usize,
}

fn pose(a: &[f32; 3]) -> Pose {
    Pose::new(a[0], a[1], a[2])
}

/// FNV-1a over the bits of the particles' poses and weights.
pub fn hash_particles(poses: &[Pose], weights: &[f32]) -> u32 {
    let mut h = 0x811C_9DC5u32;
    let mut mix = |v: f32| {
        for b in v.to_bits().to_le_bytes() {
            h = (h ^ u32::from(b)).wrapping_mul(0x0100_0193);
        }
    };
    for (p, &w) in poses.iter().zip(weights) {
        mix(p.x_m);
        mix(p.y_m);
        mix(p.theta_rad);
        mix(w);
    }
    h
}

/// Runs the track over `scans` on `store`, calling `on_step` after every update, and
/// `mark(true)` / `mark(false)` (the instruction-count markers on the device) around three
/// regions per scan: the prediction (none for the first scan), the scan's preparation and the
/// scoring alone of every particle (a baseline: its result is dropped), and the preparation and
/// the whole update (scoring, weights, estimate, resampling). The odometry noise `alpha` (every `odom_alpha`),
/// `seed` and `max_range_m` come from the asset.
///
/// # Errors
/// A message when the blob or a parameter is rejected (nothing has run then).
#[allow(clippy::too_many_arguments)]
pub fn run<const N: usize>(
    store: &mut Particles<N>,
    blob: &[u8],
    scans: &[TrackScan],
    max_range_m: f32,
    alpha: f32,
    seed: u64,
    mut mark: impl FnMut(bool),
    mut on_step: impl FnMut(&Step),
) -> Result<Summary, &'static str> {
    let tempered =
        intel_setup::tempered_field(blob, Z_HIT, Z_RAND, SIGMA_HIT_M, max_range_m, KAPPA)?;
    let layout = intel_setup::layout(max_range_m)?;
    let noise = OdometryNoise::uniform(alpha).map_err(|_| "odometry noise rejected")?;
    let config =
        MclConfig::new(noise, RESAMPLE_ESS, 0.0, 0.0).map_err(|_| "configuration rejected")?;
    let mut mcl = Mcl::new(store, config).map_err(|_| "particle storage rejected")?;
    let mut rng = SplitMix64::new(seed);
    let first = scans.first().ok_or("no scans")?;
    mcl.init_gaussian(
        N,
        &pose(&first.logged),
        INIT_SIGMA_XY_M,
        INIT_SIGMA_THETA_RAD,
        &mut rng,
    )
    .map_err(|_| "initialization rejected")?;
    let mut sum = Summary {
        updates: 0,
        trans_rmse_m: 0.0,
        heading_rmse_deg: 0.0,
        final_err: (0.0, 0.0),
        max_trans_m: 0.0,
        resamplings: 0,
    };
    let (mut se_t, mut se_h) = (0.0f64, 0.0f64);
    let mut previous: Option<&TrackScan> = None;
    for (k, s) in scans.iter().enumerate() {
        let scan = Scan::<BEAMS>::from_ranges(&s.ranges_m).map_err(|_| "scan rejected")?;
        if let Some(prev) = previous {
            let step = OdometryStep::between(&pose(&prev.odom), &pose(&s.odom))
                .map_err(|_| "odometry step rejected")?;
            mark(true);
            mcl.predict(&step, &mut rng);
            mark(false);
        }
        // The scoring alone, of the same particles (the baseline to subtract from the update;
        // it changes nothing).
        mark(true);
        let prepared = tempered.prepare(&layout, &scan);
        let mut total = 0.0f32;
        for p in mcl.poses() {
            total += prepared.score(core::hint::black_box(p)).log_likelihood;
        }
        core::hint::black_box(total);
        mark(false);
        mark(true);
        let prepared = tempered.prepare(&layout, &scan);
        let update = mcl.update_prepared(&prepared, None, &mut rng);
        mark(false);
        previous = Some(s);
        let estimate = *mcl.estimate();
        let truth = pose(&s.logged);
        let dx = f64::from(estimate.pose.x_m - truth.x_m);
        let dy = f64::from(estimate.pose.y_m - truth.y_m);
        let trans_err_m = math::sqrt_f64(dx * dx + dy * dy);
        let heading_err_deg = f64::from(wrap_angle(estimate.pose.theta_rad - truth.theta_rad))
            .abs()
            .to_degrees();
        se_t += trans_err_m * trans_err_m;
        se_h += heading_err_deg * heading_err_deg;
        sum.updates += 1;
        sum.final_err = (trans_err_m, heading_err_deg);
        if trans_err_m > sum.max_trans_m {
            sum.max_trans_m = trans_err_m;
        }
        if let Ok(u) = &update {
            sum.resamplings += usize::from(u.resampled);
        }
        on_step(&Step {
            k,
            update,
            estimate,
            trans_err_m,
            heading_err_deg,
            particles_hash: hash_particles(mcl.poses(), mcl.weights()),
        });
    }
    let n = sum.updates.max(1) as f64;
    sum.trans_rmse_m = math::sqrt_f64(se_t / n);
    sum.heading_rmse_deg = math::sqrt_f64(se_h / n);
    Ok(sum)
}
