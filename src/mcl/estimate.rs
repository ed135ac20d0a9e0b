//! The pose estimate of a weighted particle set: weighted mean, circular mean heading,
//! covariance, and the effective sample size.

use crate::math;
use crate::pose::{wrap_angle, Pose};

/// What the filter believes after an update.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Estimate {
    /// Weighted mean position (metres) and circular mean heading
    /// `atan2(Σ wᵢ sin θᵢ, Σ wᵢ cos θᵢ)` (radians, in `[−π, π)`).
    pub pose: Pose,
    /// Weighted covariance of `(x, y, θ)` (m², m², rad² and mixed), row-major. Heading
    /// deviations are wrapped differences from the circular mean.
    pub covariance: [[f32; 3]; 3],
    /// Effective sample size `1 / Σ wᵢ²` of the weights the estimate was computed from.
    pub ess: f32,
}

impl Estimate {
    /// The estimate of `poses` weighted by `weights` (summing to 1; extra entries of the longer
    /// slice are ignored). An empty set gives the default (all zeros).
    ///
    /// Two passes: means, then second moments about the means (no cancellation).
    pub fn of(poses: &[Pose], weights: &[f32]) -> Self {
        Self::of_selected(poses, weights, |_| true)
    }

    /// The estimate of the particles within `radius_m` (metres) and `half_angle_rad` (radians)
    /// of `center` only, their weights renormalized: the mode's neighbourhood, so that a few
    /// far particles (recovery's random ones, a second hypothesis) do not drag the mean into a
    /// wall. The ESS is still that of the whole set. If no particle is within, it is
    /// [`Estimate::of`] the whole set.
    pub fn around(
        poses: &[Pose],
        weights: &[f32],
        center: &Pose,
        radius_m: f32,
        half_angle_rad: f32,
    ) -> Self {
        let r2 = radius_m * radius_m;
        let near = |p: &Pose| {
            let (dx, dy) = (p.x_m - center.x_m, p.y_m - center.y_m);
            dx * dx + dy * dy <= r2
                && wrap_angle(p.theta_rad - center.theta_rad).abs() <= half_angle_rad
        };
        let all: f32 = weights.iter().map(|w| w * w).sum();
        let mut e = Self::of_selected(poses, weights, near);
        if e.ess == 0.0 {
            e = Self::of(poses, weights);
        }
        e.ess = if all > 0.0 { 1.0 / all } else { 0.0 };
        e
    }

    fn of_selected<F: Fn(&Pose) -> bool>(poses: &[Pose], weights: &[f32], keep: F) -> Self {
        let mut total = 0.0f32;
        for (p, &w) in poses.iter().zip(weights) {
            if keep(p) {
                total += w;
            }
        }
        if total <= 0.0 {
            return Self::default();
        }
        let inv = 1.0 / total;
        let (mut sx, mut sy, mut ss, mut sc, mut sw2) = (0.0f32, 0.0, 0.0, 0.0, 0.0);
        for (p, &w) in poses.iter().zip(weights) {
            let w = if keep(p) { w * inv } else { 0.0 };
            sx += w * p.x_m;
            sy += w * p.y_m;
            let (s, c) = math::sin_cos(p.theta_rad);
            ss += w * s;
            sc += w * c;
            sw2 += w * w;
        }
        let theta = wrap_angle(math::atan2(ss, sc));
        let mut cov = [[0.0f32; 3]; 3];
        for (p, &w) in poses.iter().zip(weights) {
            let w = if keep(p) { w * inv } else { 0.0 };
            let d = [p.x_m - sx, p.y_m - sy, wrap_angle(p.theta_rad - theta)];
            for (row, di) in cov.iter_mut().zip(d) {
                for (cell, dj) in row.iter_mut().zip(d) {
                    *cell += w * di * dj;
                }
            }
        }
        Self {
            pose: Pose::new(sx, sy, theta),
            covariance: cov,
            ess: if sw2 > 0.0 { 1.0 / sw2 } else { 0.0 },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::PI;

    #[test]
    fn heading_mean_across_the_seam() {
        // Two headings at ±(π − 0.1): the circular mean is π (wrapped to −π), not 0.
        let poses = [
            Pose::new(1.0, 0.0, PI - 0.1),
            Pose::new(3.0, 2.0, -PI + 0.1),
        ];
        let e = Estimate::of(&poses, &[0.5, 0.5]);
        assert!(
            (e.pose.theta_rad.abs() - PI).abs() < 1e-5,
            "{}",
            e.pose.theta_rad
        );
        assert!((e.pose.x_m - 2.0).abs() < 1e-6 && (e.pose.y_m - 1.0).abs() < 1e-6);
        // Hand-derived: var x = var y = cov xy = 1; var θ = 0.01.
        assert!((e.covariance[0][0] - 1.0).abs() < 1e-6);
        assert!((e.covariance[0][1] - 1.0).abs() < 1e-6);
        assert!((e.covariance[2][2] - 0.01).abs() < 1e-5);
        assert!((e.ess - 2.0).abs() < 1e-6);
    }
}
