//! Crosstalk-aware per-beam mixture weights and sonar scan scores (docs/models.md#sonar on the
//! beam mixture of Thrun Table 6.1, docs/models.md#mixture).
//!
//! # Pairwise crosstalk probability `q(Δβ)`
//! The probability that one co-fired transducer `j` corrupts transducer `i`'s reading (its echo
//! is timed first by `i`), as a function of their unsigned angular separation `Δβ ∈ [0, π]`:
//! - [`CrosstalkModel::Constant`]: `q(Δβ) = q` for every pair;
//! - [`CrosstalkModel::Gaussian`]: `q(Δβ) = q0·exp(−Δβ²/(2w²))`, a lobe of width `w` (radians)
//!   around the transducer's own axis: close neighbours hear each other, opposite ones rarely.
//!
//! # Per-beam weights
//! With `w_ij` the schedule's overlap weights ([`crate::sonar::Schedule::overlap_weight`]):
//!
//! ```text
//! c_i       = 1 − Π_{j ≠ i} (1 − w_ij·q(Δβ_ij))
//! z_rand,i  = z_rand,0 + (1 − z_rand,0)·c_i
//! z_x,i     = z_x,0 · (1 − z_rand,i)/(1 − z_rand,0) = z_x,0·(1 − c_i)   for x ∈ {hit, short, max}
//! ```
//!
//! The second form of the rescaling needs no division, so `z_rand,0 = 1` is harmless; the four
//! weights of every beam sum to 1 (up to f32 rounding, far inside
//! [`crate::intrinsics::WEIGHT_SUM_TOLERANCE`]). A transducer fired alone (all `w_ij = 0`) has
//! `c_i = 0` and gets the base weights back exactly.
//!
//! [`SonarModel`] precomputes one [`BeamModel`] per transducer when it is built (a handful of
//! logarithms per beam, once per schedule); scoring is then the beam model's hot path with the
//! beam's own weights, free of validation.

use crate::beam::BeamModel;
use crate::intrinsics::{BeamIntrinsics, IntrinsicsError};
use crate::math;
use crate::scan::{Scan, ScanScore};
use crate::sonar::ring::Ring;
use crate::sonar::schedule::Schedule;
use heapless::Vec;

/// Why a crosstalk model or a [`SonarModel`] was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum CrosstalkError {
    /// A probability (`q`, `q0`) not finite or outside `[0, 1]`.
    BadProbability,
    /// A lobe width not finite or ≤ 0.
    BadWidth,
    /// The schedule was built for a ring of another size.
    RingMismatch {
        /// Transducers in the ring.
        ring: usize,
        /// Transducers the schedule was built for.
        schedule: usize,
    },
    /// A per-beam parameter set was rejected (cannot happen for valid inputs; passed through).
    Intrinsics(IntrinsicsError),
}

impl core::fmt::Display for CrosstalkError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BadProbability => f.write_str("crosstalk probability must be in [0, 1]"),
            Self::BadWidth => f.write_str("crosstalk lobe width must be finite and > 0"),
            Self::RingMismatch { ring, schedule } => {
                write!(f, "schedule is for {schedule} transducers, ring has {ring}")
            }
            Self::Intrinsics(e) => write!(f, "per-beam intrinsics: {e}"),
        }
    }
}

impl core::error::Error for CrosstalkError {}

/// Pairwise crosstalk probability `q(Δβ)`; see the module docs. Build with
/// [`CrosstalkModel::constant`] or [`CrosstalkModel::gaussian`] (validated).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum CrosstalkModel {
    /// `q(Δβ) = q`.
    Constant {
        /// Probability, in `[0, 1]`.
        q: f32,
    },
    /// `q(Δβ) = q0·exp(−Δβ²/(2·width²))`.
    Gaussian {
        /// Probability at zero separation, in `[0, 1]`.
        q0: f32,
        /// Lobe width `w`, radians, > 0.
        width_rad: f32,
    },
}

fn check_probability(p: f32) -> Result<(), CrosstalkError> {
    if p.is_finite() && (0.0..=1.0).contains(&p) {
        Ok(())
    } else {
        Err(CrosstalkError::BadProbability)
    }
}

impl CrosstalkModel {
    /// A constant pairwise probability `q ∈ [0, 1]`.
    ///
    /// # Errors
    /// [`CrosstalkError::BadProbability`].
    pub fn constant(q: f32) -> Result<Self, CrosstalkError> {
        check_probability(q)?;
        Ok(Self::Constant { q })
    }

    /// A Gaussian lobe `q0·exp(−Δβ²/(2w²))`, `q0 ∈ [0, 1]`, `w > 0` radians.
    ///
    /// # Errors
    /// [`CrosstalkError::BadProbability`], [`CrosstalkError::BadWidth`].
    pub fn gaussian(q0: f32, width_rad: f32) -> Result<Self, CrosstalkError> {
        check_probability(q0)?;
        if !(width_rad.is_finite() && width_rad > 0.0) {
            return Err(CrosstalkError::BadWidth);
        }
        Ok(Self::Gaussian { q0, width_rad })
    }

    /// `q(Δβ)` for an unsigned separation in radians; always in `[0, 1]`. Costs one `exp` for the
    /// Gaussian form: call it when precomputing, not per scan.
    pub fn q(&self, separation_rad: f32) -> f32 {
        match *self {
            Self::Constant { q } => q,
            Self::Gaussian { q0, width_rad } => {
                let u = separation_rad / width_rad;
                (q0 * math::exp(-0.5 * u * u)).clamp(0.0, 1.0)
            }
        }
    }
}

/// `c_i = 1 − Π_j (1 − w_ij·q(Δβ_ij))` for transducer `i`, in `[0, 1]`.
pub fn crosstalk_probability<const R: usize, const M: usize, const G: usize>(
    ring: &Ring<R>,
    schedule: &Schedule<M, G>,
    model: &CrosstalkModel,
    i: usize,
) -> f32 {
    let mut clean = 1.0f32;
    for j in 0..ring.len() {
        let w = schedule.overlap_weight(i, j);
        if w > 0.0 {
            clean *= 1.0 - w * model.q(ring.separation_rad(i, j));
        }
    }
    (1.0 - clean).clamp(0.0, 1.0)
}

/// The weights `[z_hit, z_short, z_max, z_rand]` of a beam with crosstalk probability `c` (in
/// `[0, 1]`; clamped) from the base weights `base` (on the simplex). See the module docs.
pub fn rescale_weights(base: [f32; 4], c: f32) -> [f32; 4] {
    let c = c.clamp(0.0, 1.0);
    let keep = 1.0 - c;
    let [h, s, m, r] = base;
    [h * keep, s * keep, m * keep, r + (1.0 - r) * c]
}

/// A sonar ring ready to score: one [`BeamModel`] per transducer with its crosstalk-aware
/// weights, for at most `M` transducers.
#[derive(Clone, Debug)]
pub struct SonarModel<const M: usize> {
    models: Vec<BeamModel, M>,
    crosstalk: Vec<f32, M>,
}

impl<const M: usize> SonarModel<M> {
    /// Precomputes every beam's weights and model. `base` holds the base weights (`z_rand,0`),
    /// σ, λ and the max range shared by all transducers.
    ///
    /// # Errors
    /// [`CrosstalkError::RingMismatch`] when the schedule was built for another ring size;
    /// [`CrosstalkError::Intrinsics`] is passed through from [`BeamIntrinsics::new`].
    pub fn new<const G: usize>(
        ring: &Ring<M>,
        schedule: &Schedule<M, G>,
        base: &BeamIntrinsics,
        model: &CrosstalkModel,
    ) -> Result<Self, CrosstalkError> {
        if schedule.ring_len() != ring.len() {
            return Err(CrosstalkError::RingMismatch {
                ring: ring.len(),
                schedule: schedule.ring_len(),
            });
        }
        let mut models = Vec::new();
        let mut crosstalk = Vec::new();
        for i in 0..ring.len() {
            let c = crosstalk_probability(ring, schedule, model, i);
            let [h, s, m, r] = rescale_weights(base.weights(), c);
            let intr = BeamIntrinsics::new(
                h,
                s,
                m,
                r,
                base.sigma_hit_m(),
                base.lambda_short_per_m(),
                base.max_range_m(),
            )
            .map_err(CrosstalkError::Intrinsics)?;
            // Cannot fail: i < ring.len() ≤ M.
            let _ = models.push(BeamModel::new(intr));
            let _ = crosstalk.push(c);
        }
        Ok(Self { models, crosstalk })
    }

    /// The model of transducer `i` (its intrinsics carry the per-beam weights).
    pub fn beam_model(&self, i: usize) -> Option<&BeamModel> {
        self.models.get(i)
    }

    /// The crosstalk probability `c_i` of every transducer, in index order.
    pub fn crosstalk(&self) -> &[f32] {
        &self.crosstalk
    }

    /// Number of transducers.
    pub fn len(&self) -> usize {
        self.models.len()
    }

    /// Always false: a ring has at least one transducer.
    pub fn is_empty(&self) -> bool {
        self.models.is_empty()
    }

    /// Scores a sonar scan: reading `k` of `scan` against ray-cast range `z_star_m[k]` under
    /// transducer `k`'s weights. Readings without a ray-cast partner or past the ring are counted
    /// as unpaired; NaN and negative readings as invalid (see [`crate::scan`]).
    pub fn scan_log_likelihood<const N: usize>(
        &self,
        scan: &Scan<N>,
        z_star_m: &[f32],
    ) -> ScanScore {
        let mut score = ScanScore::default();
        let ranges = scan.ranges_m();
        let mut sum = 0.0f32;
        let mut paired = 0usize;
        for ((&z, &zs), m) in ranges.iter().zip(z_star_m).zip(&self.models) {
            paired += 1;
            match m.beam_log_likelihood(z, zs) {
                Some(l) => {
                    sum += l;
                    score.scored = score.scored.saturating_add(1);
                }
                None => score.invalid = score.invalid.saturating_add(1),
            }
        }
        score.unpaired = u16::try_from(ranges.len().saturating_sub(paired)).unwrap_or(u16::MAX);
        score.log_likelihood = sum;
        score
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alone_gives_base_weights_exactly() {
        let base = [0.7, 0.1, 0.15, 0.05];
        assert_eq!(rescale_weights(base, 0.0), base);
        let w = rescale_weights(base, 0.3);
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        assert!((w[3] - (0.05 + 0.95 * 0.3)).abs() < 1e-6);
        assert!((w[0] - 0.7 * 0.7).abs() < 1e-6);
    }

    #[test]
    fn model_validation() {
        assert!(CrosstalkModel::constant(1.5).is_err());
        assert!(CrosstalkModel::constant(f32::NAN).is_err());
        assert_eq!(
            CrosstalkModel::gaussian(0.5, 0.0),
            Err(CrosstalkError::BadWidth)
        );
        let g = CrosstalkModel::gaussian(0.4, 0.5).unwrap();
        assert!((g.q(0.0) - 0.4).abs() < 1e-7);
        assert!((g.q(0.5) - 0.4 * (-0.5f32).exp()).abs() < 1e-6);
    }

    #[test]
    fn pair_product_by_hand() {
        let deg = core::f32::consts::PI / 180.0;
        let ring = Ring::<4>::uniform(4, 0.0, 90.0 * deg, 0.2, 0.3, 3.43).unwrap();
        // Everything at once: three neighbours at 90°, 180°, 90°.
        let s = Schedule::<4, 4>::new(&ring, &[&[0, 1, 2, 3]], 0.02, 343.0).unwrap();
        let q = CrosstalkModel::constant(0.2).unwrap();
        let c = crosstalk_probability(&ring, &s, &q, 0);
        assert!((c - (1.0 - 0.8f32.powi(3))).abs() < 1e-6);
        let g = CrosstalkModel::gaussian(0.5, 1.0).unwrap();
        let q90 = 0.5 * (-0.5 * (90.0 * deg).powi(2)).exp();
        let q180 = 0.5 * (-0.5 * (180.0 * deg).powi(2)).exp();
        let want = 1.0 - (1.0 - q90) * (1.0 - q90) * (1.0 - q180);
        assert!((crosstalk_probability(&ring, &s, &g, 0) - want).abs() < 1e-6);
    }
}
