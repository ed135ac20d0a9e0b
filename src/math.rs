//! The math façade: the only module in the crate that calls a transcendental function.
//!
//! Every other module goes through these functions, so the numerical backend is chosen in one
//! place. The default backend is [`libm`] (a port of musl's libm), except `sin_cos`, which is the
//! crate's own single-precision reduction and Taylor series (private module `trig`): `libm::sincosf`
//! linked 6.8 KB of code, used about 0.9 KB of stack and cost about 1,500 instructions per call on
//! a Cortex-M4F (its exact reduction runs in soft-float f64), for 0.5 ulp better accuracy than
//! anything scoring needs. The `micromath` feature swaps in the `micromath` crate's
//! approximations for `sin_cos` and `atan2` only (about 20 instructions, 1e-3 accurate), while
//! micromath's `exp`, `ln` and `sqrt` are no faster than libm's and far
//! less accurate (measured below), so those always come from libm, as do `erf`, `erfc` and
//! `expm1`. Trig is only ever called once per pose or per layout, never per beam.
//!
//! Maximum errors against f64, measured by `host-tests/tests/math_backend.rs` on every test run
//! (which also asserts them; run it with `--features micromath` for the second column):
//!
//! | function | libm (default) | micromath feature |
//! |---|---|---|
//! | `exp` on [−80, 80] | 6.9e-8 relative | same (libm) |
//! | `ln` on [1e-30, 1e30] | 3.8e-6 absolute | same (libm) |
//! | `sqrt` on [1e-6, 1e6] | 6.0e-8 relative (correctly rounded) | same (libm) |
//! | `sin_cos` on [−2π, 2π] | 6.4e-8 absolute (own, see `trig`; libm's was 3.0e-8) | 1.1e-3 absolute |
//! | `atan2` | 2.4e-7 absolute | 2.8e-3 absolute |
//! | `erfc` on [−10, 9] | 2.2e-7 relative | same (libm) |
//! | `normal_mass_straddling_zero` | 1.3e-7 relative | same (libm) |
//!
//! For the record, micromath's own `exp`, `ln` and `sqrt` measured 2.4e-3 relative, 0.12
//! absolute and 6.1e-2 relative on the same ranges: not usable for a likelihood.
//!
//! The f64 helpers (`*_f64`) always use libm: they serve the EM and host-side code that
//! accumulates in double precision.

/// `e^x`.
#[inline]
pub fn exp(x: f32) -> f32 {
    libm::expf(x)
}

/// Natural logarithm. `ln(0) = −∞`, `ln(x < 0) = NaN` (callers never pass negatives).
#[inline]
pub fn ln(x: f32) -> f32 {
    libm::logf(x)
}

/// Square root.
#[inline]
pub fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// `(sin x, cos x)`.
#[inline]
pub fn sin_cos(x: f32) -> (f32, f32) {
    #[cfg(feature = "micromath")]
    {
        (micromath::F32(x).sin().0, micromath::F32(x).cos().0)
    }
    #[cfg(not(feature = "micromath"))]
    {
        crate::trig::sin_cos(x)
    }
}

/// Four-quadrant arctangent of `y / x`, in radians.
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    #[cfg(feature = "micromath")]
    {
        micromath::F32(y).atan2(micromath::F32(x)).0
    }
    #[cfg(not(feature = "micromath"))]
    {
        libm::atan2f(y, x)
    }
}

/// Complementary error function (always libm).
#[inline]
pub fn erfc(x: f32) -> f32 {
    libm::erfcf(x)
}

/// `e^x − 1`, accurate near 0 (always libm).
#[inline]
pub fn expm1(x: f32) -> f32 {
    libm::expm1f(x)
}

/// Error function (always libm).
#[inline]
pub fn erf(x: f32) -> f32 {
    libm::erff(x)
}

/// `Φ(hi) − Φ(lo)` for `lo ≤ 0 ≤ hi`: the mass of a standard normal between the two.
///
/// Written as `½·(erf(hi/√2) + erf(−lo/√2))`, a sum of two non-negative terms, so there is no
/// cancellation when both bounds are near 0 (a very wide Gaussian) and no loss when both are far
/// (a narrow one). For an argument above 4.0, `erf` is exactly 1 in f32 (its complement is below
/// 1.6e-8, under half an ulp), so the call is skipped: the shortcut changes no bit of the result.
#[inline]
pub fn normal_mass_straddling_zero(lo: f32, hi: f32) -> f32 {
    let half = |u: f32| {
        let x = u * core::f32::consts::FRAC_1_SQRT_2;
        if x > 4.0 {
            1.0
        } else {
            erf(x)
        }
    };
    0.5 * (half(hi) + half(-lo))
}

/// Largest integer ≤ `x`, as f32.
#[inline]
pub fn floor(x: f32) -> f32 {
    libm::floorf(x)
}

/// Standard normal CDF `Φ(u) = ½·erfc(−u/√2)`.
///
/// For `u > 6` the result is exactly 1 in f32 (the tail is below 1e-9, under half an ulp of 1),
/// so the erfc call is skipped: the shortcut changes no bit of the rounded result. The lower
/// tail is computed (it is small but representable).
#[inline]
pub fn normal_cdf(u: f32) -> f32 {
    if u > 6.0 {
        1.0
    } else {
        0.5 * erfc(-u * core::f32::consts::FRAC_1_SQRT_2)
    }
}

/// Largest integer ≤ `x`, as f64 (libm).
#[inline]
pub fn floor_f64(x: f64) -> f64 {
    libm::floor(x)
}

/// `e^x` in f64 (libm).
#[inline]
pub fn exp_f64(x: f64) -> f64 {
    libm::exp(x)
}

/// Natural logarithm in f64 (libm).
#[inline]
pub fn ln_f64(x: f64) -> f64 {
    libm::log(x)
}

/// Square root in f64 (libm).
#[inline]
pub fn sqrt_f64(x: f64) -> f64 {
    libm::sqrt(x)
}

/// `e^x − 1` in f64 (libm).
#[inline]
pub fn expm1_f64(x: f64) -> f64 {
    libm::expm1(x)
}

/// Complementary error function in f64 (libm).
#[inline]
pub fn erfc_f64(x: f64) -> f64 {
    libm::erfc(x)
}

/// Error function in f64 (libm).
#[inline]
pub fn erf_f64(x: f64) -> f64 {
    libm::erf(x)
}

/// Standard normal CDF in f64.
#[inline]
pub fn normal_cdf_f64(u: f64) -> f64 {
    0.5 * erfc_f64(-u * core::f64::consts::FRAC_1_SQRT_2)
}

/// `(sin x, cos x)` in f64 (libm).
#[inline]
pub fn sin_cos_f64(x: f64) -> (f64, f64) {
    libm::sincos(x)
}

/// Four-quadrant arctangent in f64 (libm).
#[inline]
pub fn atan2_f64(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}

/// `1/√(2π)`.
pub const INV_SQRT_2PI: f32 = 0.398_942_3;

/// `ln(√(2π))`.
pub const LN_SQRT_2PI: f32 = 0.918_938_5;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_cdf_known_values() {
        let table: [(f32, f32); 5] = [
            (0.0, 0.5),
            (1.0, 0.841_344_7),
            (-1.0, 0.158_655_25),
            (7.0, 1.0),
            (2.5, 0.993_790_3),
        ];
        for (u, want) in table {
            assert!((normal_cdf(u) - want).abs() < 2e-7, "Φ({u})");
        }
    }

    #[test]
    fn ln_sqrt_2pi_constant() {
        let want = 0.5 * (2.0 * core::f64::consts::PI).ln();
        assert!((f64::from(LN_SQRT_2PI) - want).abs() < 1e-7);
    }
}
