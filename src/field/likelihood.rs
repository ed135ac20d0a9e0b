//! The likelihood field model: Thrun's `likelihood_field_range_finder_model`, Table 6.3
//! (docs/models.md#field), scored over a [`FieldView`] in flash.
//!
//! Each reading `z_k < z_max` is projected to the point it claims to have hit,
//!
//! ```text
//! x_z = x + x_s·cosθ − y_s·sinθ + z_k·cos(θ + θ_s + θ_k)
//! y_z = y + y_s·cosθ + x_s·sinθ + z_k·sin(θ + θ_s + θ_k)
//! ```
//!
//! (`(x_s, y_s, θ_s)` the [`SensorMount`](crate::SensorMount), `θ_k` the beam's bearing), `d`
//! is the distance from there to the nearest occupied cell read from the blob, and the beam adds
//!
//! ```text
//! ln( z_hit · N(d; 0, σ_hit²) + z_rand / z_max )
//! ```
//!
//! to the scan's log-likelihood (nats). Max-range readings (`z ≥ z_max`, `+∞`) are skipped
//! outright, NaN and negative ones are skipped too; both are counted in [`ScanScore`]. The score
//! is smooth in the pose but is not a normalized density over `z`.
//!
//! # Cost
//! The per-beam term depends on `d` alone, and `d` takes one of the 256 quantized values of the
//! blob, so the terms are tabulated once per parameter set ([`LikelihoodField::new`]: 256
//! `exp`/`ln`). Scoring costs one `sin_cos` per pose; per beam, a rotation of the layout's
//! precomputed unit vector, a projection, one byte read and one table read, with no branch that
//! depends on the data (the reading's validity is a select) and no panic path.
//!
//! To score one scan at many poses (a particle filter's update, a grid search), prepare it
//! once with [`LikelihoodField::prepare`] and score the [`PreparedScan`](super::PreparedScan):
//! max-range readings are dropped once, the mount is applied once, and a beam costs a
//! fixed-point rotation, a byte read and a table read (about 21 instructions on a Cortex-M4F
//! against about 99 for [`LikelihoodField::score`]; `cargo xtask insns`). Same scores, except
//! for endpoints within rounding of a cell edge (see [`super::prepared`]).
//!
//! # Quantization
//! `d` is the stored code times `d_max/255` (error ≤ half a step from the cell's exact distance;
//! the cell itself is the rasterization error of the map). Off the map, the distance to the
//! map's rectangle is added in code steps, rounded; the sum is clamped at `d_max` (code 255),
//! like AMCL's `laser_likelihood_max_dist`.

use super::blob::CODE_MAX;
use super::view::FieldView;
use crate::math;
use crate::model::{SensorModel, Stride};
use crate::pose::Pose;
use crate::scan::{BeamLayout, Scan, ScanScore};

/// Number of entries of the per-beam term table: one per distance code.
pub const LIKELIHOOD_TABLE_LEN: usize = CODE_MAX as usize + 1;

/// Which likelihood-field parameter an error is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum LikelihoodParam {
    /// `z_hit` (AMCL `laser_z_hit`).
    ZHit,
    /// `z_rand` (AMCL `laser_z_rand`).
    ZRand,
    /// `sigma_hit_m` (AMCL `laser_sigma_hit`).
    SigmaHit,
    /// `max_range_m` (AMCL `laser_max_range`).
    MaxRange,
}

/// Why a set of likelihood-field parameters was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum LikelihoodError {
    /// A parameter is NaN or infinite.
    NonFinite(LikelihoodParam),
    /// A weight is negative.
    NegativeWeight(LikelihoodParam),
    /// `z_hit + z_rand > 1` (beyond [`crate::intrinsics::WEIGHT_SUM_TOLERANCE`]).
    WeightsAboveOne,
    /// `z_hit = z_rand = 0`: every beam would score `−∞`.
    WeightsAllZero,
    /// `sigma_hit_m ≤ 0`.
    NonPositiveSigma,
    /// `max_range_m ≤ 0`.
    NonPositiveMaxRange,
}

impl core::fmt::Display for LikelihoodError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let name = |p: &LikelihoodParam| match p {
            LikelihoodParam::ZHit => "z_hit",
            LikelihoodParam::ZRand => "z_rand",
            LikelihoodParam::SigmaHit => "sigma_hit",
            LikelihoodParam::MaxRange => "max_range",
        };
        match self {
            Self::NonFinite(p) => write!(f, "{} is not finite", name(p)),
            Self::NegativeWeight(p) => write!(f, "{} is negative", name(p)),
            Self::WeightsAboveOne => f.write_str("z_hit + z_rand exceeds 1"),
            Self::WeightsAllZero => f.write_str("z_hit and z_rand are both zero"),
            Self::NonPositiveSigma => f.write_str("sigma_hit must be > 0"),
            Self::NonPositiveMaxRange => f.write_str("max_range must be > 0"),
        }
    }
}

impl core::error::Error for LikelihoodError {}

/// The likelihood field's parameters (Table 6.3), validated.
///
/// `z_max`'s weight of Table 6.3 never enters the score (max-range readings are skipped), so
/// only `z_hit` and `z_rand` are given; they need not sum to 1 (AMCL's defaults are 0.95 and
/// 0.05), but may not exceed it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LikelihoodParams {
    z_hit: f32,
    z_rand: f32,
    sigma_hit_m: f32,
    max_range_m: f32,
}

impl LikelihoodParams {
    /// Checks and stores the parameters: weights (unitless), σ_hit and the range limit (metres).
    ///
    /// # Errors
    /// [`LikelihoodError`]: non-finite values, negative weights, `z_hit + z_rand > 1`, both
    /// weights zero, `sigma_hit_m ≤ 0`, `max_range_m ≤ 0`.
    pub fn new(
        z_hit: f32,
        z_rand: f32,
        sigma_hit_m: f32,
        max_range_m: f32,
    ) -> Result<Self, LikelihoodError> {
        let checks = [
            (z_hit, LikelihoodParam::ZHit),
            (z_rand, LikelihoodParam::ZRand),
            (sigma_hit_m, LikelihoodParam::SigmaHit),
            (max_range_m, LikelihoodParam::MaxRange),
        ];
        for (v, p) in checks {
            if !v.is_finite() {
                return Err(LikelihoodError::NonFinite(p));
            }
        }
        if z_hit < 0.0 {
            return Err(LikelihoodError::NegativeWeight(LikelihoodParam::ZHit));
        }
        if z_rand < 0.0 {
            return Err(LikelihoodError::NegativeWeight(LikelihoodParam::ZRand));
        }
        if z_hit + z_rand > 1.0 + crate::intrinsics::WEIGHT_SUM_TOLERANCE {
            return Err(LikelihoodError::WeightsAboveOne);
        }
        if z_hit == 0.0 && z_rand == 0.0 {
            return Err(LikelihoodError::WeightsAllZero);
        }
        if sigma_hit_m <= 0.0 {
            return Err(LikelihoodError::NonPositiveSigma);
        }
        if max_range_m <= 0.0 {
            return Err(LikelihoodError::NonPositiveMaxRange);
        }
        Ok(Self {
            z_hit,
            z_rand,
            sigma_hit_m,
            max_range_m,
        })
    }

    /// AMCL's defaults (`laser_z_hit` 0.95, `laser_z_rand` 0.05, `laser_sigma_hit` 0.2 m) with
    /// the given range limit.
    ///
    /// # Errors
    /// [`LikelihoodError::NonFinite`] or [`LikelihoodError::NonPositiveMaxRange`].
    pub fn amcl_defaults(max_range_m: f32) -> Result<Self, LikelihoodError> {
        Self::new(0.95, 0.05, 0.2, max_range_m)
    }

    /// Weight of the hit Gaussian.
    pub fn z_hit(&self) -> f32 {
        self.z_hit
    }

    /// Weight of the uniform random reading.
    pub fn z_rand(&self) -> f32 {
        self.z_rand
    }

    /// Standard deviation of the hit Gaussian, metres.
    pub fn sigma_hit_m(&self) -> f32 {
        self.sigma_hit_m
    }

    /// The sensor range limit `z_max`, metres: readings at or beyond it are skipped, and the
    /// uniform density is `1/z_max`.
    pub fn max_range_m(&self) -> f32 {
        self.max_range_m
    }

    /// One beam's term `ln(z_hit·N(d; 0, σ²) + z_rand/z_max)` at distance `d` (metres), computed
    /// directly (log-sum-exp, never `−∞` for valid parameters). The table is built from it.
    pub fn beam_log_likelihood(&self, distance_m: f32) -> f32 {
        let u = distance_m / self.sigma_hit_m;
        let l_hit = if self.z_hit > 0.0 {
            math::ln(self.z_hit) - math::ln(self.sigma_hit_m) - math::LN_SQRT_2PI - 0.5 * u * u
        } else {
            f32::NEG_INFINITY
        };
        let l_rand = if self.z_rand > 0.0 {
            math::ln(self.z_rand) - math::ln(self.max_range_m)
        } else {
            f32::NEG_INFINITY
        };
        math::log_add_exp(l_hit, l_rand)
    }
}

/// The likelihood field over one blob with one parameter set: the term table, ready to score.
///
/// Build it once per (blob, parameters) pair; it is `Copy`-free but small (1 KiB table plus the
/// view) and holds no mutable state, so one instance serves every pose hypothesis.
#[derive(Clone, Debug)]
pub struct LikelihoodField<'a> {
    view: FieldView<'a>,
    params: LikelihoodParams,
    table: [f32; LIKELIHOOD_TABLE_LEN],
}

impl<'a> LikelihoodField<'a> {
    /// Tabulates the per-beam term over the blob's 256 quantized distances
    /// (`table[c] = term(c · d_max/255)`). Costs 256 `exp` and `ln`; do it once.
    pub fn new(view: FieldView<'a>, params: LikelihoodParams) -> Self {
        let step = view.step_m();
        let table = core::array::from_fn(|c| params.beam_log_likelihood(c as f32 * step));
        Self {
            view,
            params,
            table,
        }
    }

    /// The blob this field reads.
    pub fn view(&self) -> &FieldView<'a> {
        &self.view
    }

    /// The parameters the table was built from.
    pub fn params(&self) -> &LikelihoodParams {
        &self.params
    }

    /// The per-beam term for each distance code, nats.
    pub fn table(&self) -> &[f32; LIKELIHOOD_TABLE_LEN] {
        &self.table
    }

    /// Log-likelihood of `scan` (read against `layout`) with the robot at `pose`.
    ///
    /// Readings are paired with the layout's beams in order; readings past the last beam are
    /// counted in [`ScanScore::unpaired`]. Max-range and invalid readings are skipped and
    /// counted. `log_likelihood` is finite for every finite pose, and NaN for a pose with a NaN
    /// or infinite coordinate (the counts are still the scan's).
    pub fn score<const N: usize>(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
        pose: &Pose,
    ) -> ScanScore {
        self.score_with(layout, scan, pose, |_, _| {})
    }

    /// As [`LikelihoodField::score`], calling `each(beam_index, distance_m)` for every scored
    /// beam in bearing order, with the quantized endpoint distance (metres) that was scored:
    /// the residuals the tempering and diagnostics work needs.
    pub fn score_with<const N: usize, F: FnMut(usize, f32)>(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
        pose: &Pose,
        each: F,
    ) -> ScanScore {
        self.score_strided_with(layout, scan, pose, Stride::ONE, each)
    }

    /// As [`LikelihoodField::score_with`], over beams `0, s, 2s, …` only (`s = stride`). Beams
    /// left out are neither scored, counted nor passed to `each`; `unpaired` still counts every
    /// reading past the layout's end.
    pub fn score_strided_with<const N: usize, F: FnMut(usize, f32)>(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
        pose: &Pose,
        stride: Stride,
        mut each: F,
    ) -> ScanScore {
        let sensor = layout.mount().sensor_pose(pose);
        let (sin_t, cos_t) = math::sin_cos(sensor.theta_rad);
        let inv = self.view.inv_cell_size();
        // Everything per pose is moved into grid units, so a beam costs a rotation and a
        // projection.
        let (ax, ay) = self.view.to_grid(sensor.x_m, sensor.y_m);
        let (c, s) = (cos_t * inv, sin_t * inv);
        let max_r = self.params.max_range_m;
        let step = self.view.step_m();
        let mut sum = 0.0f32;
        let (mut scored, mut max_range) = (0u32, 0u32);
        let ranges = scan.ranges_m();
        let mut paired = 0u32;
        for (k, (beam, &r)) in layout
            .beams()
            .iter()
            .zip(ranges)
            .enumerate()
            .step_by(stride.get())
        {
            let ux = c * beam.cos - s * beam.sin;
            let uy = s * beam.cos + c * beam.sin;
            let idx = self.view.table_index(ax + r * ux, ay + r * uy);
            // An index from `table_index` is ≤ 255, so this `get` never fails; the compiler
            // removes the check.
            let term = self.table.get(usize::from(idx)).copied().unwrap_or(0.0);
            // NaN fails both comparisons: neither valid nor max-range, hence invalid.
            let valid = (r >= 0.0) & (r < max_r);
            let is_max = r >= max_r;
            sum += if valid { term } else { 0.0 };
            scored += u32::from(valid);
            max_range += u32::from(is_max);
            paired += 1;
            if valid {
                each(k, f32::from(idx) * step);
            }
        }
        let invalid = paired - scored - max_range;
        // A NaN or infinite pose is nowhere: its cells were read at a saturated index.
        if !sensor.is_finite() {
            sum = f32::NAN;
        }
        ScanScore {
            log_likelihood: sum,
            scored: sat16(scored),
            max_range: sat16(max_range),
            invalid: sat16(invalid),
            unpaired: sat16(ranges.len().saturating_sub(layout.len())),
        }
    }

    /// As [`LikelihoodField::score`], also writing each beam's scored endpoint distance
    /// (metres) into `distances_m[k]`, and NaN for a beam that was skipped. Entries past the
    /// scan's length or the layout's are left as they are; a shorter `distances_m` receives
    /// what fits.
    pub fn score_into<const N: usize>(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
        pose: &Pose,
        distances_m: &mut [f32],
    ) -> ScanScore {
        let n = layout.len().min(scan.len());
        for d in distances_m.iter_mut().take(n) {
            *d = f32::NAN;
        }
        self.score_with(layout, scan, pose, |k, d| {
            if let Some(slot) = distances_m.get_mut(k) {
                *slot = d;
            }
        })
    }
}

impl<const N: usize> SensorModel<N> for LikelihoodField<'_> {
    /// [`LikelihoodField::score_strided_with`] without the per-beam callback.
    fn score_strided(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
        pose: &Pose,
        stride: Stride,
    ) -> ScanScore {
        self.score_strided_with(layout, scan, pose, stride, |_, _| {})
    }
}

fn sat16<T: TryInto<u16>>(n: T) -> u16 {
    n.try_into().unwrap_or(u16::MAX)
}

#[cfg(test)]
mod tests {
    use super::super::blob::{emit_blob, FieldHeader};
    use super::*;
    use crate::pose::SensorMount;

    #[test]
    fn params_validation_table() {
        let cases = [
            (
                (f32::NAN, 0.05, 0.2, 10.0),
                LikelihoodError::NonFinite(LikelihoodParam::ZHit),
            ),
            (
                (0.95, -0.1, 0.2, 10.0),
                LikelihoodError::NegativeWeight(LikelihoodParam::ZRand),
            ),
            ((0.95, 0.1, 0.2, 10.0), LikelihoodError::WeightsAboveOne),
            ((0.0, 0.0, 0.2, 10.0), LikelihoodError::WeightsAllZero),
            ((0.95, 0.05, 0.0, 10.0), LikelihoodError::NonPositiveSigma),
            (
                (0.95, 0.05, 0.2, -1.0),
                LikelihoodError::NonPositiveMaxRange,
            ),
            (
                (0.95, 0.05, 0.2, f32::INFINITY),
                LikelihoodError::NonFinite(LikelihoodParam::MaxRange),
            ),
        ];
        for ((a, b, c, d), want) in cases {
            assert_eq!(LikelihoodParams::new(a, b, c, d), Err(want));
        }
        assert!(LikelihoodParams::amcl_defaults(10.0).is_ok());
    }

    #[test]
    fn term_against_closed_form() {
        let p = LikelihoodParams::new(0.8, 0.2, 0.5, 4.0).unwrap();
        for d in [0.0f64, 0.1, 0.5, 1.0, 2.0, 5.0] {
            let want = (0.8 * (-0.5 * (d / 0.5).powi(2)).exp()
                / (0.5 * (2.0 * std::f64::consts::PI).sqrt())
                + 0.2 / 4.0)
                .ln();
            let got = f64::from(p.beam_log_likelihood(d as f32));
            assert!((got - want).abs() < 2e-6, "d = {d}: {got} vs {want}");
        }
        // z_rand = 0: far beams stay finite (pure Gaussian log).
        let g = LikelihoodParams::new(1.0, 0.0, 0.1, 4.0).unwrap();
        assert!(g.beam_log_likelihood(50.0).is_finite());
    }

    #[test]
    fn skipped_readings_are_counted() {
        let h = FieldHeader::new(4, 4, 1.0, 0.0, 0.0);
        let mut b = vec![0u8; h.required_len().unwrap()];
        emit_blob(&h, &[7; 16], &mut b).unwrap();
        let view = FieldView::parse(&b).unwrap();
        let lf = LikelihoodField::new(view, LikelihoodParams::amcl_defaults(3.0).unwrap());
        let layout = BeamLayout::<6>::uniform(0.0, 0.1, 5, 3.0, SensorMount::CENTERED).unwrap();
        let scan = Scan::<6>::from_ranges(&[1.0, f32::NAN, 3.0, -1.0, f32::INFINITY, 0.5]).unwrap();
        let mut d = [0.0f32; 6];
        let s = lf.score_into(&layout, &scan, &Pose::new(2.0, 2.0, 0.0), &mut d);
        assert_eq!((s.scored, s.invalid, s.max_range, s.unpaired), (1, 2, 2, 1));
        let want = lf.params().beam_log_likelihood(7.0 * 2.0 / 255.0);
        assert!((s.log_likelihood - want).abs() < 1e-6);
        assert!((d[0] - 7.0 * 2.0 / 255.0).abs() < 1e-7);
        assert!(d[1..5].iter().all(|x| x.is_nan()));
        assert_eq!(d[5], 0.0);
    }
}
