//! The localizer's storage, parameters, errors and update report.

use super::adaptive::AdaptiveNoise;
use super::estimate::{Estimate, ReportedCovariance};
use super::kld::Kld;
use super::motion::OdometryNoise;
use super::quality::{QualityReport, QualityThresholds, Resetting};
use super::unexplained::Unexplained;
use crate::pose::Pose;

/// Largest particle capacity: the resampling scratch holds one `u16` count per particle.
pub const MAX_PARTICLES: usize = u16::MAX as usize;

/// Errors of the localizer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum MclError {
    /// The capacity `N` is 0, or an initialization asked for 0 particles.
    ZeroParticles,
    /// More particles than the capacity `N`, or than [`MAX_PARTICLES`].
    TooManyParticles,
    /// The filter has not been initialized.
    NotInitialized,
    /// A configuration value is out of range (which one: see [`MclConfig::new`]).
    BadConfig,
    /// An initial pose or spread is NaN, infinite or negative.
    BadInitialPose,
    /// The scan has no beam to score (empty or all invalid): the measurement was skipped, the
    /// particles and weights are unchanged.
    EmptyScan,
    /// Every particle scored `−∞`: the measurement was discarded and the weights reset to
    /// uniform (the particles are unchanged).
    AllImpossible,
}

impl core::fmt::Display for MclError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::ZeroParticles => "zero particles",
            Self::TooManyParticles => "more particles than the capacity",
            Self::NotInitialized => "filter not initialized",
            Self::BadConfig => "configuration value out of range",
            Self::BadInitialPose => "initial pose or spread not finite",
            Self::EmptyScan => "scan has no beam to score",
            Self::AllImpossible => "every particle is impossible",
        })
    }
}

impl core::error::Error for MclError {}

/// Storage for up to `N` particles: pose (12 B), weight (4 B) and resampling count (2 B) each,
/// 18 bytes per particle of capacity. Build it with [`Particles::new`] (a `const fn`, so it can
/// be a `static`) and lend it to [`Mcl::new`](super::Mcl::new).
#[derive(Clone, Debug)]
pub struct Particles<const N: usize> {
    pub(super) poses: [Pose; N],
    pub(super) weights: [f32; N],
    pub(super) counts: [u16; N],
}

impl<const N: usize> Particles<N> {
    /// Empty storage (all zeros).
    pub const fn new() -> Self {
        Self {
            poses: [Pose::new(0.0, 0.0, 0.0); N],
            weights: [0.0; N],
            counts: [0; N],
        }
    }
}

impl<const N: usize> Default for Particles<N> {
    fn default() -> Self {
        Self::new()
    }
}

/// The filter's parameters (validated by [`MclConfig::new`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MclConfig {
    pub(super) noise: OdometryNoise,
    pub(super) resample_ess_fraction: f32,
    pub(super) recovery_alpha_slow: f32,
    pub(super) recovery_alpha_fast: f32,
    /// Retry threshold, nats (per scored beam for prepared scans); `+∞` is off.
    pub(super) retry_drop_nats: f32,
    /// Retry scale of the last odometry step's spread.
    pub(super) retry_scale: f32,
    /// The quality signal's thresholds.
    pub(super) quality: QualityThresholds,
    /// Expansion and free-space resetting, the settle guard; None: off.
    pub(super) resetting: Option<Resetting>,
    /// Beams the map cannot explain left out of prepared updates: the candidate distance
    /// (metres; `+∞` is off) and the largest share removed.
    pub(super) unexplained_distance_m: f32,
    pub(super) unexplained_max_share: f32,
    /// The adaptive motion noise; None: off.
    pub(super) adaptive_noise: Option<AdaptiveNoise>,
    /// KLD sampling; None: off (the count in use is the initialization's).
    pub(super) kld: Option<Kld>,
    /// How the reported covariance is made from the particles'.
    pub(super) covariance: ReportedCovariance,
}

impl MclConfig {
    /// - `noise`: the odometry motion model's `odom_alpha1..4`;
    /// - `resample_ess_fraction` `f` in `[0, 1]`: resample when the effective sample size falls
    ///   below this fraction of its range `[1, n]` (`ess − 1 < f·(n − 1)`, `n` the particles in
    ///   use; 1 resamples at every update but a perfectly even one, 0 never; 0.5 is the usual
    ///   choice). A set with an impossible particle (weight 0) is resampled whatever `f`;
    /// - `recovery_alpha_slow`, `recovery_alpha_fast` in `[0, 1]` (Thrun Table 8.3, AMCL's
    ///   `recovery_alpha_slow/fast`): the decay rates of the long- and short-term averages of
    ///   the measurement likelihood; `0 ≤ slow < fast`, or both 0 to turn recovery off.
    ///
    /// # Errors
    /// [`MclError::BadConfig`] for a value out of range or NaN.
    pub fn new(
        noise: OdometryNoise,
        resample_ess_fraction: f32,
        recovery_alpha_slow: f32,
        recovery_alpha_fast: f32,
    ) -> Result<Self, MclError> {
        let unit = |a: f32| (0.0..=1.0).contains(&a);
        let recovery_ok = (recovery_alpha_slow == 0.0 && recovery_alpha_fast == 0.0)
            || recovery_alpha_slow < recovery_alpha_fast;
        if !(unit(resample_ess_fraction)
            && unit(recovery_alpha_slow)
            && unit(recovery_alpha_fast)
            && recovery_ok)
        {
            return Err(MclError::BadConfig);
        }
        Ok(Self {
            noise,
            resample_ess_fraction,
            recovery_alpha_slow,
            recovery_alpha_fast,
            retry_drop_nats: f32::INFINITY,
            retry_scale: 1.0,
            quality: QualityThresholds::DEFAULT,
            resetting: None,
            unexplained_distance_m: f32::INFINITY,
            unexplained_max_share: 0.0,
            adaptive_noise: None,
            kld: None,
            covariance: ReportedCovariance::DEFAULT,
        })
    }

    /// How the reported covariance ([`Update::covariance`]) is made from the particles'
    /// ([`ReportedCovariance::DEFAULT`] unless given; [`ReportedCovariance::PARTICLES`] reports
    /// the particles' own).
    ///
    /// # Errors
    /// [`MclError::BadConfig`] when [`ReportedCovariance::validate`] refuses it.
    pub fn with_covariance(self, covariance: ReportedCovariance) -> Result<Self, MclError> {
        if !covariance.validate() {
            return Err(MclError::BadConfig);
        }
        Ok(Self { covariance, ..self })
    }

    /// How the reported covariance is made.
    pub fn covariance(&self) -> &ReportedCovariance {
        &self.covariance
    }

    /// The quality signal's thresholds ([`QualityThresholds::DEFAULT`] unless given).
    ///
    /// # Errors
    /// [`MclError::BadConfig`] when [`QualityThresholds::validate`] refuses them.
    pub fn with_quality(self, thresholds: QualityThresholds) -> Result<Self, MclError> {
        if !thresholds.validate() {
            return Err(MclError::BadConfig);
        }
        Ok(Self {
            quality: thresholds,
            ..self
        })
    }

    /// The quality signal's thresholds.
    pub fn quality(&self) -> &QualityThresholds {
        &self.quality
    }

    /// Turns on expansion and free-space resetting and the settle guard ([`Resetting`]; off by
    /// default, [`Resetting::DEFAULT`] for the documented values); `None` turns them off.
    ///
    /// # Errors
    /// [`MclError::BadConfig`] when [`Resetting::validate`] refuses the values.
    pub fn with_resetting(self, resetting: Option<Resetting>) -> Result<Self, MclError> {
        if resetting.is_some_and(|r| !r.validate()) {
            return Err(MclError::BadConfig);
        }
        Ok(Self { resetting, ..self })
    }

    /// Turns on the removal of beams the map cannot explain from
    /// [`Mcl::update_prepared`](super::Mcl::update_prepared) (off by default; `None` turns it
    /// off): at each update the beams that are unmapped at the predicted estimate (far from
    /// every obstacle and short of the mapped wall behind them,
    /// [`unexplained`](super::unexplained)) are left out of the weighing of every particle. The
    /// other updates ([`Mcl::update_model`](super::Mcl::update_model),
    /// [`Mcl::update_with`](super::Mcl::update_with)) ignore it.
    ///
    /// # Errors
    /// [`MclError::BadConfig`] when [`Unexplained::validate`] refuses the values.
    pub fn with_unexplained(self, unexplained: Option<Unexplained>) -> Result<Self, MclError> {
        let (unexplained_distance_m, unexplained_max_share) = match unexplained {
            Some(u) if !u.validate() => return Err(MclError::BadConfig),
            Some(u) => (u.distance_m, u.max_share),
            None => (f32::INFINITY, 0.0),
        };
        Ok(Self {
            unexplained_distance_m,
            unexplained_max_share,
            ..self
        })
    }

    /// The removal of unexplained beams, when on ([`MclConfig::with_unexplained`]).
    pub fn unexplained(&self) -> Option<Unexplained> {
        (self.unexplained_distance_m < f32::INFINITY).then_some(Unexplained {
            distance_m: self.unexplained_distance_m,
            max_share: self.unexplained_max_share,
        })
    }

    /// Turns on the adaptive motion noise ([`AdaptiveNoise`], [`super::adaptive`]; off by
    /// default, `None` turns it off): the odometry variances are scaled at every update after a
    /// motion so that the scan's correction of the predicted cloud matches the cloud's own
    /// spread ([`Mcl::noise_scale`](super::Mcl::noise_scale) is the scale in use).
    ///
    /// # Errors
    /// [`MclError::BadConfig`] when [`AdaptiveNoise::validate`] refuses the values.
    pub fn with_adaptive_noise(self, adaptive: Option<AdaptiveNoise>) -> Result<Self, MclError> {
        if adaptive.is_some_and(|a| !a.validate()) {
            return Err(MclError::BadConfig);
        }
        Ok(Self {
            adaptive_noise: adaptive,
            ..self
        })
    }

    /// Turns on KLD sampling ([`Kld`], [`super::kld`]; off by default, `None` turns it off):
    /// the number of particles in use is chosen at each resampling (by the weights, not at the
    /// resamplings of a retry, an expansion or a reset), between [`Kld::min`] and
    /// [`Kld::max`] and at most the capacity.
    ///
    /// # Errors
    /// [`MclError::BadConfig`] when [`Kld::validate`] refuses the values.
    pub fn with_kld(self, kld: Option<Kld>) -> Result<Self, MclError> {
        if kld.is_some_and(|k| !k.validate()) {
            return Err(MclError::BadConfig);
        }
        Ok(Self { kld, ..self })
    }

    /// KLD sampling, when on ([`MclConfig::with_kld`]).
    pub fn kld(&self) -> Option<&Kld> {
        self.kld.as_ref()
    }

    /// The adaptive motion noise, when on ([`MclConfig::with_adaptive_noise`]).
    pub fn adaptive_noise(&self) -> Option<&AdaptiveNoise> {
        self.adaptive_noise.as_ref()
    }

    /// The resetting, when on ([`MclConfig::with_resetting`]).
    pub fn resetting(&self) -> Option<&Resetting> {
        self.resetting.as_ref()
    }

    /// Turns on the retry (off by default): a second proposal within an update. When an
    /// update's average likelihood (`ln w_avg`, per scored beam as for recovery, see
    /// [`Mcl`](super::Mcl)) falls more than `drop_nats` below its recent level (an exponential
    /// average of the earlier updates' values, rate [`RETRY_LEVEL_RATE`]), the update
    /// resamples the set by those weights, moves every particle by a further normal step with
    /// `scale` times the last odometry step's spread, and weighs the set again by the same scan
    /// (one more scoring pass, at those updates only). `drop_nats = −∞` retries at every update
    /// (but the first, which sets the level, and those after a zero step or none); `+∞` turns the retry off.
    ///
    /// On the Intel lab log a scale below 1 works best (a local refinement of the cloud around
    /// the particles the scan favoured); a scale above 1 (re-searching a wider region) loses the
    /// robot more often. See `docs/localization.md`.
    ///
    /// # Errors
    /// [`MclError::BadConfig`] for a NaN `drop_nats` or a `scale` not positive or above
    /// [`MAX_RETRY_SCALE`] (`--retry=-inf,1e30` moved every particle to infinity).
    pub fn with_retry(self, drop_nats: f32, scale: f32) -> Result<Self, MclError> {
        if drop_nats.is_nan() || !(scale > 0.0 && scale <= MAX_RETRY_SCALE) {
            return Err(MclError::BadConfig);
        }
        Ok(Self {
            retry_drop_nats: drop_nats,
            retry_scale: scale,
            ..self
        })
    }

    /// True when the retry is on ([`MclConfig::with_retry`]).
    pub fn retry(&self) -> bool {
        self.retry_drop_nats < f32::INFINITY
    }

    /// The motion model.
    pub fn noise(&self) -> &OdometryNoise {
        &self.noise
    }

    /// True when augmented-MCL recovery is on.
    pub fn recovery(&self) -> bool {
        self.recovery_alpha_fast > 0.0
    }
}

/// The largest scale of the odometry step's spread the retry takes ([`MclConfig::with_retry`]):
/// a thousand times the step's own spread is already a global search.
pub const MAX_RETRY_SCALE: f32 = 1_000.0;

/// The rate of the exponential average of `ln w_avg` that the retry compares each
/// update with ([`MclConfig::with_retry`]).
pub const RETRY_LEVEL_RATE: f32 = 0.1;

/// What one measurement update did.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Update {
    /// The estimate from the weighted set, before resampling (its covariance is the
    /// particles').
    pub estimate: Estimate,
    /// The covariance to report with the estimate (m², rad², row-major; `ReportedCovariance`:
    /// the particles' inflated by what they cannot see, and growing while the quality is not
    /// `Tracking`).
    pub covariance: [[f32; 3]; 3],
    /// `ln` of the average measurement likelihood `Σ wᵢ p(z | xᵢ)` (nats; the weights before
    /// the update sum to 1), Table 8.3's `w_avg`.
    pub ln_avg_likelihood: f32,
    /// Table 8.3's `max(0, 1 − w_fast / w_slow)`: the fraction of particles to replace by random
    /// ones at this resampling.
    pub random_fraction: f32,
    /// True when the set was resampled.
    pub resampled: bool,
    /// Random particles drawn from free space at this resampling.
    pub injected: u16,
    /// True when the retry ([`MclConfig::with_retry`]) moved and reweighted the set
    /// at this update (`ln_avg_likelihood` is the first weighing's).
    pub retried: bool,
    /// The quality signal of this update (from the first weighing, before any retry or
    /// expansion).
    pub quality: QualityReport,
    /// True when expansion resetting ([`MclConfig::with_resetting`]) widened the cloud and
    /// reweighted it at this update.
    pub expanded: bool,
    /// True when this update's resampling was a free-space reset (the particles replaced are
    /// counted in `injected`).
    pub reset: bool,
    /// Beams left out of this update as unexplained by the map
    /// ([`MclConfig::with_unexplained`]; 0 when off).
    pub unexplained: u16,
}
