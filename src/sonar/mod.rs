//! Ultrasonic ring, crosstalk-aware `z_rand` (docs/models.md#sonar, on the beam mixture of Thrun
//! Table 6.1).
//!
//! - [`ring`]: transducer geometry ([`Ring`]);
//! - [`schedule`]: the firing schedule and the overlap weights of lingering echoes ([`Schedule`]);
//! - [`crosstalk`]: `q(Δβ)`, per-beam weights `c_i`, `z_rand,i` and scoring ([`SonarModel`]);
//! - [`learn`]: EM of the mixture weights grouped by co-fired count, and the fit of `q` and
//!   `z_rand,0` to the per-group `z_rand(k)`;
//! - `driver` (feature `hal`): an embedded-hal 1.0 I²C driver for SRF08-class rangers.

pub mod crosstalk;
#[cfg(feature = "hal")]
pub mod driver;
pub mod learn;
pub mod ring;
pub mod schedule;

pub use crosstalk::{
    crosstalk_probability, rescale_weights, CrosstalkError, CrosstalkModel, SonarModel,
};
pub use learn::{
    fit_constant_q, fit_gaussian_q, FitError, GroupRate, GroupedWeightEm, NeighbourRate,
    PassReport, QFit,
};
pub use ring::{Ring, RingError, Transducer};
pub use schedule::{Schedule, ScheduleError, SPEED_OF_SOUND_M_PER_S};
