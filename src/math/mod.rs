//! The math module: every elementary function of the crate, and the only place that calls a
//! transcendental function.
//!
//! Contract: `no_std`, no allocation, no panics, no tables beyond constants; nothing here
//! imports from the rest of the crate (every model, the localizer and the fixed-point scorer
//! sit above it), so the numerical backend is chosen in one place. Each function states its
//! accuracy; the table below collects them all.
//!
//! - The façade (this file): [`exp`], [`ln`], [`sqrt`], [`sin_cos`], [`atan2`], [`erf`],
//!   [`erfc`], [`expm1`], [`floor`], [`normal_cdf`], [`normal_mass_straddling_zero`] and their
//!   `*_f64` twins. The default backend is [`libm`] (a port of musl's libm), except `sin_cos`,
//!   which is the crate's own single-precision reduction and Taylor series (private module
//!   `trig`): `libm::sincosf` linked 6.8 KB of code, used about 0.9 KB of stack and cost about
//!   1,500 instructions per call on a Cortex-M4F (its exact reduction runs in soft-float f64),
//!   for 0.5 ulp better accuracy than anything scoring needs. The `micromath` feature swaps in
//!   the `micromath` crate's approximations for `sin_cos` and `atan2` only (about 20
//!   instructions, 1e-3 accurate), while micromath's `exp`, `ln` and `sqrt` are no faster than
//!   libm's and far less accurate (measured below), so those always come from libm, as do
//!   `erf`, `erfc` and `expm1`. Trig is only ever called once per pose or per layout, never per
//!   beam. The f64 helpers always use libm: they serve the EM and host-side code that
//!   accumulates in double precision.
//! - [`wrap_angle`], [`wrap_angle_f64`] (private module `angle`): headings into `[−π, π)`.
//! - [`log_add_exp`], [`log_sum_exp4`] (private module `log_sum_exp`): sums of probabilities
//!   kept as logarithms, for the likelihood field's term, the beam mixture and the localizer's
//!   recovery averages.
//! - The localizer's per-particle functions (crate-private module `fast`): `exp_nonpositive`,
//!   `sin_cos_near` and `wrap_once`, specialized to the filter's ranges, each falling back to
//!   the façade outside them.
//! - `sin_cos_q30` (feature `fixed`, private module `fixed_trig`): integer sine and cosine in
//!   Q2.30 for the fixed-point scorer, re-exported as `fixed_point::sin_cos_q30`.
//!
//! # Accuracy
//!
//! Every function of the module: maximum errors against f64 (std's functions or, for `erf`,
//! `erfc` and the normal masses, the independent f64 series of `host_tests::reference`; the
//! f64 functions against the same, so their rows are as much the reference's error as theirs),
//! measured on every test run by the test in the last column, which asserts them (each bound is
//! the measured maximum rounded up in its second digit). `math_backend` is
//! `host-tests/tests/math_backend.rs`; run it with `--features micromath` for that column. The
//! others are this module's unit tests of the named file (`cargo test -p beamfield --lib
//! math::`; `--features fixed` for `fixed_trig`).
//!
//! | function | domain | error (default backend) | error (`micromath`) | asserted by |
//! |---|---|---|---|---|
//! | [`exp`] | [−80, 80] | 6.9e-8 relative | same (libm) | `math_backend` |
//! | [`ln`] | [1e-30, 1e30] | 3.8e-6 absolute (half an ulp of ln 1e30 ≈ 69) | same (libm) | `math_backend` |
//! | [`sqrt`] | [1e-6, 1e6] | 6.0e-8 relative (correctly rounded) | same (libm) | `math_backend` |
//! | [`sin_cos`] | [−2π, 2π] | 6.2e-8 absolute (own `trig`; 6.3e-8 on [−7, 7]; libm's was 3.0e-8) | 1.1e-3 absolute | `math_backend`, `trig` |
//! | [`atan2`] | radii 0.01, 1, 100 | 2.5e-7 absolute | 2.8e-3 absolute | `math_backend` |
//! | [`erf`] | [−10, 10] | 4.4e-8 absolute | same (libm) | `math_backend` |
//! | [`erfc`] | [−10, 9] | 2.2e-7 relative | same (libm) | `math_backend` |
//! | [`expm1`] | [−20, 20] | 7.6e-8 relative | same (libm) | `math_backend` |
//! | [`floor`] | [−1e6, 1e6] | exact | same (libm) | `math_backend` |
//! | [`normal_cdf`] | [−12, 12] | 1.1e-5 relative (the lower tail: `u/√2` rounds, ×2u² there) | same (libm) | `math_backend` |
//! | [`normal_mass_straddling_zero`] | lo ∈ [−8, 0], hi ∈ [0, 8] | 1.4e-7 relative | same (libm) | `math_backend` |
//! | [`log_add_exp`] | [−40, 40]² and `−∞` | 2.0e-6 absolute (half an ulp of results near 40; 1 ulp) | same (libm) | `math_backend` |
//! | [`log_sum_exp4`] | [−40, 40]⁴, each term `−∞` with p = ¼ | 2.0e-6 absolute (as `log_add_exp`) | same (libm) | `math_backend` |
//! | [`wrap_angle`] | [−100, 100] | 5.3e-6 absolute on the circle (one f32 spacing of the input; exact on [−π, π)) | same | `angle` |
//! | `fast::exp_nonpositive` | [−87, 0] | 2.6e-7 relative (0 below −87.3) | same | `fast` |
//! | `fast::sin_cos_near` | [−16, 16] | 3.7e-7 absolute (the façade's `sin_cos` beyond) | same inside, micromath's beyond | `fast` |
//! | `fast::wrap_once` | [−3π, 3π) | the bits of [`wrap_angle`] (its fallback beyond) | same | `fast` |
//! | `sin_cos_q30` (`fixed`) | I16F16, \|θ\| < 40 | 5.8e-8 absolute (integers; Q2.30 step 9.3e-10) | same | `fixed_trig` |
//! | [`exp_f64`] | [−700, 700] | 2.3e-16 relative | same (libm) | `math_backend` |
//! | [`ln_f64`] | [1e-300, 1e300] | 2.3e-16 relative | same (libm) | `math_backend` |
//! | [`sqrt_f64`] | [1e-300, 1e300] | exact (correctly rounded, as std's) | same (libm) | `math_backend` |
//! | [`expm1_f64`] | [−40, 40] | 2.1e-16 relative | same (libm) | `math_backend` |
//! | [`sin_cos_f64`] | [−2π, 2π] | 1.2e-16 absolute | same (libm) | `math_backend` |
//! | [`atan2_f64`] | radii 0.01, 1, 100 | 4.5e-16 absolute | same (libm) | `math_backend` |
//! | [`erf_f64`] | [−6, 6] | 8.0e-15 absolute (mostly the reference's) | same (libm) | `math_backend` |
//! | [`erfc_f64`] | [−6, 26] | 1.6e-11 relative (the reference's `1 − erf` near 2.5) | same (libm) | `math_backend` |
//! | [`normal_cdf_f64`] | [−37, 8] | 1.8e-11 relative (as `erfc_f64`) | same (libm) | `math_backend` |
//! | [`floor_f64`] | [−1e15, 1e15] | exact | same (libm) | `math_backend` |
//! | [`wrap_angle_f64`] | any | as `wrap_angle` in f64, one f64 spacing of the input (not measured: it is `wrap_angle`'s reference) | same | `angle` (the range) |
//!
//! For the record, micromath's own `exp`, `ln` and `sqrt` measured 2.4e-3 relative, 0.12
//! absolute and 6.1e-2 relative on the same ranges: not usable for a likelihood.

mod angle;
pub(crate) mod fast;
#[cfg(feature = "fixed")]
mod fixed_trig;
mod log_sum_exp;
// With `micromath`, its sin/cos are used instead and this module only runs its tests.
#[cfg_attr(feature = "micromath", allow(dead_code))]
mod trig;

pub use angle::{wrap_angle, wrap_angle_f64};
#[cfg(feature = "fixed")]
pub(crate) use fixed_trig::sat_i32;
#[cfg(feature = "fixed")]
pub use fixed_trig::sin_cos_q30;
pub use log_sum_exp::{log_add_exp, log_sum_exp4};

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
        trig::sin_cos(x)
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
