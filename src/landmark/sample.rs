//! Sampling a pose from one landmark observation: Thrun Table 6.5,
//! `sample_landmark_model_known_correspondence`.

use super::{Feature, FeatureNoise, Landmark};
use crate::gaussian::{standard_normal_pair, uniform_f32};
use crate::math;
use crate::pose::{wrap_angle, Pose};
use core::f32::consts::{PI, TAU};
use rand_core::Rng;

/// How many extra Box–Muller pairs [`sample_pose`] draws at most when the noisy range comes out
/// negative, before settling for `r̂ = 0`. Each pair offers two candidates, each accepted with
/// probability ≥ ½ for a valid feature (range ≥ 0), so the fallback happens with probability
/// below 2⁻³² ≈ 2.3e-10 per sample.
pub const MAX_RANGE_REDRAWS: u32 = 16;

/// The noisy observation `(r̂, φ̂) = (r + ε_r, φ + ε_φ)` with `ε ~ N(0, σ²)`, the range
/// conditioned on `r̂ ≥ 0` by redrawing `ε_r`. Consumes 2 + 2k `next_u32`, `k ≤`
/// [`MAX_RANGE_REDRAWS`] the number of redraw pairs (0 unless the first range was negative).
pub(super) fn perturb<R: Rng + ?Sized>(
    feature: &Feature,
    noise: &FeatureNoise,
    rng: &mut R,
) -> (f32, f32) {
    let (z_range, z_bearing) = standard_normal_pair(rng);
    let bearing_rad = feature.bearing_rad + noise.sigma_bearing_rad * z_bearing;
    let mut range_m = feature.range_m + noise.sigma_range_m * z_range;
    let mut pairs = 0;
    while range_m < 0.0 && pairs < MAX_RANGE_REDRAWS {
        let (a, b) = standard_normal_pair(rng);
        range_m = feature.range_m + noise.sigma_range_m * a;
        if range_m < 0.0 {
            range_m = feature.range_m + noise.sigma_range_m * b;
        }
        pairs += 1;
    }
    (range_m.max(0.0), bearing_rad)
}

/// Draws a pose from `p(x | f, c, m)` under a uniform pose prior: Thrun Table 6.5.
///
/// ```text
/// γ ~ U[0, 2π),  r̂ = r + ε_r,  φ̂ = φ + ε_φ,  ε_r ~ N(0, σ_r²),  ε_φ ~ N(0, σ_φ²)
/// x = m_x + r̂·cos γ,  y = m_y + r̂·sin γ,  θ = wrap(γ − π − φ̂)
/// ```
///
/// The robot sits at angle γ around the landmark, from where the landmark bears γ − π in the
/// map frame, so the heading that shows it at relative bearing φ̂ is γ − π − φ̂. The heading is
/// returned wrapped into `[−π, π)`. The result is a *proposal*: real pose priors are not
/// uniform (walls, the last estimate), so reweight it before trusting it.
///
/// # Random numbers
/// In this order: one `next_u32` for γ (`γ = 2π·u`, `u` from [`uniform_f32`], so γ ∈ [0, 2π)
/// on a 2⁻²⁴ grid), then one Box–Muller pair ([`standard_normal_pair`], two `next_u32`) giving
/// `ε_r` (first) and `ε_φ` (second). Nothing else, unless the range is redrawn (below).
///
/// # Negative noisy range
/// `r + ε_r < 0` is impossible physically, and plugging it into the formula would put the robot
/// on the far side of the landmark while the heading still assumes the near side (the landmark
/// would appear at φ̂ + π). Clamping it to 0 (the chapter's code) would pile a point mass onto
/// the landmark. Instead `ε_r` is redrawn (extra Box–Muller pairs, both values used) until
/// `r̂ ≥ 0`: the sampled range follows `N(r, σ_r²)` *conditioned on* `r̂ ≥ 0`, a normal truncated
/// at 0, which is the range likelihood restricted to physical ranges. This only matters when
/// `r` is within a few σ_r of 0. After [`MAX_RANGE_REDRAWS`] pairs (probability < 2.3e-10)
/// `r̂ = 0` is used, so the run time is bounded.
pub fn sample_pose<R: Rng + ?Sized>(
    feature: &Feature,
    landmark: &Landmark,
    noise: &FeatureNoise,
    rng: &mut R,
) -> Pose {
    let gamma_rad = TAU * uniform_f32(rng);
    let (range_m, bearing_rad) = perturb(feature, noise, rng);
    let (s, c) = math::sin_cos(gamma_rad);
    Pose {
        x_m: landmark.x_m + range_m * c,
        y_m: landmark.y_m + range_m * s,
        theta_rad: wrap_angle(gamma_rad - PI - bearing_rad),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A counter generator: every word is the previous plus a large odd step.
    struct Weyl(u32);

    impl rand_core::TryRng for Weyl {
        type Error = core::convert::Infallible;
        fn try_next_u32(&mut self) -> Result<u32, Self::Error> {
            self.0 = self.0.wrapping_add(0x9E37_79B9);
            Ok(self.0)
        }
        fn try_next_u64(&mut self) -> Result<u64, Self::Error> {
            Ok(u64::from(self.try_next_u32()?) << 32 | u64::from(self.try_next_u32()?))
        }
        fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Self::Error> {
            for b in dst {
                *b = self.try_next_u32()? as u8;
            }
            Ok(())
        }
    }

    #[test]
    fn zero_range_feature_never_goes_negative() {
        let f = Feature::new(0.0, 0.3, 0.0).unwrap();
        let lm = Landmark::new(2.0, -1.0, 0.0).unwrap();
        let noise = FeatureNoise::new(0.5, 0.1, 1.0).unwrap();
        let mut rng = Weyl(1);
        for _ in 0..1000 {
            let p = sample_pose(&f, &lm, &noise, &mut rng);
            assert!(p.is_finite());
            assert!((-PI..PI).contains(&p.theta_rad));
            let (r, _) = super::super::predict(&lm, &p);
            // Re-observed range is |r̂| up to rounding, and r̂ ≤ 0 + 5.77σ.
            assert!(r <= 0.5 * crate::gaussian::STANDARD_NORMAL_MAX_ABS + 1e-5);
        }
    }
}
