//! Honest confidence: tempering a scan log-likelihood, and normalizing particle weights without
//! underflow (docs/models.md#tempering; Thrun §6.3.4's p^{1/κ}).
//!
//! The product over K beams treats correlated beams as independent and overstates every
//! log-odds by about `K/K_eff`. [`Tempered`] divides the log-likelihood by `κ ≥ 1` — one scalar,
//! no data thrown away, the peak stays where the full scan puts it. It also offers a `stride`
//! (subsampling, AMCL's `laser_max_beams`), which widens the posterior too but moves its peak;
//! prefer κ and use the stride only when the cost of the beams is the problem.
//!
//! [`normalize_log_weights`] turns the log-likelihoods of a set of hypotheses into normalized
//! weights in place, with a max-shifted log-sum-exp: never NaN, never all zero.

use crate::field::{LikelihoodField, PreparedScan};
use crate::math;
use crate::model::{SensorModel, Stride};
use crate::pose::Pose;
use crate::scan::{BeamLayout, Scan, ScanScore};

/// Errors building a [`Tempered`] model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum TemperError {
    /// κ is NaN or infinite.
    NonFiniteKappa,
    /// κ ≤ 0.
    NonPositiveKappa,
    /// A stride of 0 beams.
    ZeroStride,
}

impl core::fmt::Display for TemperError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::NonFiniteKappa => "kappa is not finite",
            Self::NonPositiveKappa => "kappa must be > 0",
            Self::ZeroStride => "stride must be at least 1",
        })
    }
}

impl core::error::Error for TemperError {}

/// A model told to be less sure of itself: `ln q_κ = (1/κ)·Σ_k ln p(z_k | x, m)` over every
/// `stride`-th beam.
#[derive(Clone, Copy, Debug)]
pub struct Tempered<M> {
    inner: M,
    kappa: f32,
    inv_kappa: f32,
    stride: Stride,
}

impl<M> Tempered<M> {
    /// Wraps `inner` with tempering exponent `1/kappa` and a beam stride.
    ///
    /// `kappa = 1, stride = 1` is the raw product. Values of κ below 1 are accepted (they
    /// sharpen the posterior) but are rarely what a user wants.
    ///
    /// # Errors
    /// [`TemperError::NonFiniteKappa`], [`TemperError::NonPositiveKappa`],
    /// [`TemperError::ZeroStride`].
    pub fn new(inner: M, kappa: f32, stride: usize) -> Result<Self, TemperError> {
        if !kappa.is_finite() {
            return Err(TemperError::NonFiniteKappa);
        }
        if kappa <= 0.0 {
            return Err(TemperError::NonPositiveKappa);
        }
        let stride = Stride::new(stride).ok_or(TemperError::ZeroStride)?;
        Ok(Self {
            inner,
            kappa,
            inv_kappa: 1.0 / kappa,
            stride,
        })
    }

    /// κ.
    pub fn kappa(&self) -> f32 {
        self.kappa
    }

    /// The beam stride.
    pub fn stride(&self) -> usize {
        self.stride.get()
    }

    /// The wrapped model.
    pub fn inner(&self) -> &M {
        &self.inner
    }

    /// Gives the wrapped model back.
    pub fn into_inner(self) -> M {
        self.inner
    }
}

impl<M: SensorModel<N>, const N: usize> SensorModel<N> for Tempered<M> {
    /// The inner model's score over every `stride`-th beam (the wrapper's stride times the
    /// caller's), divided by κ. The counts in the report are the inner model's.
    fn score_strided(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
        pose: &Pose,
        stride: Stride,
    ) -> ScanScore {
        let combined =
            Stride::new(self.stride.get().saturating_mul(stride.get())).unwrap_or(stride);
        let mut s = self.inner.score_strided(layout, scan, pose, combined);
        s.log_likelihood *= self.inv_kappa;
        s
    }
}

impl<'a> Tempered<LikelihoodField<'a>> {
    /// Prepares `scan` (read against `layout`) for scoring at many poses with the tempered
    /// likelihood field ([`TemperedScan::score`]): the wrapper's stride is applied once here
    /// ([`LikelihoodField::prepare_strided`]) and `1/κ` at every score. The result is
    /// [`SensorModel::score`] of this wrapper, up to the rare beams whose endpoint the prepared
    /// path puts in the neighbouring cell (see [`PreparedScan`]).
    pub fn prepare<const N: usize>(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
    ) -> TemperedScan<'_, N> {
        TemperedScan {
            prepared: self.inner.prepare_strided(layout, scan, self.stride),
            inv_kappa: self.inv_kappa,
        }
    }
}

/// A scan prepared for the tempered likelihood field: a [`PreparedScan`] over the wrapper's
/// stride, and `1/κ`. Built by [`Tempered::prepare`].
#[derive(Clone, Debug)]
pub struct TemperedScan<'f, const N: usize> {
    prepared: PreparedScan<'f, N>,
    inv_kappa: f32,
}

impl<const N: usize> TemperedScan<'_, N> {
    /// Tempered log-likelihood (nats, divided by κ) of the prepared scan with the robot at
    /// `pose`; the counts are the prepared scan's (beams kept by the stride only).
    pub fn score(&self, pose: &Pose) -> ScanScore {
        let mut s = self.prepared.score(pose);
        s.log_likelihood *= self.inv_kappa;
        s
    }

    /// The untempered prepared scan (its scores are not divided by κ).
    pub fn prepared(&self) -> &PreparedScan<'_, N> {
        &self.prepared
    }

    /// The same tempered scan over the beams `j` for which `keep(j)` is true
    /// ([`PreparedScan::retain`]).
    pub fn retain<K: FnMut(usize) -> bool>(&self, keep: K) -> Self {
        Self {
            prepared: self.prepared.retain(keep),
            inv_kappa: self.inv_kappa,
        }
    }
}

/// Errors normalizing log-weights. The caller's slice is left unchanged on every error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum NormalizeError {
    /// The slice is empty.
    Empty,
    /// Entry `i` is NaN.
    NaN(usize),
    /// Entry `i` is `+∞`: one hypothesis claims infinite likelihood.
    PositiveInfinity(usize),
    /// Every entry is `−∞`: no hypothesis is possible, so there is nothing to normalize.
    AllImpossible,
}

impl core::fmt::Display for NormalizeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Empty => f.write_str("no weights to normalize"),
            Self::NaN(i) => write!(f, "log-weight {i} is NaN"),
            Self::PositiveInfinity(i) => write!(f, "log-weight {i} is +inf"),
            Self::AllImpossible => f.write_str("every log-weight is -inf"),
        }
    }
}

impl core::error::Error for NormalizeError {}

/// What [`normalize_log_weights`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Normalized {
    /// `ln Σ_j e^{l_j}` of the input: the log of the total (unnormalized) weight, the
    /// log-evidence of the set.
    pub log_total: f32,
    /// Index of the largest input (the first one on ties).
    pub best: usize,
    /// Effective sample size `1 / Σ w_i²`, in `[1, n]`.
    pub ess: f32,
}

/// Replaces the log-weights `l_i` in `weights` by normalized linear weights
/// `w_i = e^{l_i − max l − ln Σ_j e^{l_j − max l}}`, which sum to 1.
///
/// `−∞` entries (impossible hypotheses) get weight exactly 0. Finite entries never underflow
/// all together: the largest one gets at least `1/n`. Any finite input magnitude works
/// (log-likelihoods of −1e30 included): only differences from the maximum are exponentiated.
///
/// # Errors
/// [`NormalizeError`] for an empty slice, a NaN or `+∞` entry, or all entries `−∞`; the slice is
/// then left unchanged.
pub fn normalize_log_weights(weights: &mut [f32]) -> Result<Normalized, NormalizeError> {
    let mut max = f32::NEG_INFINITY;
    let mut best = 0usize;
    if weights.is_empty() {
        return Err(NormalizeError::Empty);
    }
    for (i, &l) in weights.iter().enumerate() {
        if l.is_nan() {
            return Err(NormalizeError::NaN(i));
        }
        if l == f32::INFINITY {
            return Err(NormalizeError::PositiveInfinity(i));
        }
        if l > max {
            max = l;
            best = i;
        }
    }
    if max == f32::NEG_INFINITY {
        return Err(NormalizeError::AllImpossible);
    }
    // Σ e^{l − max} ≥ 1 (the maximum contributes exactly 1), ≤ n. Both sums are compensated
    // (Kahan), so their error does not grow with n: thousands of particles keep full precision.
    let mut sum = Kahan::default();
    for w in weights.iter_mut() {
        *w = if *w == f32::NEG_INFINITY {
            0.0
        } else {
            math::exp(*w - max)
        };
        sum.add(*w);
    }
    let inv = 1.0 / sum.total;
    let mut sum_sq = Kahan::default();
    for w in weights.iter_mut() {
        *w *= inv;
        sum_sq.add(*w * *w);
    }
    Ok(Normalized {
        log_total: max + math::ln(sum.total),
        best,
        ess: 1.0 / sum_sq.total,
    })
}

/// Kahan–Babuška compensated summation.
#[derive(Default)]
struct Kahan {
    total: f32,
    carry: f32,
}

impl Kahan {
    #[inline]
    fn add(&mut self, x: f32) {
        let y = x - self.carry;
        let t = self.total + y;
        self.carry = (t - self.total) - y;
        self.total = t;
    }
}

/// Effective sample size `1 / Σ w_i²` of weights that already sum to 1; 0 for an empty slice
/// or all-zero weights.
pub fn effective_sample_size(weights: &[f32]) -> f32 {
    let s: f32 = weights.iter().map(|w| w * w).sum();
    if s > 0.0 {
        1.0 / s
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_and_peaked() {
        let mut w = [-1e30f32; 4];
        let n = normalize_log_weights(&mut w).unwrap();
        assert_eq!(w, [0.25; 4]);
        assert!((n.ess - 4.0).abs() < 1e-6);
        let mut w = [0.0, -1000.0, f32::NEG_INFINITY];
        let n = normalize_log_weights(&mut w).unwrap();
        assert_eq!(w, [1.0, 0.0, 0.0]);
        assert_eq!(n.best, 0);
    }

    #[test]
    fn errors_leave_the_slice_alone() {
        let mut w = [1.0, f32::NAN];
        assert_eq!(normalize_log_weights(&mut w), Err(NormalizeError::NaN(1)));
        assert_eq!(w[0], 1.0);
        let mut w = [f32::NEG_INFINITY; 3];
        assert_eq!(
            normalize_log_weights(&mut w),
            Err(NormalizeError::AllImpossible)
        );
        assert_eq!(normalize_log_weights(&mut []), Err(NormalizeError::Empty));
        let mut w = [0.0, f32::INFINITY];
        assert_eq!(
            normalize_log_weights(&mut w),
            Err(NormalizeError::PositiveInfinity(1))
        );
    }

    #[test]
    fn tempering_validation() {
        assert_eq!(
            Tempered::new((), f32::NAN, 1).err(),
            Some(TemperError::NonFiniteKappa)
        );
        assert_eq!(
            Tempered::new((), 0.0, 1).err(),
            Some(TemperError::NonPositiveKappa)
        );
        assert_eq!(
            Tempered::new((), 2.0, 0).err(),
            Some(TemperError::ZeroStride)
        );
        assert!(Tempered::new((), 2.0, 3).is_ok());
    }
}
