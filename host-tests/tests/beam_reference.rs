//! The crate's f32 beam mixture against the independent f64 reference (docs/models.md#mixture).
//!
//! # Tolerance table (derived, not tuned)
//! Inputs are drawn as f32 and handed to both sides exactly, so input rounding is no error
//! source. The f32 side then rounds `d = (z − z*)·(1/σ)` with a relative error of about
//! 2 ulp (≤ 2.4e-7), so `½d²` carries ≤ 4.8e-7·½d² absolute error; every other step (η through
//! erf, expm1, one exp, one ln, four products) adds a few ulp relative (≤ 1e-6) to the density,
//! i.e. ≤ 1e-6 absolute to its log.
//!
//! | quantity | tolerance |
//! |---|---|
//! | per-beam `ln p(z|z*)` | `2e-6 + 1e-6·|ln p|` absolute (`½d² ≤ |ln p| + ln terms`) |
//! | unweighted component density, where `½d² ≤ 20` | `1e-5` relative |
//! | scan sum of K beams | Σ per-beam tolerances + `K·6e-8·Σ|ln p|` (f32 summation) |
//! | ∫ p_hit over [0, z_max], ∫ p_short over [0, z*] | `2e-5` absolute (density ≤ 1e-5 relative, quadrature error checked ≤ 1e-8 by refinement) |

use beamfield::{BeamIntrinsics, BeamModel, Scan, BEAM_LOG_FLOOR};
use host_tests::reference::{self as r, Intrinsics};
use proptest::prelude::*;

fn crate_model(p: &Intrinsics) -> BeamModel {
    BeamModel::new(
        BeamIntrinsics::new(
            p.z_hit as f32,
            p.z_short as f32,
            p.z_max as f32,
            p.z_rand as f32,
            p.sigma_hit as f32,
            p.lambda_short as f32,
            p.max_range as f32,
        )
        .expect("valid intrinsics"),
    )
}

fn toy() -> Intrinsics {
    Intrinsics {
        z_hit: 0.25,
        z_short: 0.25,
        z_max: 0.25,
        z_rand: 0.25,
        sigma_hit: 1.0,
        lambda_short: 0.5,
        max_range: 10.0,
    }
}

fn beam_tol(reference: f64) -> f64 {
    2e-6 + 1e-6 * reference.abs()
}

/// Thrun Table 6.1: the components and mixture of z = 4.5, and one textbook EM step, to 1e-6.
#[test]
fn worked_example_to_1e6() {
    let p = toy();
    let m = crate_model(&p);
    let c = m.components(4.5, 5.0).unwrap();
    assert!(
        (f64::from(c.hit) - 0.352_066).abs() < 1e-6,
        "p_hit {}",
        c.hit
    );
    assert!(
        (f64::from(c.short) - 0.057_412).abs() < 1e-6,
        "p_short {}",
        c.short
    );
    assert_eq!(c.max, 0.0);
    assert!((f64::from(c.rand) - 0.1).abs() < 1e-7);
    assert!((f64::from(m.beam_likelihood(4.5, 5.0)) - 0.127_369).abs() < 1e-6);

    // The f64 reference's textbook EM step reproduces docs/models.md#mixture, including the
    // corrected λ = 0.283739 (the chapter's 0.283737 is a misprint, docs/models.md#mixture).
    let z = [4.5, 5.0, 3.0, 7.0, 10.0];
    let zs = [5.0; 5];
    let (next, ll_before) = r::em_step_textbook(&p, &z, &zs);
    let want = [
        (ll_before, -2.275_038, "mean ll"),
        (next.z_hit, 0.394_282, "z_hit"),
        (next.z_short, 0.127_210, "z_short"),
        (next.z_max, 0.200_000, "z_max"),
        (next.z_rand, 0.278_508, "z_rand"),
        (next.sigma_hit, 1.093_905, "sigma"),
        (next.lambda_short, 0.283_739, "lambda"),
    ];
    for (got, w, name) in want {
        assert!((got - w).abs() < 1e-6, "{name}: {got} vs {w}");
    }
    // And it is *not* the misprinted value.
    assert!((next.lambda_short - 0.283_737).abs() > 1e-6);

    // The crate's mean log-likelihood of the five beams agrees with the reference's.
    let scan = Scan::<5>::from_ranges(&[4.5, 5.0, 3.0, 7.0, 10.0]).unwrap();
    let s = m.scan_log_likelihood(&scan, &[5.0; 5]);
    assert_eq!(s.scored, 5);
    assert!((f64::from(s.log_likelihood) / 5.0 - ll_before).abs() < 1e-6);
}

/// Every row of the chapter's component table, crate vs reference (the chapter drops η_hit
/// there, so its printed p_hit differs from the exact one in the 6th decimal; we compare with
/// the exact reference instead).
#[test]
fn worked_example_component_table() {
    let p = toy();
    let m = crate_model(&p);
    for z in [4.5f32, 5.0, 3.0, 7.0, 10.0] {
        let c = m.components(z, 5.0).unwrap();
        let want = r::components(&p, f64::from(z), 5.0).unwrap();
        let got = [c.hit, c.short, c.max, c.rand].map(f64::from);
        for k in 0..4 {
            assert!(
                (got[k] - want[k]).abs() <= 1e-5 * want[k].abs() + 1e-12,
                "z={z} component {k}: {} vs {}",
                got[k],
                want[k]
            );
        }
    }
}

/// Valid intrinsics: weights from four uniforms (each sometimes exactly 0), normalized in f32,
/// then rebalanced so that they pass the crate's 1e-4 sum check.
fn intrinsics() -> impl Strategy<Value = Intrinsics> {
    (
        prop::array::uniform4(prop_oneof![1 => Just(0.0f32), 6 => 0.0f32..1.0]),
        0.01f32..5.0,
        0.01f32..10.0,
        0.5f32..100.0,
    )
        .prop_filter("some weight", |(w, ..)| w.iter().sum::<f32>() > 0.05)
        .prop_map(|(w, sigma, lambda, zmax)| {
            let s: f32 = w.iter().sum();
            let w = w.map(|x| x / s);
            Intrinsics {
                z_hit: f64::from(w[0]),
                z_short: f64::from(w[1]),
                z_max: f64::from(w[2]),
                z_rand: f64::from(w[3]),
                sigma_hit: f64::from(sigma),
                lambda_short: f64::from(lambda),
                max_range: f64::from(zmax),
            }
        })
}

/// A reading relative to the range limit, with the special values mixed in.
fn reading(zmax: f32) -> impl Strategy<Value = f32> {
    prop_oneof![
        8 => (0.0f32..1.0).prop_map(move |u| u * zmax),
        1 => Just(0.0f32),
        1 => Just(zmax),
        1 => (1.0f32..1.5).prop_map(move |u| u * zmax),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NAN),
        1 => -5.0f32..-1e-6,
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]

    /// f32 crate vs f64 reference, per beam, over random valid inputs.
    #[test]
    fn per_beam_log_likelihood_matches_reference(
        (p, z, zs) in intrinsics().prop_flat_map(|p| {
            let zmax = p.max_range as f32;
            (Just(p), reading(zmax), prop_oneof![9 => (0.0f32..1.0).prop_map(move |u| u * zmax), 1 => Just(0.0f32), 1 => Just(zmax)])
        })
    ) {
        let m = crate_model(&p);
        let got = m.beam_log_likelihood(z, zs);
        let want = r::beam_log_likelihood(&p, f64::from(z), f64::from(zs));
        match (got, want) {
            (None, None) => {}
            (Some(g), Some(w)) => {
                prop_assert!(!g.is_nan());
                prop_assert!(g >= BEAM_LOG_FLOOR);
                let g = f64::from(g);
                prop_assert!((g - w).abs() <= beam_tol(w), "z={z} z*={zs} {p:?}: {g} vs {w}");
            }
            _ => prop_assert!(false, "validity differs for z={z}: {got:?} vs {want:?}"),
        }
    }

    /// Unweighted components, relative, where the Gaussian exponent is moderate.
    #[test]
    fn components_match_reference(
        (p, t, v) in (intrinsics(), -6.3f32..6.3, 0.0f32..1.0)
    ) {
        // z within ±6.3σ of z* (so ½d² ≤ 20), kept inside [0, z_max).
        let zmax = p.max_range as f32;
        let zs = v * zmax;
        let z = (zs + t * p.sigma_hit as f32).clamp(0.0, zmax * (1.0 - 1e-6));
        let d = (f64::from(z) - f64::from(zs)) / p.sigma_hit;
        prop_assert!(0.5 * d * d <= 20.0 + 1e-3);
        let c = crate_model(&p).components(z, zs).unwrap();
        let want = r::components(&p, f64::from(z), f64::from(zs)).unwrap();
        let got = [c.hit, c.short, c.max, c.rand].map(f64::from);
        for k in 0..4 {
            prop_assert!((got[k] - want[k]).abs() <= 1e-5 * want[k].abs() + 1e-30,
                "component {k}: {} vs {} (z={z}, z*={zs}, {p:?})", got[k], want[k]);
        }
    }

    /// A whole scan: the f32 sum stays within the summed per-beam budget.
    #[test]
    fn scan_sum_matches_reference(
        (p, zs) in intrinsics().prop_flat_map(|p| {
            let zmax = p.max_range as f32;
            (Just(p), prop::collection::vec((reading(zmax), (0.0f32..1.0).prop_map(move |u| u * zmax)), 1..360))
        })
    ) {
        let z: Vec<f32> = zs.iter().map(|x| x.0).collect();
        let zstar: Vec<f32> = zs.iter().map(|x| x.1).collect();
        let scan = Scan::<360>::from_ranges(&z).unwrap();
        let s = crate_model(&p).scan_log_likelihood(&scan, &zstar);
        let per: Vec<f64> = z.iter().zip(&zstar)
            .filter_map(|(&a, &b)| r::beam_log_likelihood(&p, f64::from(a), f64::from(b)))
            .collect();
        let want: f64 = per.iter().sum();
        let abs_sum: f64 = per.iter().map(|x| x.abs()).sum();
        let tol: f64 = per.iter().map(|&x| beam_tol(x)).sum::<f64>() + per.len() as f64 * 6e-8 * abs_sum;
        prop_assert_eq!(usize::from(s.scored), per.len());
        prop_assert_eq!(usize::from(s.invalid), z.len() - per.len());
        prop_assert!((f64::from(s.log_likelihood) - want).abs() <= tol,
            "{} vs {want} (tol {tol})", s.log_likelihood);
    }
}

/// Composite Simpson over [a, b] with n (even) intervals.
fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    let mut s = f(a) + f(b);
    for i in 1..n {
        let x = a + i as f64 * h;
        s += if i % 2 == 1 { 4.0 } else { 2.0 } * f(x);
    }
    s * h / 3.0
}

/// Integrates, doubling the grid until two estimates agree to 1e-8.
fn integrate(f: impl Fn(f64) -> f64 + Copy, a: f64, b: f64) -> f64 {
    let mut n = 2000;
    let mut prev = simpson(f, a, b, n);
    loop {
        n *= 2;
        let next = simpson(f, a, b, n);
        if (next - prev).abs() < 1e-8 || n > 4_000_000 {
            assert!((next - prev).abs() < 1e-8, "quadrature did not converge");
            return next;
        }
        prev = next;
    }
}

/// ∫ p_hit = 1 over [0, z_max] and ∫ p_short = 1 over [0, z*]: both truncation normalizers
/// are right, including where z* sits near a boundary and the normalizer is far from 1.
#[test]
fn densities_integrate_to_one() {
    let cases: [(f32, f32, f32, f32); 8] = [
        // (sigma, lambda, zmax, zstar)
        (1.0, 0.5, 10.0, 5.0),
        (1.0, 0.5, 10.0, 0.3),  // hit Gaussian cut at 0: η_hit ≈ 1.6
        (1.0, 0.5, 10.0, 9.9),  // cut at z_max
        (0.2, 0.1, 30.0, 12.0), // AMCL-like
        (3.0, 2.0, 5.0, 2.5),   // σ wider than the range
        (0.05, 5.0, 4.0, 0.01), // z* → 0: p_short ≈ 1/z* on a tiny interval
        (0.5, 0.001, 81.83, 40.0),
        (2.0, 10.0, 8.0, 8.0), // z* = z_max
    ];
    for (sigma, lambda, zmax, zstar) in cases {
        let m = BeamModel::new(
            BeamIntrinsics::new(0.25, 0.25, 0.25, 0.25, sigma, lambda, zmax).unwrap(),
        );
        let hit = |z: f64| f64::from(m.components(z as f32, zstar).unwrap().hit);
        let short = |z: f64| f64::from(m.components(z as f32, zstar).unwrap().short);
        // The Gaussian lives within ±12σ of z*: integrate there (and over the rest, which
        // must contribute nothing measurable).
        let lo = (f64::from(zstar) - 12.0 * f64::from(sigma)).max(0.0);
        let hi = (f64::from(zstar) + 12.0 * f64::from(sigma)).min(f64::from(zmax));
        let ih = integrate(hit, lo, hi);
        assert!(
            (ih - 1.0).abs() < 2e-5,
            "∫p_hit = {ih} for {sigma} {zmax} {zstar}"
        );
        // p_hit at z = z_max belongs to a max-range reading; integrate [0, z_max) only.
        let is = integrate(short, 0.0, f64::from(zstar) * (1.0 - 1e-12));
        assert!(
            (is - 1.0).abs() < 2e-5,
            "∫p_short = {is} for λ={lambda} z*={zstar}"
        );
    }
}

/// Edge cases: every one matches the reference and none gives NaN.
#[test]
fn edge_cases() {
    let base = Intrinsics {
        z_hit: 0.7,
        z_short: 0.1,
        z_max: 0.1,
        z_rand: 0.1,
        sigma_hit: 0.2,
        lambda_short: 1.0,
        max_range: 10.0,
    };
    let tiny_sigma = Intrinsics {
        sigma_hit: 1e-4,
        ..base
    };
    let no_rand = Intrinsics {
        z_hit: 0.8,
        z_rand: 0.0,
        ..base
    };
    let cases: &[(&Intrinsics, f32, f32, &str)] = &[
        (&base, 0.0, 3.0, "z = 0"),
        (&base, 3.0, 3.0, "z = z*"),
        (&base, 0.0, 0.0, "z = z* = 0"),
        (&base, 1e-7, 1e-6, "z* -> 0 (short density ~ 1/z*)"),
        (&base, 0.5, 1e-6, "z beyond a tiny z*"),
        (&base, 9.9, 9.999, "z* near z_max"),
        (&base, 9.9, 10.0, "z* = z_max"),
        (&base, 9.9, 50.0, "z* beyond z_max (clamped)"),
        (&base, 4.0, f32::NAN, "NaN z* (read as z_max)"),
        (&base, 10.0, 4.0, "z = z_max"),
        (&base, f32::INFINITY, 4.0, "z = +inf (max-range reading)"),
        (&tiny_sigma, 3.0, 3.0, "tiny sigma, on the wall"),
        (&tiny_sigma, 3.1, 3.0, "tiny sigma, 1000 sigma off"),
        (&no_rand, 9.0, 3.0, "no z_rand, far beyond the wall"),
    ];
    for &(p, z, zs, name) in cases {
        let got = crate_model(p).beam_log_likelihood(z, zs).unwrap();
        let want = r::beam_log_likelihood(p, f64::from(z), f64::from(zs)).unwrap();
        assert!(!got.is_nan(), "{name}: NaN");
        assert!(
            (f64::from(got) - want).abs() <= beam_tol(want),
            "{name}: {got} vs {want}"
        );
    }
    for bad in [f32::NAN, -1.0, f32::NEG_INFINITY, -0.0 - 1e-30] {
        assert_eq!(
            crate_model(&base).beam_log_likelihood(bad, 3.0),
            None,
            "{bad}"
        );
    }
}

/// A scan of nothing but NaN, negative and infinite readings never yields NaN.
#[test]
fn hostile_scan_never_nan() {
    let m = crate_model(&toy());
    let mut ranges = [0.0f32; 360];
    for (i, r) in ranges.iter_mut().enumerate() {
        *r = match i % 4 {
            0 => f32::NAN,
            1 => -1.0,
            2 => f32::INFINITY,
            _ => f32::NEG_INFINITY,
        };
    }
    let scan = Scan::<360>::from_ranges(&ranges).unwrap();
    let s = m.scan_log_likelihood(&scan, &[f32::NAN; 360]);
    assert!(s.log_likelihood.is_finite());
    assert_eq!((s.scored, s.invalid), (90, 270));
    // Each +∞ is a max-range reading: ln(z_max·1 + z_hit·p_hit(z_max)) with z* = z_max.
    let per = r::beam_log_likelihood(&toy(), f64::INFINITY, f64::NAN).unwrap();
    assert!((f64::from(s.log_likelihood) - 90.0 * per).abs() < 90.0 * beam_tol(per) + 1e-4);
}

/// The short component on the log-space path (Thrun Table 6.1's `p_short`, taken as a logarithm
/// where the mixture underflows f32): no max or uniform weight, a narrow Gaussian and a steep
/// exponential put the mixture below the crate's linear-space threshold (1e-30), and the f64
/// reference's short term is the largest component or within a few nats of the hit term. The
/// expected values come from the reference; tolerance as in the table at the top of this file.
#[test]
fn short_component_on_the_log_path_matches_reference() {
    let short_log = Intrinsics {
        z_hit: 0.5,
        z_short: 0.5,
        z_max: 0.0,
        z_rand: 0.0,
        sigma_hit: 0.01,
        lambda_short: 5.0,
        max_range: 40.0,
    };
    let steep = Intrinsics {
        z_hit: 0.2,
        z_short: 0.8,
        z_max: 0.0,
        z_rand: 0.0,
        sigma_hit: 0.02,
        lambda_short: 50.0,
        max_range: 10.0,
    };
    let cases: &[(&Intrinsics, f32, f32)] = &[
        (&short_log, 20.0, 25.0),
        (&short_log, 30.0, 30.5),
        (&short_log, 24.84, 25.0),
        (&short_log, 36.0, 39.0),
        (&short_log, 15.0, 39.0),
        (&steep, 2.0, 2.5),
        (&steep, 1.5, 2.0),
    ];
    for &(p, z, zs) in cases {
        let (zf, zsf) = (f64::from(z), f64::from(zs));
        let want = r::beam_log_likelihood(p, zf, zsf).unwrap();
        let [l_hit, l_short, _, _] = r::log_weighted_components(p, zf, zsf).unwrap();
        // The case exercises what it claims: the mixture underflows and p_short carries it.
        assert!(
            want < (1e-30f64).ln(),
            "z={z} z*={zs}: {want} is not on the log path"
        );
        assert!(
            l_short > l_hit - 5.0,
            "z={z} z*={zs}: short term {l_short} vs hit {l_hit}"
        );
        assert!(want > BEAM_LOG_FLOOR as f64, "z={z} z*={zs}: at the floor");
        let m = crate_model(p);
        assert!(
            m.beam_likelihood(z, zs) < 1e-30,
            "z={z} z*={zs}: linear path taken"
        );
        let got = f64::from(m.beam_log_likelihood(z, zs).unwrap());
        assert!(
            (got - want).abs() <= beam_tol(want),
            "z={z} z*={zs}: {got} vs reference {want}"
        );
    }
}
