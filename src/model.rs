//! The one trait every range-finder model of the crate implements, so that wrappers such as
//! [`crate::tempered::Tempered`] work over any of them.

use crate::pose::Pose;
use crate::scan::{BeamLayout, Scan, ScanScore};
use core::num::NonZeroUsize;

/// Which beams of a scan to score: every `stride`-th, starting with beam 0.
///
/// AMCL's `laser_max_beams` is a stride in disguise (`stride = ceil(n / max_beams)`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Stride(NonZeroUsize);

impl Stride {
    /// Every beam.
    pub const ONE: Self = Self(NonZeroUsize::MIN);

    /// A stride of `n` beams; `None` for 0.
    pub const fn new(n: usize) -> Option<Self> {
        match NonZeroUsize::new(n) {
            Some(s) => Some(Self(s)),
            None => None,
        }
    }

    /// The stride as a count of beams (≥ 1).
    pub const fn get(self) -> usize {
        self.0.get()
    }
}

/// A measurement model `ln p(z | x, m)` of a whole scan at one pose, in nats.
///
/// The map is part of the model value (a distance-field view, a ray caster), so a model is
/// built once and then scores many poses. Implementations never panic and never return NaN.
pub trait SensorModel<const N: usize> {
    /// Scores beams `0, s, 2s, …` of `scan` (read against `layout`) at `pose`.
    ///
    /// Beams left out by the stride are not scored and not counted in the report.
    fn score_strided(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
        pose: &Pose,
        stride: Stride,
    ) -> ScanScore;

    /// Scores every beam of `scan` at `pose`.
    fn score(&self, layout: &BeamLayout<N>, scan: &Scan<N>, pose: &Pose) -> ScanScore {
        self.score_strided(layout, scan, pose, Stride::ONE)
    }
}
