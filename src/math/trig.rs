//! `sin` and `cos` together in single precision, small and stack-light, for once-per-pose use.
//!
//! Why not `libm::sincosf`: on a Cortex-M4F it links 6.8 KB of code (its exact reduction for
//! huge arguments runs in soft-float f64), uses about 0.9 KB of stack and costs about 1,500
//! instructions per call. Scoring calls it once per pose, so it was most of a pose's fixed cost
//! and most of the scoring core's flash (`cargo xtask budgets`). This one costs a few dozen
//! single-precision instructions and no stack beyond registers.
//!
//! Method: `k = round(x · 2/π)`, `r = x − k·π/2` in f32 with π/2 split in three parts (the first
//! two carry 12 significant bits, so `k·HI` and `k·MID` are exact while `|k| < 4096`), then the
//! Taylor series of `sin r` to `r⁹` and `cos r` to `r¹⁰` on `|r| ≤ π/4` (truncation below
//! 1.8e-9), and the quadrant `k mod 4` picks signs and swaps.
//!
//! Contract: f32 arithmetic only (no f64, no tables, no stack beyond registers), every input
//! accepted, no panics. Accuracy (asserted against f64 by this file's test and by
//! `host-tests/tests/math_backend.rs`): see [`sin_cos`].

/// π/2, high part: 3217/2048, 12 significant bits.
const FRAC_PI_2_HI: f32 = 3_217.0 / 2_048.0;
/// π/2 − HI, its first 12 significant bits: −2391 · 2⁻²⁹.
const FRAC_PI_2_MID: f32 = -2_391.0 / 536_870_912.0;
/// π/2 − HI − MID = −8.7055157e-10, rounded to f32 (bit pattern, to state it exactly).
const FRAC_PI_2_LO: f32 = f32::from_bits(0xb06f_4b9f);
/// From here on f32 values are at least 2 rad apart: no angle information is left.
const NO_ANGLE_LEFT: f32 = 16_777_216.0;

/// `(sin x, cos x)` for `x` in radians.
///
/// Measured maximum absolute error against f64: 6.33e-8 on `[−7, 7]` (this module's test) and
/// on `[−2π, 2π]` (host-tests `math_backend`), 1.06 f32 ulp of values near 0.7, where `r` itself
/// carries up to half an ulp of rounding. `libm::sincosf` is correctly rounded (3.0e-8 on the
/// same grid); the difference moves a beam endpoint 80 m away by 2.7 µm.
///
/// For `|x| > 6,434` rad (`|k| ≥ 4,096`) the products `k·HI`, `k·MID` round, which adds at most
/// about one f32 spacing of `x` (4.9e-4 rad at 6,434; the test checks up to 20,000 rad). At
/// `|x| ≥ 2²⁴` rad, where neighbouring f32 values are 2 rad or more apart, the result is the
/// arbitrary but valid `(0, 1)`. Non-finite `x` gives `(NaN, NaN)`. No panics, no tables, no
/// f64, no stack beyond registers.
// Not inlined: a few dozen instructions once per pose, where inlining at every call site
// cost about 250 bytes of flash each (`cargo xtask budgets`).
#[inline(never)]
pub fn sin_cos(x: f32) -> (f32, f32) {
    if !x.is_finite() {
        return (f32::NAN, f32::NAN);
    }
    if x.abs() >= NO_ANGLE_LEFT {
        return (0.0, 1.0);
    }
    let q = x * core::f32::consts::FRAC_2_PI;
    // Round to nearest (ties away); |q| < 1.1e7 < 2^31, so the conversion cannot saturate.
    let k = if q >= 0.0 {
        (q + 0.5) as i32
    } else {
        (q - 0.5) as i32
    };
    let kf = k as f32;
    let r = ((x - kf * FRAC_PI_2_HI) - kf * FRAC_PI_2_MID) - kf * FRAC_PI_2_LO;
    let z = r * r;
    // sin r = r + r·z·(−1/6 + z·(1/120 + z·(−1/5040 + z/362880)))
    let ps = -1.0 / 6.0 + z * (1.0 / 120.0 + z * (-1.0 / 5_040.0 + z * (1.0 / 362_880.0)));
    let s = r + r * z * ps;
    // cos r = 1 − z/2 + z²·(1/24 + z·(−1/720 + z·(1/40320 − z/3628800)))
    let pc = 1.0 / 24.0 + z * (-1.0 / 720.0 + z * (1.0 / 40_320.0 + z * (-1.0 / 3_628_800.0)));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    // (1 − w) − hz recovers the rounding error of w exactly (Sterbenz), as in fdlibm's cos.
    let c = w + (((1.0 - w) - hz) + z * z * pc);
    match k & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quadrants_and_special_values() {
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        let (s, c) = sin_cos(core::f32::consts::FRAC_PI_2);
        assert!((s - 1.0).abs() < 1e-7 && c.abs() < 1e-7);
        let (s, c) = sin_cos(-core::f32::consts::PI);
        assert!(s.abs() < 1e-7 && (c + 1.0).abs() < 1e-7);
        let (s, c) = sin_cos(f32::NAN);
        assert!(s.is_nan() && c.is_nan());
        let (s, c) = sin_cos(f32::INFINITY);
        assert!(s.is_nan() && c.is_nan());
        assert_eq!(sin_cos(f32::MAX), (0.0, 1.0));
        assert_eq!(sin_cos(-16_777_216.0), (0.0, 1.0));
    }

    #[test]
    fn against_f64_everywhere_it_is_used() {
        let mut worst = 0.0f64;
        let mut worst_far = 0.0f64;
        let n = 400_000;
        for i in 0..=n {
            let x = -7.0 + 14.0 * (i as f32 / n as f32);
            let (s, c) = sin_cos(x);
            let xd = f64::from(x);
            worst = worst
                .max((f64::from(s) - xd.sin()).abs())
                .max((f64::from(c) - xd.cos()).abs());
        }
        let far = (0..=n)
            .map(|i| -20_000.0 + 40_000.0 * (i as f32 / n as f32))
            .chain((0..=1_000).map(|i| -1.6e7 + 3.2e7 * (i as f32 / 1_000.0)));
        for x in far {
            let (s, c) = sin_cos(x);
            let xd = f64::from(x);
            let e = (f64::from(s) - xd.sin())
                .abs()
                .max((f64::from(c) - xd.cos()).abs());
            // Allowed: the f32 spacing of x there (the fold's error is at most half of it) plus
            // the near-zone bound.
            let ulp = f64::from(f32::from_bits(x.abs().to_bits() + 1) - x.abs());
            worst_far = worst_far.max(e / (ulp + 6.4e-8));
        }
        println!("sin_cos: worst {worst:.3e} on [-7, 7]; far zone ratio {worst_far:.3}");
        assert!(worst <= 6.4e-8, "{worst}");
        assert!(worst_far <= 1.0, "{worst_far}");
    }
}
