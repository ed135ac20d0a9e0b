//! A motion model whose spread follows the data: the odometry noise is scaled at every update
//! so that the scan's correction of the predicted cloud is as large as that cloud's own spread
//! says it should be (an innovation test, as adaptive Kalman filters estimate their process
//! noise).
//!
//! At each update after a motion, the filter compares the mean of the predicted set (the
//! prior, before the scan) with the particle the scan weighs highest: `ν = dᵀ Σ⁻¹ d`, with `d`
//! the difference (x, y, heading) and `Σ` the prior set's covariance (plus a floor). When the
//! motion model's spread is right and the scan is informative, the best particle is the one
//! nearest the robot, which the prior says lies about one σ per dimension from its mean, and
//! `ν` averages about the number of dimensions (3); when the odometry is worse than the model,
//! the robot is outside the cloud and the best particle sits on its edge (`ν` larger); when
//! the model is far wider than the odometry, the best particle is near the middle (smaller).
//! (The weighted mean would not do: averaging the particles near the edge pulls it back into
//! the cloud, and a cloud that misses the robot looks consistent.) The
//! scale `q` of the odometry variances (`odom_alpha1..4` times `q`, the standard deviations
//! times `√q`) moves by `q ← q·(1 + rate·(min(ν, cap)/target − 1))`, within `[min_scale,
//! max_scale]`.
//!
//! Fixed cost: one pass over the particles per update for the prior's moments (sums of
//! deviations from the first particle, no trigonometry) and a 3×3 solve; nothing per beam,
//! no memory per particle.

use crate::pose::Pose;

/// The parameters of the adaptive motion noise ([`MclConfig::with_adaptive_noise`](super::MclConfig::with_adaptive_noise)).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AdaptiveNoise {
    /// The value of `ν` (dimensionless, a squared Mahalanobis distance in 3 dimensions) the
    /// scale is steered to.
    pub target: f32,
    /// How far one update moves the scale towards it (0 to 1).
    pub rate: f32,
    /// The smallest variance scale (`> 0`, at most 1).
    pub min_scale: f32,
    /// The largest variance scale (at least 1).
    pub max_scale: f32,
}

impl AdaptiveNoise {
    /// The defaults: target 1, rate 0.3, the variances between a quarter and 4 times the
    /// configured ones (the standard deviations between half and twice). Chosen on two logs
    /// (docs/localization.md, "Adaptive motion noise"): a larger bound (16, 64) widens the
    /// proposal so far under systematic wheel errors that the filter is lost where the
    /// fixed model is not; target 3 (the consistent value) reacts too little.
    pub const DEFAULT: Self = Self {
        target: 1.0,
        rate: 0.3,
        min_scale: 0.25,
        max_scale: 4.0,
    };

    /// True when every value is in range: `target` finite and positive, `rate` in `(0, 1]`,
    /// `0 < min_scale ≤ 1 ≤ max_scale ≤` [`MAX_NOISE_SCALE`].
    pub fn validate(&self) -> bool {
        self.target.is_finite()
            && self.target > 0.0
            && self.rate > 0.0
            && self.rate <= 1.0
            && self.min_scale > 0.0
            && self.min_scale <= 1.0
            && self.max_scale >= 1.0
            && self.max_scale <= MAX_NOISE_SCALE
    }

    /// The next scale after an update whose innovation was `nis` (NaN leaves it as it was).
    pub fn next_scale(&self, scale: f32, nis: f32) -> f32 {
        if nis.is_nan() {
            return scale;
        }
        let ratio = nis.min(NIS_CAP * self.target) / self.target;
        let next = scale * (1.0 + self.rate * (ratio - 1.0));
        next.clamp(self.min_scale, self.max_scale)
    }
}

impl Default for AdaptiveNoise {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The largest variance scale [`AdaptiveNoise::max_scale`] takes.
pub const MAX_NOISE_SCALE: f32 = 1_000.0;

/// One update's innovation counts at most this many times the target (one outlying scan moves
/// the scale by at most `rate·(NIS_CAP − 1)`).
pub const NIS_CAP: f32 = 10.0;

/// The prior's variance floor in x and y, m² ((1 cm)²): a collapsed set (all particles equal
/// after resampling) does not make every correction infinitely surprising.
pub const PRIOR_FLOOR_M2: f32 = 1e-4;

/// The prior's variance floor in heading, rad² ((0.25°)²).
pub const PRIOR_FLOOR_RAD2: f32 = 2e-5;

/// Weighted mean and covariance of a set (the prior), as deviations from its first pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Prior {
    pub(super) mean: Pose,
    pub(super) covariance: [[f32; 3]; 3],
}

impl Prior {
    /// The weighted moments of `poses` (weights `weights`, any positive total; `uniform`: all
    /// equal, `weights` unread). None for an empty set or a zero total.
    pub(super) fn of(poses: &[Pose], weights: &[f32], uniform: bool) -> Option<Self> {
        let origin = *poses.first()?;
        // Σw, Σw·d and Σw·d·dᵀ (upper triangle) of the deviations d from the first pose.
        let (mut w0, mut sx, mut sy, mut st) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        let (mut xx, mut xy, mut xt, mut yy, mut yt, mut tt) = (0.0f32, 0.0, 0.0, 0.0, 0.0, 0.0);
        let mut add = |w: f32, p: &Pose| {
            let a = p.x_m - origin.x_m;
            let b = p.y_m - origin.y_m;
            let c = crate::pose::wrap_angle(p.theta_rad - origin.theta_rad);
            w0 += w;
            sx += w * a;
            sy += w * b;
            st += w * c;
            xx += w * a * a;
            xy += w * a * b;
            xt += w * a * c;
            yy += w * b * b;
            yt += w * b * c;
            tt += w * c * c;
        };
        if uniform {
            poses.iter().for_each(|p| add(1.0, p));
        } else {
            poses.iter().zip(weights).for_each(|(p, &w)| add(w, p));
        }
        if w0.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            return None;
        }
        let inv = 1.0 / w0;
        let (mx, my, mt) = (sx * inv, sy * inv, st * inv);
        let (cxy, cxt, cyt) = (xy * inv - mx * my, xt * inv - mx * mt, yt * inv - my * mt);
        let covariance = [
            [xx * inv - mx * mx, cxy, cxt],
            [cxy, yy * inv - my * my, cyt],
            [cxt, cyt, tt * inv - mt * mt],
        ];
        Some(Self {
            mean: Pose::new(
                origin.x_m + mx,
                origin.y_m + my,
                crate::pose::wrap_angle(origin.theta_rad + mt),
            ),
            covariance,
        })
    }

    /// `ν = dᵀ (Σ + floor)⁻¹ d` for `d` the difference of `posterior` from the prior's mean
    /// (heading wrapped); NaN when the matrix is not positive definite (it always is with the
    /// floor, unless an input is NaN).
    pub(super) fn nis(&self, posterior: &Pose) -> f32 {
        let d = [
            posterior.x_m - self.mean.x_m,
            posterior.y_m - self.mean.y_m,
            crate::pose::wrap_angle(posterior.theta_rad - self.mean.theta_rad),
        ];
        let [[c00, c01, c02], [c10, c11, c12], [c20, c21, c22]] = self.covariance;
        let a = [
            [c00 + PRIOR_FLOOR_M2, c01, c02],
            [c10, c11 + PRIOR_FLOOR_M2, c12],
            [c20, c21, c22 + PRIOR_FLOOR_RAD2],
        ];
        // Cholesky, a = L Lᵀ; ν = |L⁻¹ d|². A pivot that is not positive (or NaN) fails.
        let positive = |v: f32| v.partial_cmp(&0.0) == Some(core::cmp::Ordering::Greater);
        let [[a00, _, _], [a10, a11, _], [a20, a21, a22]] = a;
        let [d0, d1, d2] = d;
        if !positive(a00) {
            return f32::NAN;
        }
        let l00 = crate::math::sqrt(a00);
        let l10 = a10 / l00;
        let l20 = a20 / l00;
        let q11 = a11 - l10 * l10;
        if !positive(q11) {
            return f32::NAN;
        }
        let l11 = crate::math::sqrt(q11);
        let l21 = (a21 - l20 * l10) / l11;
        let q22 = a22 - l20 * l20 - l21 * l21;
        if !positive(q22) {
            return f32::NAN;
        }
        let l22 = crate::math::sqrt(q22);
        let y0 = d0 / l00;
        let y1 = (d1 - l10 * y0) / l11;
        let y2 = (d2 - l20 * y0 - l21 * y1) / l22;
        y0 * y0 + y1 * y1 + y2 * y2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validate_bounds() {
        assert!(AdaptiveNoise::DEFAULT.validate());
        let d = AdaptiveNoise::DEFAULT;
        for bad in [
            AdaptiveNoise { target: 0.0, ..d },
            AdaptiveNoise {
                target: f32::NAN,
                ..d
            },
            AdaptiveNoise { rate: 0.0, ..d },
            AdaptiveNoise { rate: 1.5, ..d },
            AdaptiveNoise {
                min_scale: 0.0,
                ..d
            },
            AdaptiveNoise {
                min_scale: 2.0,
                ..d
            },
            AdaptiveNoise {
                max_scale: 0.5,
                ..d
            },
            AdaptiveNoise {
                max_scale: 1e6,
                ..d
            },
        ] {
            assert!(!bad.validate(), "{bad:?}");
        }
    }

    #[test]
    fn scale_moves_towards_the_target_and_stays_in_bounds() {
        let a = AdaptiveNoise::DEFAULT;
        assert_eq!(a.next_scale(1.0, a.target), 1.0);
        assert!(a.next_scale(1.0, 4.0 * a.target) > 1.0);
        assert!(a.next_scale(1.0, 0.25 * a.target) < 1.0);
        assert_eq!(a.next_scale(2.0, f32::NAN), 2.0);
        let mut q = 1.0;
        for _ in 0..1000 {
            q = a.next_scale(q, f32::INFINITY);
        }
        assert_eq!(q, a.max_scale);
        for _ in 0..1000 {
            q = a.next_scale(q, 0.0);
        }
        assert_eq!(q, a.min_scale);
    }

    #[test]
    fn nis_of_a_known_cloud() {
        // Four poses at ±0.1 m in x and y around (1, 2), heading ±0.05 rad: variances 0.01 m²
        // (x and y) and 0.0025 rad² (θ), uncorrelated.
        let poses = [
            Pose::new(1.1, 2.1, 0.05),
            Pose::new(0.9, 2.1, -0.05),
            Pose::new(1.1, 1.9, -0.05),
            Pose::new(0.9, 1.9, 0.05),
        ];
        let p = Prior::of(&poses, &[], true).unwrap();
        assert!((p.mean.x_m - 1.0).abs() < 1e-6 && (p.mean.y_m - 2.0).abs() < 1e-6);
        assert!(p.mean.theta_rad.abs() < 1e-6);
        assert!(
            (p.covariance[0][0] - 0.01).abs() < 1e-6,
            "{:?}",
            p.covariance
        );
        // One σ off in x (plus the floor): ν ≈ 0.01 / (0.01 + 1e-4).
        let nis = p.nis(&Pose::new(1.1, 2.0, 0.0));
        assert!((nis - 0.01 / 0.0101).abs() < 1e-3, "{nis}");
        assert_eq!(p.nis(&p.mean), 0.0);
        assert!(p.nis(&Pose::new(f32::NAN, 0.0, 0.0)).is_nan());
        // A collapsed set: the floor keeps ν finite.
        let same = [Pose::new(0.0, 0.0, 0.0); 3];
        let c = Prior::of(&same, &[], true).unwrap();
        let nis = c.nis(&Pose::new(0.01, 0.0, 0.0));
        assert!((nis - 1.0).abs() < 1e-3, "{nis}");
        assert!(Prior::of(&[], &[], true).is_none());
        assert!(Prior::of(&poses, &[0.0; 4], false).is_none());
    }
}
