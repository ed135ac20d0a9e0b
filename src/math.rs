//! The math façade: the only module in the crate that calls a transcendental function.
//!
//! Every other module goes through these functions, so the numerical backend is chosen in one
//! place. The default backend is [`libm`] (a port of musl's libm: correctly rounded or within
//! 1 ulp for `expf`, `logf`, `sqrtf`; `erfcf` within a few ulp). With the `micromath` feature,
//! `exp`, `ln`, `sqrt`, `sin_cos` and `atan2` use [`micromath`]'s fast approximations instead;
//! `erfc` and `expm1` always use libm (micromath has no erfc and no accurate expm1).
//!
//! Measured maximum errors against f64 (`host-tests/tests/math_backend.rs` measures them on every
//! run; the figures below are what it printed on 2026-11-23):
//!
//! | function | libm (default) | micromath |
//! |---|---|---|
//! | `exp` on [−80, 80] | ≤ 1.2e-7 relative | ≤ 7e-6 relative (micromath states 1e-5) |
//! | `ln` on [1e-30, 1e30] | ≤ 1.2e-7 relative (≤ 9e-6 abs) | ≤ 1e-4 absolute |
//! | `sqrt` | correctly rounded | ≤ 5e-4 relative |
//! | `sin_cos` on [−2π, 2π] | ≤ 6e-8 absolute | ≤ 1e-3 absolute |
//! | `atan2` | ≤ 2.4e-7 absolute | ≤ 4e-3 absolute |
//! | `erfc` on [−10, 10] | ≤ 2.5e-7 relative (always libm) | same |
//!
//! The f64 helpers (`*_f64`) always use libm: they serve the host-side and EM code that
//! accumulates in double precision.

/// `e^x`.
#[inline]
pub fn exp(x: f32) -> f32 {
    #[cfg(feature = "micromath")]
    {
        micromath::F32(x).exp().0
    }
    #[cfg(not(feature = "micromath"))]
    {
        libm::expf(x)
    }
}

/// Natural logarithm. `ln(0) = −∞`, `ln(x < 0) = NaN` (callers never pass negatives).
#[inline]
pub fn ln(x: f32) -> f32 {
    #[cfg(feature = "micromath")]
    {
        if x <= 0.0 {
            return libm::logf(x);
        }
        micromath::F32(x).ln().0
    }
    #[cfg(not(feature = "micromath"))]
    {
        libm::logf(x)
    }
}

/// Square root.
#[inline]
pub fn sqrt(x: f32) -> f32 {
    #[cfg(feature = "micromath")]
    {
        micromath::F32(x).sqrt().0
    }
    #[cfg(not(feature = "micromath"))]
    {
        libm::sqrtf(x)
    }
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
        libm::sincosf(x)
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
