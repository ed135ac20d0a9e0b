//! `e^x` and `e^x − 1` in f64 for the E-step, as plain inline arithmetic instead of a libm call.
//!
//! libm's `exp` (fdlibm's algorithm) evaluates a rational approximation (one division) behind a
//! function call; the E-step makes about two of them per reading and per pass, and they were
//! half of the EM time. Here: the usual reduction `x = k·ln 2 + r`, `|r| ≤ ln 2 / 2`, with
//! `ln 2` split in two so that `x − k·ln2_hi` is exact (fdlibm's split), then
//! `e^r ≈ 1 + (r + r²·q(r))` with `q` a degree-9 polynomial fitted to `(e^r − 1 − r)/r²`
//! on `|r| ≤ ln 2 / 2` (so that only the last addition rounds at the size of the result), and
//! scaled by `2^k` built from its bits (exact). The result is within 1 ulp of `e^x` (the unit
//! tests check it against libm over the whole fast range). Outside `|x| ≤ 708` (overflow,
//! subnormal results, NaN) the libm call is kept.
//!
//! The coefficients: `mpmath.chebyfit(q, [-ln2/2, ln2/2], 10)` at 50 digits (a Chebyshev fit,
//! near-minimax), rounded to f64; with the rounded coefficients, `1 + r + r²·q(r)` is within
//! 1.6e-17 (0.14·2⁻⁵³) relative of `e^r` on a 4,001-point grid of the interval, evaluated at
//! 50 digits. It replaced the Taylor series to degree 13 (12 coefficients, truncation error
//! 4.2e-18): two products and two sums fewer per `e^x`.

use crate::math;

/// `log₂ e`.
const LOG2E: f64 = core::f64::consts::LOG2_E;
/// `1.5·2⁵²`: adding and subtracting it rounds an f64 of magnitude below 2⁵¹ to the nearest
/// integer (round to nearest, as IEEE arithmetic does by default).
const ROUND_SHIFT: f64 = 6_755_399_441_055_744.0;
/// `ln 2` split as `LN2_HI + LN2_LO` (fdlibm's split): `LN2_HI` = 0x3FE62E42FEE00000 has 32
/// significant bits (its low 21 fraction bits are 0), so `k·LN2_HI` is exact for any integer
/// `|k| < 2²¹` (6.9314718036912382e-1).
pub(crate) const LN2_HI: f64 = f64::from_bits(0x3FE6_2E42_FEE0_0000);
/// The rest of `ln 2` (1.9082149292705877e-10).
pub(crate) const LN2_LO: f64 = f64::from_bits(0x3DEA_39EF_3579_3C76);
/// Largest `|x|` of the inline path: `e^{±708}` and the scale `2^k`, `|k| ≤ 1022`, are normal.
const FAST_LIMIT: f64 = 708.0;

/// `q(r) ≈ (e^r − 1 − r)/r²` on `|r| ≤ ln 2 / 2`: coefficients of `r⁰ … r⁹`, a Chebyshev fit
/// (near-minimax) computed with mpmath at 50 digits and rounded to f64 (see the module docs).
const Q0: f64 = f64::from_bits(0x3FE0_0000_0000_0001); // 0.5000000000000001
const Q1: f64 = f64::from_bits(0x3FC5_5555_5555_5556); // 0.16666666666666669
const Q2: f64 = f64::from_bits(0x3FA5_5555_5555_3D68); // 0.041666666666624164
const Q3: f64 = f64::from_bits(0x3F81_1111_1111_09B5); // 0.008333333333330065
const Q4: f64 = f64::from_bits(0x3F56_C16C_1788_9EF1); // 0.0013888888917196719
const Q5: f64 = f64::from_bits(0x3F2A_01A0_1A7C_2EFE); // 0.00019841269863040545
const Q6: f64 = f64::from_bits(0x3EFA_019B_9149_A41C); // 2.4801521322368692e-05
const Q7: f64 = f64::from_bits(0x3EC7_1DE0_DB2F_6B19); // 2.7557268480310024e-06
const Q8: f64 = f64::from_bits(0x3E92_8917_C89A_43A7); // 2.7620075879983367e-07
const Q9: f64 = f64::from_bits(0x3E5A_F389_ECFC_4B9C); // 2.5100375832561234e-08

/// `t = 1.5·2⁵² + k` with `k = round(x / ln 2)` exactly (|k| ≤ 1022 for `|x| ≤ FAST_LIMIT`): an
/// f64 in [2⁵², 2⁵³) whose fraction bits are 2⁵¹ + k, so the low 12 bits of t's bits + 1023
/// are k + 1023 (no carry leaves them); and the reduced argument `r = x − k·ln 2`.
#[inline(always)]
fn reduce(x: f64) -> (f64, f64) {
    let t = x * LOG2E + ROUND_SHIFT;
    let kf = t - ROUND_SHIFT;
    (t, (x - kf * LN2_HI) - kf * LN2_LO)
}

/// `e^r` on the reduced range: `1 + r + r²·q(r)`, q by Estrin's scheme (short dependency
/// chains).
#[inline(always)]
fn poly(r: f64) -> f64 {
    let r2 = r * r;
    let r4 = r2 * r2;
    let r8 = r4 * r4;
    let q = (Q0 + r * Q1)
        + r2 * (Q2 + r * Q3)
        + r4 * ((Q4 + r * Q5) + r2 * (Q6 + r * Q7))
        + r8 * (Q8 + r * Q9);
    1.0 + (r + r2 * q)
}

/// `2^k` from [`reduce`]'s `t`: |k| ≤ 1022, so the biased exponent k + 1023 is in 1..=2045, a
/// normal number, built from t's bits (shifting left by 52 keeps exactly those 12 low bits; no
/// float-to-int conversion).
#[inline(always)]
fn scale(t: f64) -> f64 {
    f64::from_bits(t.to_bits().wrapping_add(1023) << 52)
}

/// `e^x`, within 1 ulp.
#[inline]
pub(crate) fn exp(x: f64) -> f64 {
    // NaN fails the comparison too, and goes to libm.
    let inline = x.abs() <= FAST_LIMIT;
    if !inline {
        return math::exp_f64(x);
    }
    let (t, r) = reduce(x);
    poly(r) * scale(t)
}

/// `[e^a, e^b]`: the same operations as [`exp`] on two lanes side by side (bit for bit the
/// same results), written so that the compiler can keep both lanes in one SIMD register.
#[inline]
pub(crate) fn exp_pair([a, b]: [f64; 2]) -> [f64; 2] {
    if !(a.abs() <= FAST_LIMIT && b.abs() <= FAST_LIMIT) {
        return [exp(a), exp(b)];
    }
    let [(ta, ra), (tb, rb)] = [reduce(a), reduce(b)];
    let p = [ra, rb].map(poly);
    [p[0] * scale(ta), p[1] * scale(tb)]
}

/// `e^x − 1` for `x ≥ 0`. From `x ≥ ln 2` on, `e^x ≥ 2` and subtracting 1 loses no accuracy
/// (within 2 ulp); below that libm's `expm1` (which avoids the cancellation).
#[inline]
pub(crate) fn expm1_nonneg(x: f64) -> f64 {
    if x >= core::f64::consts::LN_2 {
        exp(x) - 1.0
    } else {
        math::expm1_f64(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in ulps between two positive finite f64.
    fn ulps(a: f64, b: f64) -> u64 {
        a.to_bits().abs_diff(b.to_bits())
    }

    /// Within 1 ulp of libm's `exp` (itself within 1 ulp of `e^x`) over the whole inline range,
    /// on a dense grid plus the reduction's boundaries `x = (k + ½)·ln 2`.
    #[test]
    fn exp_matches_libm() {
        let mut worst = 0u64;
        let n = 2_000_000;
        for i in 0..=n {
            let x = -FAST_LIMIT + 2.0 * FAST_LIMIT * (i as f64) / (n as f64);
            worst = worst.max(ulps(exp(x), libm::exp(x)));
        }
        for k in -1021..1021 {
            let x = (f64::from(k) + 0.5) * core::f64::consts::LN_2;
            for y in [
                x,
                f64::from_bits(x.to_bits() + 1),
                f64::from_bits(x.to_bits() - 1),
            ] {
                worst = worst.max(ulps(exp(y), libm::exp(y)));
            }
        }
        for x in [
            0.0, -0.0, 1e-300, -1e-300, 1e-17, -1e-17, 0.5, -0.5, 1.0, -1.0,
        ] {
            worst = worst.max(ulps(exp(x), libm::exp(x)));
        }
        assert!(worst <= 1, "worst {worst} ulp");
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(710.0), f64::INFINITY);
        assert_eq!(exp(-746.0), 0.0);
        assert_eq!(exp(-709.0).to_bits(), libm::exp(-709.0).to_bits());
        assert!(exp(f64::NAN).is_nan());
    }

    /// [`exp_pair`] is [`exp`] on each lane, bit for bit, inside and outside the inline range
    /// (the lanes are independent: every pairing of a grid of arguments).
    #[test]
    fn exp_pair_is_exp_per_lane() {
        let mut xs: Vec<f64> = (0..=4_000)
            .map(|i| -720.0 + 1_440.0 * f64::from(i) / 4_000.0)
            .collect();
        xs.extend([0.0, -0.0, 1e-300, 708.0, -708.0, 709.5, -745.0, f64::NAN]);
        let mut checked = 0u64;
        for (i, &a) in xs.iter().enumerate() {
            for &b in xs.iter().skip(i % 97).step_by(97) {
                let [ea, eb] = exp_pair([a, b]);
                for (got, want) in [(ea, exp(a)), (eb, exp(b))] {
                    assert!(
                        got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                        "exp_pair([{a}, {b}])"
                    );
                }
                checked += 1;
            }
        }
        assert!(checked > 100_000, "{checked}");
    }

    /// Within 2 ulp of libm's `expm1` from ln 2 on, identical below.
    #[test]
    fn expm1_matches_libm() {
        let mut worst = 0u64;
        let n = 1_000_000;
        for i in 0..=n {
            let x = 720.0 * (i as f64) / (n as f64);
            let (a, b) = (expm1_nonneg(x), libm::expm1(x));
            if b.is_finite() {
                worst = worst.max(ulps(a, b));
            } else {
                assert_eq!(a, b);
            }
            if x < core::f64::consts::LN_2 {
                assert_eq!(a.to_bits(), b.to_bits());
            }
        }
        assert!(worst <= 2, "worst {worst} ulp");
    }
}
