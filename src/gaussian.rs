//! Uniform and Gaussian variates from any [`rand_core::Rng`], without `std` or allocation.
//!
//! The samplers of Thrun Table 6.5 ([`crate::landmark`]) need `U[0, 2π)` and `N(0, σ²)` draws.
//! `rand_core` 0.10 only hands out integers, so the conversion to floats is done here, once, and
//! documented exactly, so a firmware user can reproduce a sequence bit for bit on the host.
//!
//! # Uniform: integer to float
//! One `next_u32` per variate; its top 24 bits `k = u >> 8` (the best bits of weak generators
//! such as LCGs sit at the top) give
//!
//! - [`uniform_f32`]: `k · 2⁻²⁴ ∈ [0, 1 − 2⁻²⁴]`, i.e. `[0, 1)`;
//! - the Box–Muller radius input: `(k + 1) · 2⁻²⁴ ∈ [2⁻²⁴, 1]`, i.e. `(0, 1]`.
//!
//! Both products are exact in f32 (24 significant bits), so every one of the 2²⁴ values is equally
//! likely and there is no rounding bias. The grid step is 2⁻²⁴ ≈ 6.0e-8.
//!
//! # Gaussian: Box–Muller
//! [`standard_normal_pair`] draws `u₁ ∈ (0, 1]` and `u₂ ∈ [0, 1)` (two `next_u32`, in that order)
//! and returns
//!
//! ```text
//! R = √(−2·ln u₁),  α = π·(2u₂ − 1) ∈ [−π, π)
//! (z₀, z₁) = (R·cos α, R·sin α)
//! ```
//!
//! two independent standard normals (the basic Box–Muller transform; `α` is the usual `2πu₂`
//! shifted by `−π`, which only flips the sign of both outputs and keeps the argument of
//! `sin_cos` small). It costs one `ln`, one `sqrt` and one `sin_cos` through [`crate::math`], and
//! a fixed two generator calls: no rejection loop, so its run time is constant.
//!
//! Limits, from the 24-bit uniforms: `|z| ≤ √(−2·ln 2⁻²⁴) = 5.768`, so the tails beyond 5.77σ
//! (probability 8.0e-9 under a true normal) are cut off, and far in the tail the attainable
//! values are coarsely spaced (`u₁` is a multiple of 2⁻²⁴). The variance lost to the cut is
//! below 1e-6 relative. With the default libm backend the f32 arithmetic adds errors of a few
//! 1e-7 to each draw; with the `micromath` backend `ln` has an absolute error up to 1e-4
//! (`R²` off by ≤ 2e-4) and `sin_cos` up to 1e-3, which shift individual draws by up to ~1e-2
//! near `z = 0` but leave mean and variance within 1e-3 of the normal's.

use crate::math;
use rand_core::Rng;

/// `2⁻²⁴`, the grid step of the uniforms (exact in f32).
const TWO_POW_MINUS_24: f32 = 1.0 / 16_777_216.0;

/// Largest magnitude [`standard_normal_pair`] can return: `√(−2·ln 2⁻²⁴)` (rounded up).
pub const STANDARD_NORMAL_MAX_ABS: f32 = 5.768_4;

/// A uniform variate on `[0, 1)`: the top 24 bits of one `next_u32`, times `2⁻²⁴` (exact).
#[inline]
pub fn uniform_f32<R: Rng + ?Sized>(rng: &mut R) -> f32 {
    // `u32 >> 8` is below 2²⁴, so the conversion to f32 is exact.
    (rng.next_u32() >> 8) as f32 * TWO_POW_MINUS_24
}

/// A uniform variate on `(0, 1]`: `(k + 1)·2⁻²⁴` with `k` the top 24 bits of one `next_u32`.
/// Never 0, so its logarithm is finite.
#[inline]
pub fn uniform_open_closed_f32<R: Rng + ?Sized>(rng: &mut R) -> f32 {
    ((rng.next_u32() >> 8) + 1) as f32 * TWO_POW_MINUS_24
}

/// Two independent standard normal variates (mean 0, variance 1) by the Box–Muller transform.
///
/// Consumes exactly two `next_u32`. See the module docs for the exact recipe and its limits
/// (`|z| ≤` [`STANDARD_NORMAL_MAX_ABS`]).
#[inline]
pub fn standard_normal_pair<R: Rng + ?Sized>(rng: &mut R) -> (f32, f32) {
    let u1 = uniform_open_closed_f32(rng);
    let u2 = uniform_f32(rng);
    // u1 ∈ (0, 1]: ln u1 ∈ [−16.64, 0], so the radius is finite and ≥ 0 (−0.0 for u1 = 1 is
    // harmless: sqrt(−0.0) = −0.0 and multiplies out to a signed zero).
    let radius = math::sqrt(-2.0 * math::ln(u1));
    let alpha = core::f32::consts::PI * (2.0 * u2 - 1.0);
    let (s, c) = math::sin_cos(alpha);
    (radius * c, radius * s)
}

/// One standard normal variate: the first of a [`standard_normal_pair`] (the second is
/// discarded). Consumes exactly two `next_u32`.
#[inline]
pub fn standard_normal<R: Rng + ?Sized>(rng: &mut R) -> f32 {
    standard_normal_pair(rng).0
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::convert::Infallible;

    /// Replays a fixed list of words, then zeros.
    struct Replay<'a>(&'a [u32]);

    impl rand_core::TryRng for Replay<'_> {
        type Error = Infallible;
        fn try_next_u32(&mut self) -> Result<u32, Infallible> {
            let (first, rest) = self.0.split_first().map_or((0, &[][..]), |(f, r)| (*f, r));
            self.0 = rest;
            Ok(first)
        }
        fn try_next_u64(&mut self) -> Result<u64, Infallible> {
            let lo = u64::from(self.try_next_u32()?);
            let hi = u64::from(self.try_next_u32()?);
            Ok(lo | (hi << 32))
        }
        fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Infallible> {
            for b in dst {
                *b = self.try_next_u32()? as u8;
            }
            Ok(())
        }
    }

    #[test]
    fn uniform_endpoints() {
        let mut r = Replay(&[0, u32::MAX, 0x0000_00FF, 0x8000_0000]);
        assert_eq!(uniform_f32(&mut r), 0.0);
        let top = uniform_f32(&mut r);
        assert!(top < 1.0);
        assert_eq!(f64::from(top), 1.0 - 2f64.powi(-24));
        // The low 8 bits are ignored.
        assert_eq!(uniform_f32(&mut r), 0.0);
        assert_eq!(uniform_f32(&mut r), 0.5);
        let mut r = Replay(&[0, u32::MAX]);
        assert_eq!(f64::from(uniform_open_closed_f32(&mut r)), 2f64.powi(-24));
        assert_eq!(uniform_open_closed_f32(&mut r), 1.0);
    }

    #[test]
    fn box_muller_extremes_against_f64() {
        // u1 = 2⁻²⁴ (word 0) gives the largest radius; u2 = 0.5 (word 0x8000_0000) gives α = 0.
        let mut r = Replay(&[0, 0x8000_0000]);
        let (z0, z1) = standard_normal_pair(&mut r);
        let want = (-2.0 * (2f64.powi(-24)).ln()).sqrt();
        assert!((f64::from(z0) - want).abs() < 1e-5, "{z0} vs {want}");
        assert!(z1.abs() < 1e-6);
        assert!(z0 <= STANDARD_NORMAL_MAX_ABS && f64::from(STANDARD_NORMAL_MAX_ABS) >= want);
        // u1 = 1 (word u32::MAX) gives radius 0 whatever the angle.
        let mut r = Replay(&[u32::MAX, 0x1234_5678]);
        let (z0, z1) = standard_normal_pair(&mut r);
        assert_eq!((z0.abs(), z1.abs()), (0.0, 0.0));
    }
}
