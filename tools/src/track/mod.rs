//! Monte Carlo localization ([`beamfield::mcl`]) over a whole CARMEN log, measured against the
//! logged poses: the runs behind `beamfield track` (its CLI is [`crate::cmd::track`]).
//!
//! The shared logs carry corrected poses and no raw odometry, so odometry is synthesized:
//! starting at the first logged pose, each step between consecutive logged poses (Thrun's
//! `(δrot1, δtrans, δrot2)`) is perturbed by the filter's own motion model
//! (the variances of [`beamfield::mcl::OdometryNoise::sigmas`], AMCL's `odom_alpha1..4` convention, drawn with
//! Box–Muller normals by `odometry_sample`, not the filter's ziggurat) and chained. The
//! filter sees only these odometry poses and the scans; the logged poses are the truth it is
//! scored against.
//!
//! Random numbers, all [`SplitMix64`](beamfield::mcl::SplitMix64):
//! - odometry: seed `S ^ ODOMETRY_SEED_XOR`;
//! - the filter (initialization, motion samples, resampling, recovery): seed `S`;
//! - the kidnapping's wrong pose: seed `S ^ KIDNAP_SEED_XOR`;
//! - with `--wheel-odometry`, the odometry comes from the wheel model ([`wheels`]: wrong radii
//!   and wheelbase, slip; not the filter's model), its slip drawn from seed `S ^ WHEEL_SEED_XOR`.
//!
//! The FLASER pose is the laser's pose, so the filter estimates laser poses (centred mount).

use crate::input::carmen::LogError;
use beamfield::field::{BlobError, FreeSpaceError};
use beamfield::mcl::MclError;
use clap::ValueEnum;
use std::path::PathBuf;

/// Largest `--particles`.
pub const MAX_TRACK_PARTICLES: usize = 20_000;
/// Largest `--seeds`: 1,000 runs (each a whole pass over the log; the docs' studies use 20).
pub const MAX_TRACK_SEEDS: u64 = 1000;
/// XOR applied to the seed for the odometry generator.
pub const ODOMETRY_SEED_XOR: u64 = 0x6F64_6F6D_6574_7279;
/// XOR applied to the seed for the wheel model's slip (`--wheel-odometry`; "wheel" in ASCII, the
/// XOR the host tests' `intel_quality` study uses, so seed S gives the same odometry there).
pub const WHEEL_SEED_XOR: u64 = 0x77_6865_656c;
/// XOR applied to the seed for the kidnapping's wrong pose.
pub const KIDNAP_SEED_XOR: u64 = 0x6B69_646E_6170_0000;
/// Spread of the initial cloud around the first logged pose (`--init logged`): σ metres.
pub const INIT_SIGMA_XY_M: f32 = 0.05;
/// Spread of the initial cloud around the first logged pose: σ radians (2°).
pub const INIT_SIGMA_THETA_RAD: f32 = 0.035;
/// A run is lost when the estimate is ever farther than this from the logged pose, metres.
pub const LOST_M: f64 = 0.5;
/// Converged (global localization, kidnapping): within this distance, metres …
pub const CONVERGED_M: f64 = 0.20;
/// … and this heading error, degrees …
pub const CONVERGED_DEG: f64 = 5.0;
/// … for this many consecutive scans.
pub const CONVERGED_SCANS: usize = 20;
/// The kidnapped robot is put at least this far from the truth, metres.
pub const KIDNAP_MIN_M: f32 = 3.0;

/// How the initial cloud is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Init {
    /// Gaussian around the first logged pose (σ 5 cm, 2°).
    Logged,
    /// Uniform over the free space appended to the field file (global localization).
    Global,
}

/// A wheel model preset for `--wheel-odometry` ([`wheels::WheelErrors`]): the real wheels of a
/// differential-drive base relative to what its odometry believes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum WheelPreset {
    /// Left radius +0.6 %, right −0.4 %, wheelbase +1.5 %, slip σ 1.5 % of each wheel's travel
    /// per step.
    Mild,
    /// Twice mild: left radius +1.2 %, right −0.8 %, wheelbase +3 %, slip σ 3 % per step.
    Strong,
    /// `cargo xtask robot`'s: left radius +0.3 %, right −0.2 %, wheelbase +1 %, slip σ 1 % per
    /// step, and one step in 500 in which one wheel loses 20 % of its travel.
    Typical,
}

impl WheelPreset {
    /// The wheel errors of the preset.
    pub fn errors(self) -> wheels::WheelErrors {
        match self {
            Self::Mild => wheels::WheelErrors::MILD,
            Self::Strong => wheels::WheelErrors::STRONG,
            Self::Typical => wheels::WheelErrors::TYPICAL,
        }
    }

    /// The preset's name on the command line and in reports (`mild`, `strong`, `typical`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Mild => "mild",
            Self::Strong => "strong",
            Self::Typical => "typical",
        }
    }

    /// The odometry of run seed `seed` along `logged`: [`wheels::wheel_odometry`] with the
    /// preset's errors, its slip drawn from `seed ^ WHEEL_SEED_XOR`. One pose per logged pose.
    pub fn odometry(self, logged: &[beamfield::Pose], seed: u64) -> Vec<beamfield::Pose> {
        wheels::wheel_odometry(logged, &self.errors(), seed ^ WHEEL_SEED_XOR)
    }
}

/// How particles are weighted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Weighting {
    /// The crate's likelihood field: Σ ln p(z_k | x, m) over every stride-th beam, divided by κ.
    Product,
    /// AMCL's `likelihood_field` weighting, as a baseline: weight 1 + Σ p_k³ with
    /// p_k = z_hit·exp(−d²/2σ²) + z_rand/z_max (unnormalized Gaussian), every stride-th beam.
    AmclCube,
}

/// Errors of `beamfield track`.
#[derive(Debug)]
#[non_exhaustive]
pub enum TrackError {
    /// A file could not be read or written.
    Io(PathBuf, std::io::Error),
    /// A file that is not a regular file or over its size limit (docs/resource-limits.md).
    Read(crate::input::limits::ReadError),
    /// The distance-field blob is malformed.
    Blob(BlobError),
    /// The free-space section after the blob is malformed.
    FreeSpace(FreeSpaceError),
    /// The log could not be read.
    Log(LogError),
    /// A bad option value.
    Usage(String),
    /// The filter refused its input.
    Filter(MclError),
    /// The picture could not be written.
    Png(PathBuf, String),
}

impl std::fmt::Display for TrackError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Io(p, e) => write!(f, "{}: {e}", p.display()),
            Self::Read(e) => write!(f, "{e}"),
            Self::Blob(e) => write!(
                f,
                "bad field blob: {e}{}",
                crate::input::field_file::blob_hint(e)
            ),
            Self::FreeSpace(e) => write!(f, "bad free-space section: {e}"),
            Self::Log(e) => write!(f, "{e}"),
            Self::Usage(m) => f.write_str(m),
            Self::Filter(e) => write!(f, "filter: {e}"),
            Self::Png(p, e) => write!(f, "{}: {e}", p.display()),
        }
    }
}

impl std::error::Error for TrackError {}

/// A [`TrackError::Usage`].
pub fn usage(m: impl Into<String>) -> TrackError {
    TrackError::Usage(m.into())
}

pub mod draws;
mod input;
mod odometry;
mod recorded;
mod run;
pub mod wheels;

pub use input::{field_bytes, load, load_with_max_range, TrackInput};
pub use odometry::{odometry_sample, synthesize_odometry};
pub use recorded::{load_bag, read_odometry_file, read_reference_file, BagSummary, ScanLayout};
pub use run::{quality_name, run_once, Metrics, QualityTable, RunOptions, RunResult, ScanRecord};
