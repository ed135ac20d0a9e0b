//! The filter's per-particle elementary functions, specialized to the ranges the localizer
//! (`crate::mcl`) feeds them so they skip the general functions' checks and reductions (the
//! façade serves everything else).
//!
//! Contract: plain f32 arithmetic without fused multiply-adds, so the host and the Cortex-M4F
//! round them alike (the device's track is checked bit-identical with the host's); each falls
//! back to the general function of this module's parent outside its range, so no input is
//! refused; no panics, no tables. Crate-private: their ranges are the filter's, not a general
//! contract. Each function's accuracy is measured by this file's tests (the table in the parent
//! module's docs).

use super::angle::wrap_angle;
use core::f32::consts::{FRAC_2_PI, PI, TAU};

/// `a` wrapped into `[−π, π)` by at most one turn, the same operations as [`wrap_angle`] for
/// `a ∈ [−3π, 3π)` (so the same bits); [`wrap_angle`] beyond.
#[inline]
pub(crate) fn wrap_once(a: f32) -> f32 {
    if a >= PI {
        let b = a - TAU;
        if b < PI {
            return b;
        }
    } else if a < -PI {
        let b = a + TAU;
        if b >= -PI {
            return b;
        }
    } else {
        return a;
    }
    wrap_angle(a)
}

/// `π/2` in two parts: the high part has 7 trailing zero bits, so `k·HI` is exact for
/// `|k| < 128`; `LO` is the f32 nearest `π/2 − HI`.
const FRAC_PI_2_HI: f32 = f32::from_bits(0x3fc9_0f80);
const FRAC_PI_2_LO: f32 = 1.080_433_4e-5;
/// `1.5·2²³`: adding and subtracting it rounds an f32 below 2²² in magnitude to an integer.
const ROUND: f32 = 12_582_912.0;

/// `(sin x, cos x)` for `|x| ≤ 16` (the filter's `θ + δrot1`): `x·2/π` rounded to the nearest
/// integer `k` (the quadrant), reduced in two parts (`r = x − k·π/2`, `|r| ≤ π/4`), then the
/// Taylor polynomials of degree 7 (sine) and 8 (cosine), whose truncation is below 3.2e-7 and
/// 2.5e-8 on `|r| ≤ π/4`. Within 3.7e-7 of the true values (3.61e-7 measured against f64 by
/// this file's test): for a motion sample, a direction error of 4e-7 rad, 0.4 µm per metre
/// driven. `math::sin_cos`
/// beyond 16 and for non-finite `x`.
#[inline]
pub(crate) fn sin_cos_near(x: f32) -> (f32, f32) {
    if x.abs() <= 16.0 {
        // Round to nearest by adding and removing 1.5·2²³ (|q| ≤ 10.2: exact, ties to even).
        let kf = (x * FRAC_2_PI + ROUND) - ROUND;
        let k = kf as i32;
        let r = (x - kf * FRAC_PI_2_HI) - kf * FRAC_PI_2_LO;
        let z = r * r;
        let s = r + r * z * (-1.0 / 6.0 + z * (1.0 / 120.0 + z * (-1.0 / 5_040.0)));
        let c = 1.0 - 0.5 * z + z * z * (1.0 / 24.0 + z * (-1.0 / 720.0 + z * (1.0 / 40_320.0)));
        return match k & 3 {
            0 => (s, c),
            1 => (c, -s),
            2 => (-s, -c),
            _ => (-c, s),
        };
    }
    super::sin_cos(x)
}

/// `ln 2` in two parts (`HI` has 9 trailing zero bits: `k·HI` is exact for `|k| < 512`).
const LN_2_HI: f32 = f32::from_bits(0x3f31_7200);
const LN_2_LO: f32 = 1.428_606_8e-6;
/// Below this, `e^x` is under f32's smallest normal number: the result is 0.
const EXP_UNDERFLOW: f32 = -87.3;

/// `e^x` for `x ≤ 0` (the filter's shifted log-weights): `x = k·ln 2 + r` with `k` the nearest
/// integer to `x/ln 2` (`|r| ≤ ln 2 / 2`, reduced in two parts), `e^r` by its Taylor polynomial
/// of degree 6 (truncation below 1.3e-7 relative), scaled by `2^k` through the exponent bits.
/// Within 2.6e-7 relative of `e^x` (2.53e-7 measured against f64 by this file's test). 0 for
/// `x < −87.3` (and `−∞`), where `e^x` is below the smallest normal f32: such a weight is
/// nothing next to the best particle's 1. `math::exp` for `x > 0` and NaN.
#[inline]
pub(crate) fn exp_nonpositive(x: f32) -> f32 {
    if x < EXP_UNDERFLOW {
        return 0.0;
    }
    if x <= 0.0 {
        let k = (x * core::f32::consts::LOG2_E - 0.5) as i32;
        let kf = k as f32;
        let r = (x - kf * LN_2_HI) - kf * LN_2_LO;
        let p = 1.0
            + r * (1.0
                + r * (0.5
                    + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0 + r * (1.0 / 720.0))))));
        // k ∈ [−126, 0]: 2^k is a normal f32.
        let scale = f32::from_bits(((k + 127) as u32) << 23);
        return p * scale;
    }
    super::exp(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math;

    #[test]
    fn wrap_once_is_wrap_angle() {
        let mut a = -3.0 * PI - 0.5;
        while a < 3.0 * PI + 0.5 {
            assert_eq!(wrap_once(a).to_bits(), wrap_angle(a).to_bits(), "{a}");
            a += 0.001_3;
        }
        for a in [PI, -PI, 3.0 * PI, -3.0 * PI, 100.0, f32::NAN] {
            assert_eq!(wrap_once(a).to_bits(), wrap_angle(a).to_bits(), "{a}");
        }
    }

    #[test]
    fn sin_cos_near_against_f64() {
        let mut worst = 0.0f64;
        let mut x = -16.0f32;
        while x <= 16.0 {
            let (s, c) = sin_cos_near(x);
            let xd = f64::from(x);
            worst = worst
                .max((f64::from(s) - xd.sin()).abs())
                .max((f64::from(c) - xd.cos()).abs());
            x += 0.000_37;
        }
        println!("sin_cos_near: worst {worst:.3e} on [-16, 16]");
        assert!(worst <= 3.7e-7, "{worst}");
        assert!(sin_cos_near(f32::NAN).0.is_nan());
        assert_eq!(sin_cos_near(20.0), math::sin_cos(20.0));
    }

    #[test]
    fn exp_nonpositive_against_f64() {
        let mut worst = 0.0f64;
        let mut x = -87.0f32;
        while x <= 0.0 {
            let want = f64::from(x).exp();
            worst = worst.max((f64::from(exp_nonpositive(x)) - want).abs() / want);
            x += 0.000_71;
        }
        println!("exp_nonpositive: worst relative {worst:.3e} on [-87, 0]");
        assert!(worst <= 2.6e-7, "{worst}");
        assert_eq!(exp_nonpositive(0.0), 1.0);
        assert_eq!(exp_nonpositive(-0.0), 1.0);
        assert_eq!(exp_nonpositive(f32::NEG_INFINITY), 0.0);
        assert_eq!(exp_nonpositive(-100.0), 0.0);
        assert_eq!(exp_nonpositive(1.0), math::exp(1.0));
        assert!(exp_nonpositive(f32::NAN).is_nan());
    }
}
