//! Angle wrapping into `[−π, π)`, in f32 and f64.
//!
//! Contract: the result is in `[−π, π)` for every finite input, equal to the input when it is
//! already there, and differs from the input by a whole number of f32 (f64) turns `TAU`;
//! non-finite input comes back unchanged. No panics, no tables. Uses only this module's
//! siblings (`floor` of the façade) and `libm`.

use core::f32::consts::{PI, TAU};

/// Wraps an angle into `[−π, π)`, radians. Non-finite input comes back unchanged (NaN stays NaN).
///
/// 179° and −179° wrap to values 2° apart: `wrap_angle(a − b)` is the signed shortest
/// difference between two headings.
///
/// Accuracy: exact inside `[−π, π)` (the input itself). Beyond, `a − TAU·⌊(a + π)/TAU⌋` in f32:
/// the product rounds at the size of the input and the f32 `TAU` is 1.7e-7 above 2π, so against
/// the f64 wrap of the same input the error is about one f32 spacing of the input: 5.3e-6
/// measured on `[−100, 100]` rad, where that spacing is 7.6e-6 (this module's test). For
/// `|a| < 3π` (one turn) the subtraction is exact and the error is the `TAU` offset, below 4e-7.
pub fn wrap_angle(angle_rad: f32) -> f32 {
    if !angle_rad.is_finite() {
        return angle_rad;
    }
    if (-PI..PI).contains(&angle_rad) {
        return angle_rad;
    }
    let mut a = angle_rad - TAU * super::floor((angle_rad + PI) / TAU);
    // Rounding can land exactly on +π (or a hair outside); fold it back.
    if a >= PI {
        a -= TAU;
    }
    if a < -PI {
        a += TAU;
    }
    a
}

/// Wraps an angle into `[−π, π)`, radians, in f64. Non-finite input comes back unchanged.
///
/// Accuracy: as [`wrap_angle`], in f64 (`TAU` is 2.4e-16 below 2π).
pub fn wrap_angle_f64(angle_rad: f64) -> f64 {
    use core::f64::consts::{PI, TAU};
    if !angle_rad.is_finite() || (-PI..PI).contains(&angle_rad) {
        return angle_rad;
    }
    let mut a = angle_rad - TAU * libm::floor((angle_rad + PI) / TAU);
    if a >= PI {
        a -= TAU;
    }
    if a < -PI {
        a += TAU;
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_table() {
        let deg = PI / 180.0;
        let cases: [(f32, f32); 7] = [
            (0.0, 0.0),
            (PI, -PI),
            (-PI, -PI),
            (2.5 * PI, 0.5 * PI),
            (179.0 * deg - (-179.0 * deg), -2.0 * deg),
            (TAU + 0.5, 0.5),
            (-TAU - 0.5, -0.5),
        ];
        for (input, want) in cases {
            let got = wrap_angle(input);
            assert!(
                (got - want).abs() < 1e-5,
                "wrap({input}) = {got}, want {want}"
            );
            assert!((-PI..PI).contains(&got));
        }
        assert!(wrap_angle(f32::NAN).is_nan());
        assert_eq!(wrap_angle_f64(f64::INFINITY), f64::INFINITY);
    }

    #[test]
    fn wrap_stays_in_range_for_large_inputs() {
        for k in -1000..1000 {
            let a = k as f32 * 0.731;
            let w = wrap_angle(a);
            assert!((-PI..PI).contains(&w), "{a} -> {w}");
            let w = wrap_angle_f64(f64::from(a));
            assert!((-core::f64::consts::PI..core::f64::consts::PI).contains(&w));
        }
    }

    #[test]
    fn against_f64() {
        // The error against the f64 wrap of the same input, as a distance on the circle (±π
        // and −π are the same angle).
        let circle = |a: f64, b: f64| {
            let d = (a - b).abs();
            d.min(2.0 * core::f64::consts::PI - d)
        };
        let mut worst = 0.0f64;
        let n = 400_000;
        for i in 0..=n {
            let x = -100.0 + 200.0 * (i as f32 / n as f32);
            let want = wrap_angle_f64(f64::from(x));
            worst = worst.max(circle(f64::from(wrap_angle(x)), want));
        }
        println!("wrap_angle: worst {worst:.3e} on [-100, 100]");
        assert!(worst <= 5.4e-6, "{worst}");
    }
}
