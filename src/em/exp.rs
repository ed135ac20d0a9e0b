//! `e^x` and `e^x − 1` in f64 for the E-step, as plain inline arithmetic instead of a libm call.
//!
//! libm's `exp` (fdlibm's algorithm) evaluates a rational approximation (one division) behind a
//! function call; the E-step makes about two of them per reading and per pass, and they were
//! half of the EM time. Here: the usual reduction `x = k·ln 2 + r`, `|r| ≤ ln 2 / 2`, with
//! `ln 2` split in two so that `x − k·ln2_hi` is exact (fdlibm's split), then the Taylor series
//! of `e^r` to degree 13 (truncation error `r¹⁴/14! < 4.2e-18 < 2⁻⁵⁷` relative for
//! `|r| ≤ 0.3466`), evaluated as `1 + (r + r²·q(r))` so that only the last addition rounds at
//! the size of the result, and scaled by `2^k` built from its bits (exact). The result is
//! within 1 ulp of `e^x` (the unit tests check it against libm over the whole fast range).
//! Outside `|x| ≤ 708` (overflow, subnormal results, NaN) the libm call is kept.

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

/// `1/k!`, k = 2..=13 (each a correctly rounded f64 quotient of two exact integers).
const C2: f64 = 1.0 / 2.0;
const C3: f64 = 1.0 / 6.0;
const C4: f64 = 1.0 / 24.0;
const C5: f64 = 1.0 / 120.0;
const C6: f64 = 1.0 / 720.0;
const C7: f64 = 1.0 / 5_040.0;
const C8: f64 = 1.0 / 40_320.0;
const C9: f64 = 1.0 / 362_880.0;
const C10: f64 = 1.0 / 3_628_800.0;
const C11: f64 = 1.0 / 39_916_800.0;
const C12: f64 = 1.0 / 479_001_600.0;
const C13: f64 = 1.0 / 6_227_020_800.0;

/// `e^x`, within 1 ulp.
#[inline]
pub(crate) fn exp(x: f64) -> f64 {
    // NaN fails the comparison too, and goes to libm.
    let inline = x.abs() <= FAST_LIMIT;
    if !inline {
        return math::exp_f64(x);
    }
    // t = 1.5·2⁵² + k exactly (|k| ≤ 1022): an f64 in [2⁵², 2⁵³), whose fraction bits are
    // 2⁵¹ + k, so the low 12 bits of t's bits + 1023 are k + 1023 (no carry leaves them).
    let t = x * LOG2E + ROUND_SHIFT;
    let kf = t - ROUND_SHIFT;
    let r = (x - kf * LN2_HI) - kf * LN2_LO;
    let r2 = r * r;
    let r4 = r2 * r2;
    let r8 = r4 * r4;
    // q(r) = Σ_{k=2}^{13} r^{k−2}/k!, by Estrin's scheme (short dependency chains).
    let q = (C2 + r * C3)
        + r2 * (C4 + r * C5)
        + r4 * ((C6 + r * C7) + r2 * (C8 + r * C9))
        + r8 * ((C10 + r * C11) + r2 * (C12 + r * C13));
    let p = 1.0 + (r + r2 * q);
    // |k| ≤ 1022 here, so the biased exponent k + 1023 is in 1..=2045: a normal 2^k, built
    // from t's bits (shifting left by 52 keeps exactly those 12 low bits; no float-to-int
    // conversion).
    let scale = f64::from_bits(t.to_bits().wrapping_add(1023) << 52);
    p * scale
}

/// `[e^a, e^b]`: the same operations as [`exp`] on two lanes side by side (bit for bit the
/// same results), written so that the compiler can keep both lanes in one SIMD register.
#[inline]
pub(crate) fn exp_pair([a, b]: [f64; 2]) -> [f64; 2] {
    if !(a.abs() <= FAST_LIMIT && b.abs() <= FAST_LIMIT) {
        return [exp(a), exp(b)];
    }
    let x = [a, b];
    let t = x.map(|x| x * LOG2E + ROUND_SHIFT);
    let kf = t.map(|t| t - ROUND_SHIFT);
    let r = [
        (x[0] - kf[0] * LN2_HI) - kf[0] * LN2_LO,
        (x[1] - kf[1] * LN2_HI) - kf[1] * LN2_LO,
    ];
    let lane = |r: f64| {
        let r2 = r * r;
        let r4 = r2 * r2;
        let r8 = r4 * r4;
        let q = (C2 + r * C3)
            + r2 * (C4 + r * C5)
            + r4 * ((C6 + r * C7) + r2 * (C8 + r * C9))
            + r8 * ((C10 + r * C11) + r2 * (C12 + r * C13));
        1.0 + (r + r2 * q)
    };
    let p = r.map(lane);
    let scale = t.map(|t| f64::from_bits(t.to_bits().wrapping_add(1023) << 52));
    [p[0] * scale[0], p[1] * scale[1]]
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
