//! Measures the math façade's error against f64 (std) and checks it against the bounds written
//! in `src/math.rs`. Run with `--features micromath` to measure that backend.
//!
//! Each bound is the measured maximum (2026-11-23) rounded up in its second digit: the test pins
//! the documented figures, so a backend change that worsens them fails here.

use beamfield::math;

struct Case {
    name: &'static str,
    /// Documented bound for (libm, micromath).
    bound: (f64, f64),
    /// true: relative error; false: absolute.
    relative: bool,
    worst: f64,
}

fn bound(c: &Case) -> f64 {
    if cfg!(feature = "micromath") {
        c.bound.1
    } else {
        c.bound.0
    }
}

fn record(c: &mut Case, got: f32, want: f64) {
    let err = if c.relative {
        ((f64::from(got) - want) / want).abs()
    } else {
        (f64::from(got) - want).abs()
    };
    if err > c.worst || err.is_nan() {
        c.worst = if err.is_nan() { f64::INFINITY } else { err };
    }
}

/// `n` points spread over [a, b], exactly representable in f32.
fn grid(a: f32, b: f32, n: usize) -> impl Iterator<Item = f32> {
    (0..=n).map(move |i| a + (b - a) * (i as f32 / n as f32))
}

#[test]
fn facade_errors_within_documented_bounds() {
    let mut cases = vec![];

    let mut c = Case {
        name: "exp [-80,80]",
        bound: (7e-8, 7e-8),
        relative: true,
        worst: 0.0,
    };
    for x in grid(-80.0, 80.0, 200_000) {
        record(&mut c, math::exp(x), f64::from(x).exp());
    }
    cases.push(c);

    let mut c = Case {
        name: "ln [1e-30,1e30]",
        bound: (3.9e-6, 3.9e-6),
        relative: false,
        worst: 0.0,
    };
    for e in grid(-30.0, 30.0, 200_000) {
        let x = 10f32.powf(e);
        record(&mut c, math::ln(x), f64::from(x).ln());
    }
    cases.push(c);

    let mut c = Case {
        name: "sqrt [1e-6,1e6]",
        bound: (6e-8, 6e-8),
        relative: true,
        worst: 0.0,
    };
    for e in grid(-6.0, 6.0, 100_000) {
        let x = 10f32.powf(e);
        record(&mut c, math::sqrt(x), f64::from(x).sqrt());
    }
    cases.push(c);

    let mut c = Case {
        name: "sin_cos [-2pi,2pi]",
        // The crate's own sin_cos (src/trig.rs, 2026-11-29: 6.33e-8 measured); libm's sincosf,
        // used before, measured 3.0e-8 here.
        bound: host_tests::reference_backend::SIN_COS_ABS_BOUNDS,
        relative: false,
        worst: 0.0,
    };
    for x in grid(-6.3, 6.3, 200_000) {
        let (s, co) = math::sin_cos(x);
        record(&mut c, s, f64::from(x).sin());
        record(&mut c, co, f64::from(x).cos());
    }
    cases.push(c);

    let mut c = Case {
        name: "atan2",
        bound: (2.5e-7, 2.9e-3),
        relative: false,
        worst: 0.0,
    };
    for a in grid(-3.1, 3.1, 20_000) {
        for r in [0.01f32, 1.0, 100.0] {
            let (y, x) = (r * a.sin(), r * a.cos());
            record(&mut c, math::atan2(y, x), f64::from(y).atan2(f64::from(x)));
        }
    }
    cases.push(c);

    // erfc: relative where the value is representable; reference from the independent
    // f64 series/continued fraction of host-tests (not libm).
    let mut c = Case {
        name: "erfc [-10,10]",
        bound: (2.2e-7, 2.2e-7),
        relative: true,
        worst: 0.0,
    };
    for x in grid(-10.0, 9.0, 100_000) {
        record(
            &mut c,
            math::erfc(x),
            host_tests::reference::erfc(f64::from(x)),
        );
    }
    cases.push(c);

    let mut c = Case {
        name: "normal_mass [lo<=0<=hi]",
        bound: (1.4e-7, 1.4e-7),
        relative: true,
        worst: 0.0,
    };
    for lo in grid(-8.0, 0.0, 300) {
        for hi in grid(0.0, 8.0, 300) {
            if lo == 0.0 && hi == 0.0 {
                continue;
            }
            let want = host_tests::reference::phi(f64::from(hi))
                - host_tests::reference::phi(f64::from(lo));
            record(&mut c, math::normal_mass_straddling_zero(lo, hi), want);
        }
    }
    cases.push(c);

    let backend = if cfg!(feature = "micromath") {
        "micromath"
    } else {
        "libm"
    };
    let mut failed = vec![];
    for c in &cases {
        println!(
            "{backend:9} {:24} max {} error {:.3e} (documented bound {:.1e})",
            c.name,
            if c.relative { "relative" } else { "absolute" },
            c.worst,
            bound(c)
        );
        if c.worst.partial_cmp(&bound(c)) != Some(std::cmp::Ordering::Less) && c.worst != bound(c) {
            failed.push(c.name);
        }
    }
    assert!(failed.is_empty(), "over the documented bound: {failed:?}");
}
