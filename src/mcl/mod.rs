//! Monte Carlo localization on the device (Thrun, Burgard & Fox ch. 8, on the ch. 6 models):
//! allocation-free, capacity as a const generic, storage placed by the caller.
//!
//! - [`motion`]: the odometry motion model, sampled (Table 5.6), with AMCL's
//!   `odom_alpha1..4` variance convention.
//! - [`resample`]: low-variance resampling (Table 4.4) in place, one `u16` per particle.
//! - [`estimate`]: weighted mean, circular mean heading, covariance, effective sample size.
//! - [`config`]: [`Particles`] (the caller-placed storage), [`MclConfig`], [`MclError`],
//!   [`Update`].
//! - [`filter`]: [`Mcl`] over [`Particles`]: prediction, reweighting by any
//!   [`SensorModel`](crate::SensorModel) or a prepared tempered scan, resampling when the
//!   effective sample size drops, augmented-MCL recovery (Table 8.3) from a
//!   [`FreeSpace`](crate::field::FreeSpace) section, uniform and Gaussian initialization.
//! - [`odometry`]: differential-drive odometry from encoder ticks ([`odometry::DiffDrive`]),
//!   exact arc integration, wrapping counters.
//! - [`quality`]: the localization-quality signal ([`Quality`]: tracking, uncertain, lost)
//!   reported by every update, and the recovery it drives in fixed memory ([`Resetting`]:
//!   expansion resetting, free-space resetting, the settle guard).
//! - [`adaptive`]: the odometry noise scaled by the scans' corrections ([`AdaptiveNoise`],
//!   opt-in).
//! - [`kld`]: KLD sampling ([`Kld`], opt-in): the particle count adapts inside the capacity.
//! - [`unexplained`]: readings the map cannot explain ([`Unexplained`]), left out of an
//!   update (opt-in).
//! - [`rng`]: [`SplitMix64`] (the filter's) and [`XorShift64`] (the randomized checks'), seeded
//!   generators the host and the device run identically.
//!
//! Memory: 18 bytes per particle of capacity (pose 12, weight 4, resampling count 2) in
//! [`Particles`], plus a fixed 336 bytes (on a 64-bit host; less on a 32-bit target) in [`Mcl`]
//! (the configuration, the recovery and quality
//! averages, the last estimate and quality report). See `docs/localization.md` for the
//! measurements on the Intel lab log.

pub mod adaptive;
pub mod config;
pub mod estimate;
pub mod filter;
pub mod kld;
pub mod motion;
pub mod normal;
pub mod odometry;
pub mod quality;
pub mod resample;
pub mod rng;
pub mod unexplained;

pub use adaptive::{AdaptiveNoise, MAX_NOISE_SCALE};
pub use config::{
    MclConfig, MclError, Particles, Update, MAX_PARTICLES, MAX_RETRY_SCALE, RETRY_LEVEL_RATE,
};
pub use estimate::{diagonal_variances, Estimate, ReportedCovariance};
pub use filter::{Mcl, ESTIMATE_HALF_ANGLE_RAD, ESTIMATE_RADIUS_M};
pub use kld::Kld;
pub use motion::{
    MotionError, OdometryNoise, OdometryStep, IN_PLACE_TURN_M, MAX_ALPHA, MAX_STEP_M,
    MAX_STEP_ROTATION_RAD,
};
pub use quality::{Quality, QualityReport, QualityThresholds, Resetting};
pub use rng::{SplitMix64, XorShift64};
pub use unexplained::{ScanFit, Unexplained};
