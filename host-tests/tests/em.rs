//! EM for the beam intrinsics (`beamfield::em`) against the independent f64 reference
//! (`host_tests::reference`), closed forms and data sampled from known mixtures.

use beamfield::em::{fit, fit_grouped, fit_slices, EmConfig, ShapeUpdate, StopReason};
use beamfield::{BeamIntrinsics, Param};
use host_tests::reference::{self, Intrinsics};
use host_tests::splitmix::{Draws, SplitMix64 as Rng};

fn to_ref(i: &BeamIntrinsics) -> Intrinsics {
    Intrinsics {
        z_hit: f64::from(i.z_hit()),
        z_short: f64::from(i.z_short()),
        z_max: f64::from(i.z_max()),
        z_rand: f64::from(i.z_rand()),
        sigma_hit: f64::from(i.sigma_hit_m()),
        lambda_short: f64::from(i.lambda_short_per_m()),
        max_range: f64::from(i.max_range_m()),
    }
}

/// Draws one reading from the mixture `p` given `z_star` (generative model, docs/models.md#mixture).
fn sample_reading(rng: &mut Rng, p: &Intrinsics, z_star: f64) -> f64 {
    let u = rng.uniform();
    let zmax = p.max_range;
    if u < p.z_hit {
        loop {
            let z = z_star + p.sigma_hit * rng.normal();
            if (0.0..=zmax).contains(&z) {
                return z;
            }
        }
    } else if u < p.z_hit + p.z_short {
        let l = p.lambda_short;
        let m = 1.0 - (-l * z_star).exp();
        -(1.0 - rng.uniform() * m).ln() / l
    } else if u < p.z_hit + p.z_short + p.z_max {
        zmax
    } else {
        rng.uniform() * zmax
    }
}

/// A random data set of `n` readings: `z*` uniform in `[zs_lo, zmax]`, readings from `p`.
fn sample_set(rng: &mut Rng, p: &Intrinsics, n: usize, zs_lo: f64) -> (Vec<f32>, Vec<f32>) {
    let mut z = Vec::with_capacity(n);
    let mut zs = Vec::with_capacity(n);
    for _ in 0..n {
        let s = rng.range(zs_lo, p.max_range) as f32;
        z.push(sample_reading(rng, p, f64::from(s)) as f32);
        zs.push(s);
    }
    (z, zs)
}

/// The reference's mean log-likelihood at `p` with its weights divided by their sum: the
/// likelihood the crate's EM evaluates and reports (f32 weights sum to 1 only to ~6e-8; see the
/// em module docs, Precision).
fn ref_mean_ll(p: &Intrinsics, z: &[f32], zs: &[f32]) -> f64 {
    let sum: f64 = p.weights().iter().sum();
    let p = &Intrinsics {
        z_hit: p.z_hit / sum,
        z_short: p.z_short / sum,
        z_max: p.z_max / sum,
        z_rand: p.z_rand / sum,
        ..*p
    };
    let z64: Vec<f64> = z.iter().map(|&x| f64::from(x)).collect();
    let s64: Vec<f64> = zs.iter().map(|&x| f64::from(x)).collect();
    reference::scan_log_likelihood(p, &z64, &s64) / z.len() as f64
}

fn toy_start() -> BeamIntrinsics {
    BeamIntrinsics::new(0.25, 0.25, 0.25, 0.25, 1.0, 0.5, 10.0).unwrap()
}

fn one_step(shape: ShapeUpdate, start: BeamIntrinsics, z: &[f32], zs: &[f32]) -> BeamIntrinsics {
    let cfg = EmConfig {
        max_iterations: 1,
        tolerance_nats: 0.0,
        shape_update: shape,
        ..EmConfig::default()
    };
    let mut trace = [0.0; 4];
    fit_slices(&cfg, start, z, zs, &mut trace)
        .unwrap()
        .intrinsics
}

/// Thrun Table 6.1: the chapter's worked example, one textbook step, to 1e-6 (with the corrected
/// λ = 0.283739, not the printed 0.283737).
#[test]
fn worked_example_one_textbook_step() {
    let z = [4.5f32, 5.0, 3.0, 7.0, 10.0];
    let zs = [5.0f32; 5];
    let cfg = EmConfig {
        max_iterations: 1,
        tolerance_nats: 0.0,
        ..EmConfig::textbook()
    };
    let mut trace = [0.0; 8];
    let out = fit_slices(&cfg, toy_start(), &z, &zs, &mut trace).unwrap();
    assert_eq!(out.stop, StopReason::IterationLimit);
    assert_eq!(out.iterations, 1);
    assert_eq!(out.trace_len, 2);
    assert!(
        (trace[0] - -2.275_038).abs() < 1e-6,
        "LL before {}",
        trace[0]
    );
    let i = out.intrinsics;
    let want = [
        (i.z_hit(), 0.394_282),
        (i.z_short(), 0.127_210),
        (i.z_max(), 0.200_000),
        (i.z_rand(), 0.278_508),
        (i.sigma_hit_m(), 1.093_905),
        (i.lambda_short_per_m(), 0.283_739),
    ];
    for (k, (got, want)) in want.into_iter().enumerate() {
        assert!(
            (f64::from(got) - want).abs() < 1e-6,
            "param {k}: {got} vs {want}"
        );
    }
    // The same step from the independent reference, and the LL after it.
    let z64: Vec<f64> = z.iter().map(|&x| f64::from(x)).collect();
    let s64 = vec![5.0; 5];
    let (next, ll0) = reference::em_step_textbook(&to_ref(&toy_start()), &z64, &s64);
    assert!((ll0 - trace[0]).abs() < 1e-12, "{ll0} vs {}", trace[0]);
    let got = to_ref(&i);
    for (a, b) in [
        (got.z_hit, next.z_hit),
        (got.z_short, next.z_short),
        (got.z_max, next.z_max),
        (got.z_rand, next.z_rand),
        (got.sigma_hit, next.sigma_hit),
        (got.lambda_short, next.lambda_short),
    ] {
        // f32 storage: half an ulp of a number below 2 is < 1.2e-7.
        assert!((a - b).abs() < 1.2e-7, "{a} vs {b}");
    }
    let ll1 = ref_mean_ll(&got, &z, &zs);
    assert!((trace[1] - ll1).abs() < 1e-12, "{} vs {ll1}", trace[1]);
}

/// The truncated M-step is the exact M-step when Newton is given enough passes: on a random data
/// set, σ and λ after one step maximize the expected complete log-likelihood with the
/// normalizers, found independently by golden-section search on the reference's densities with
/// the reference's responsibilities.
#[test]
fn truncated_step_is_the_exact_m_step() {
    let mut rng = Rng::new(0x5EED_0004);
    let truth = Intrinsics {
        z_hit: 0.5,
        z_short: 0.3,
        z_max: 0.05,
        z_rand: 0.15,
        sigma_hit: 0.8,
        lambda_short: 0.7,
        max_range: 4.0,
    };
    let (z, zs) = sample_set(&mut rng, &truth, 400, 0.1);
    let start = BeamIntrinsics::new(0.4, 0.3, 0.1, 0.2, 0.5, 1.5, 4.0).unwrap();
    let cfg = EmConfig {
        max_iterations: 1,
        tolerance_nats: 0.0,
        max_newton_passes: 60,
        shape_update: ShapeUpdate::TruncatedExact,
    };
    let mut trace = [0.0; 4];
    let next = fit_slices(&cfg, start, &z, &zs, &mut trace)
        .unwrap()
        .intrinsics;
    let p0 = to_ref(&start);
    // Reference responsibilities at the start.
    let resp: Vec<[f64; 4]> = z
        .iter()
        .zip(&zs)
        .map(|(&a, &b)| {
            let c = reference::components(&p0, f64::from(a), f64::from(b)).unwrap();
            let w = p0.weights();
            let t: f64 = (0..4).map(|k| w[k] * c[k]).sum();
            [0, 1, 2, 3].map(|k| w[k] * c[k] / t)
        })
        .collect();
    // Q's hit (k = 0) or short (k = 1) part as a function of σ or λ.
    let q = |k: usize, x: f64| -> f64 {
        let mut p = p0;
        if k == 0 {
            p.sigma_hit = x;
        } else {
            p.lambda_short = x;
        }
        z.iter()
            .zip(&zs)
            .zip(&resp)
            .filter(|(_, e)| e[k] > 0.0)
            .map(|((&a, &b), e)| {
                let c = reference::components(&p, f64::from(a), f64::from(b)).unwrap();
                e[k] * c[k].ln()
            })
            .sum()
    };
    let golden = |k: usize, mut lo: f64, mut hi: f64| {
        let r = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..200 {
            let a = hi - r * (hi - lo);
            let b = lo + r * (hi - lo);
            if q(k, a) < q(k, b) {
                lo = a;
            } else {
                hi = b;
            }
        }
        0.5 * (lo + hi)
    };
    let sigma_ref = golden(0, 0.01, 4.0);
    let lambda_ref = golden(1, 0.01, 20.0);
    let (sigma, lambda) = (
        f64::from(next.sigma_hit_m()),
        f64::from(next.lambda_short_per_m()),
    );
    println!("exact M-step: sigma {sigma} vs {sigma_ref}, lambda {lambda} vs {lambda_ref}");
    // Both sides are exact to well below f32 resolution (golden section: ~1.5e-8 relative, the
    // square root of f64's epsilon), so the result must be the optimum rounded to f32:
    // within one f32 ulp (≤ 1.2e-7 relative) plus the search's own error.
    assert!(
        (sigma - sigma_ref).abs() < 1.5e-7 * sigma_ref,
        "{sigma} vs {sigma_ref}"
    );
    assert!(
        (lambda - lambda_ref).abs() < 1.5e-7 * lambda_ref,
        "{lambda} vs {lambda_ref}"
    );
    assert!(q(0, sigma) >= q(0, sigma_ref) - 1e-9 * q(0, sigma_ref).abs());
    assert!(q(1, lambda) >= q(1, lambda_ref) - 1e-9 * q(1, lambda_ref).abs());
    // The textbook σ and λ differ from the exact ones on this data (the normalizers matter).
    let tb = one_step(ShapeUpdate::Textbook, start, &z, &zs);
    assert!((f64::from(tb.lambda_short_per_m()) - lambda_ref).abs() > 1e-3);
}

/// On the worked example the short readings' weighted mean (≈ 4.2 m) exceeds z*/2 = 2.5 m, so
/// the truncated-exponential likelihood increases all the way to λ → 0 (no interior root of the
/// score equation): the monotone EM runs λ down to its documented lower bound, 1e-3/z_max.
#[test]
fn worked_example_truncated_lambda_goes_to_its_bound() {
    let z = [4.5f32, 5.0, 3.0, 7.0, 10.0];
    let zs = [5.0f32; 5];
    let mut trace = [0.0; 128];
    let out = fit_slices(&EmConfig::default(), toy_start(), &z, &zs, &mut trace).unwrap();
    let lam = out.intrinsics.lambda_short_per_m();
    assert_eq!(lam, 1e-4f32, "{out:?}");
    let t = &trace[..out.trace_len];
    assert!(t.windows(2).all(|w| w[1] >= w[0] - 1e-12), "{t:?}");
}

/// docs/models.md#em: 40,000 short readings of λ = 1 truncated at z* = 2 m.
#[test]
fn lambda_from_truncated_short_readings() {
    let mut rng = Rng::new(0x5EED_0001);
    let p = Intrinsics {
        z_hit: 0.0,
        z_short: 1.0,
        z_max: 0.0,
        z_rand: 0.0,
        sigma_hit: 1.0,
        lambda_short: 1.0,
        max_range: 10.0,
    };
    let n = 40_000;
    let z: Vec<f32> = (0..n)
        .map(|_| sample_reading(&mut rng, &p, 2.0) as f32)
        .collect();
    let zs = vec![2.0f32; n];
    let start = BeamIntrinsics::new(0.0, 1.0, 0.0, 0.0, 1.0, 0.5, 10.0).unwrap();
    let mut trace = vec![0.0; 128];
    let tb = fit_slices(&EmConfig::textbook(), start, &z, &zs, &mut trace).unwrap();
    let tr = fit_slices(&EmConfig::default(), start, &z, &zs, &mut trace).unwrap();
    let lt = f64::from(tb.intrinsics.lambda_short_per_m());
    let lc = f64::from(tr.intrinsics.lambda_short_per_m());
    // Textbook fixed point: 1/mean(z), computed directly; and the population value
    // 1/(1 − 2/(e² − 1)) = 1.4565.
    let mean = z.iter().map(|&x| f64::from(x)).sum::<f64>() / n as f64;
    let e2 = 2.0f64.exp();
    let population = 1.0 / (1.0 - 2.0 / (e2 - 1.0));
    println!(
        "lambda: textbook {lt} (1/mean {}), truncated {lc}, stops {:?} {:?}",
        1.0 / mean,
        tb.stop,
        tr.stop
    );
    assert!(
        (lt - 1.0 / mean).abs() < 1e-6 * lt,
        "{lt} vs {}",
        1.0 / mean
    );
    assert!((lt - population).abs() < 0.03, "{lt} vs {population}");
    assert!((lc - 1.0).abs() < 0.03, "truncated λ {lc}");
    // The truncated λ is the sample's maximum-likelihood estimate: bisection on the score.
    let score = |l: f64| 1.0 / l - mean - 2.0 / ((2.0 * l).exp() - 1.0);
    let (mut lo, mut hi) = (1e-3, 50.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if score(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    assert!(
        (lc - lo).abs() <= 2.0 * f64::from(f32::EPSILON) * lo,
        "{lc} vs MLE {lo}"
    );
    assert_eq!(tr.stop, StopReason::Converged);
    assert_eq!(tr.counts.used, n as u64);
}

/// Known intrinsics are recovered from 20,000 readings sampled from the mixture.
#[test]
fn recovers_known_intrinsics() {
    let mut rng = Rng::new(0x5EED_0002);
    let truth = Intrinsics {
        z_hit: 0.7,
        z_short: 0.1,
        z_max: 0.05,
        z_rand: 0.15,
        sigma_hit: 0.2,
        lambda_short: 0.8,
        max_range: 10.0,
    };
    let n = 20_000;
    let (z, zs) = sample_set(&mut rng, &truth, n, 0.5);
    let start = BeamIntrinsics::amcl_defaults(10.0).unwrap();
    let mut trace = vec![0.0; 256];
    let out = fit_slices(&EmConfig::default(), start, &z, &zs, &mut trace).unwrap();
    let i = to_ref(&out.intrinsics);
    println!(
        "recovered {i:?} in {} iterations, {} passes, {:?}",
        out.iterations, out.passes, out.stop
    );
    assert_eq!(out.stop, StopReason::Converged);
    // Tolerances: about 4–5 standard errors for n = 20,000 (a weight w has SE √(w(1−w)/n) ≤ 0.0035;
    // σ has SE ≈ σ/√(2·n·z_hit) = 0.0012; λ from ~2,000 short readings, SE ≈ 0.03).
    let checks = [
        ("z_hit", i.z_hit, truth.z_hit, 0.015),
        ("z_short", i.z_short, truth.z_short, 0.015),
        ("z_max", i.z_max, truth.z_max, 0.01),
        ("z_rand", i.z_rand, truth.z_rand, 0.015),
        ("sigma", i.sigma_hit, truth.sigma_hit, 0.006),
        ("lambda", i.lambda_short, truth.lambda_short, 0.15),
    ];
    for (name, got, want, tol) in checks {
        assert!((got - want).abs() < tol, "{name}: {got} vs {want}");
    }
    let t = &trace[..out.trace_len];
    assert!(t.windows(2).all(|w| w[1] >= w[0] - 1e-12));
    // The last trace entry is the log-likelihood of the returned intrinsics (reference).
    let last = ref_mean_ll(&i, &z, &zs);
    assert!(
        (t[t.len() - 1] - last).abs() < 1e-10,
        "{} vs {last}",
        t[t.len() - 1]
    );
}

/// A textbook step that lowers the log-likelihood exists (docs/models.md#em); the truncated EM on
/// the same data set does not lower it.
#[test]
fn textbook_step_can_decrease_the_log_likelihood() {
    let mut worst: Option<(f64, u64)> = None;
    for seed in 0..400u64 {
        let mut rng = Rng::new(seed);
        let truth = random_truth(&mut rng);
        let n = 10 + (rng.next_u64() % 40) as usize;
        let (z, zs) = sample_set(&mut rng, &truth, n, 0.0);
        let start = random_start(&mut rng, truth.max_range as f32);
        let before = ref_mean_ll(&to_ref(&start), &z, &zs);
        let tb = one_step(ShapeUpdate::Textbook, start, &z, &zs);
        let drop = before - ref_mean_ll(&to_ref(&tb), &z, &zs);
        if drop > worst.map_or(1e-9, |w| w.0) {
            worst = Some((drop, seed));
        }
    }
    let (drop, seed) = worst.expect("no textbook decrease in 400 random data sets");
    // Re-check the worst case with the reference's own textbook step (no f32 rounding) and with
    // the monotone EM.
    let mut rng = Rng::new(seed);
    let truth = random_truth(&mut rng);
    let n = 10 + (rng.next_u64() % 40) as usize;
    let (z, zs) = sample_set(&mut rng, &truth, n, 0.0);
    let start = random_start(&mut rng, truth.max_range as f32);
    let z64: Vec<f64> = z.iter().map(|&x| f64::from(x)).collect();
    let s64: Vec<f64> = zs.iter().map(|&x| f64::from(x)).collect();
    let (next, before) = reference::em_step_textbook(&to_ref(&start), &z64, &s64);
    let ref_drop = before - reference::scan_log_likelihood(&next, &z64, &s64) / n as f64;
    let tr = one_step(ShapeUpdate::Truncated, start, &z, &zs);
    let tr_gain = ref_mean_ll(&to_ref(&tr), &z, &zs) - before;
    println!(
        "textbook decrease: seed {seed}, n {n}, {drop:.3e} nats/beam (reference step: \
         {ref_drop:.3e}); truncated step on it: {tr_gain:+.3e}; start {start:?}; truth {truth:?}"
    );
    assert!(
        ref_drop > 1e-9,
        "reference step does not decrease: {ref_drop}"
    );
    assert!(tr_gain >= -1e-12, "{tr_gain}");
}

fn random_truth(rng: &mut Rng) -> Intrinsics {
    let mut w = [0.0; 4];
    for x in &mut w {
        *x = rng.range(0.05, 1.0);
    }
    let s: f64 = w.iter().sum();
    Intrinsics {
        z_hit: w[0] / s,
        z_short: w[1] / s,
        z_max: w[2] / s,
        z_rand: w[3] / s,
        sigma_hit: rng.range(0.05, 3.0),
        lambda_short: rng.range(0.05, 3.0),
        max_range: rng.range(2.0, 20.0),
    }
}

fn random_start(rng: &mut Rng, zmax: f32) -> BeamIntrinsics {
    let mut w = [0.0f32; 4];
    for x in &mut w {
        *x = rng.range(0.05, 1.0) as f32;
    }
    let s: f32 = w.iter().sum();
    BeamIntrinsics::new(
        w[0] / s,
        w[1] / s,
        w[2] / s,
        1.0 - (w[0] + w[1] + w[2]) / s,
        rng.range(0.05, 3.0) as f32,
        rng.range(0.05, 3.0) as f32,
        zmax,
    )
    .unwrap()
}

/// Skipped readings are counted, not lost: invalid ones, unexplained ones, bad groups; an empty
/// source reports `NoData` and returns the start.
#[test]
fn skipped_readings_are_counted() {
    let start = BeamIntrinsics::new(0.0, 1.0, 0.0, 0.0, 1.0, 0.5, 10.0).unwrap();
    // Only the short component: z > z* below the limit is unexplained.
    let z = [1.0f32, f32::NAN, -2.0, 6.0, 0.5];
    let zs = [5.0f32, 5.0, 5.0, 5.0, 5.0];
    let mut trace = [0.0; 8];
    let out = fit_slices(&EmConfig::default(), start, &z, &zs, &mut trace).unwrap();
    assert_eq!(out.counts.used, 2);
    assert_eq!(out.counts.invalid, 2);
    assert_eq!(out.counts.unexplained, 1);

    let empty: [f32; 0] = [];
    let out = fit_slices(&EmConfig::default(), start, &empty, &empty, &mut trace).unwrap();
    assert_eq!(out.stop, StopReason::NoData);
    assert_eq!(out.intrinsics, start);
    assert_eq!(out.trace_len, 0);

    let bad = EmConfig {
        tolerance_nats: f64::NAN,
        ..EmConfig::default()
    };
    assert!(fit_slices(&bad, start, &z, &zs, &mut trace).is_err());
}

/// σ collapses when every hit reading equals its z*: reported as degenerate, not looped on.
#[test]
fn collapsing_sigma_is_reported() {
    let start = BeamIntrinsics::new(0.9, 0.0, 0.0, 0.1, 0.5, 0.5, 10.0).unwrap();
    let z = [2.0f32, 3.0, 4.0, 5.0, 6.0];
    let mut trace = [0.0; 200];
    let out = fit_slices(&EmConfig::default(), start, &z, &z, &mut trace).unwrap();
    assert_eq!(out.stop, StopReason::Degenerate(Param::SigmaHit));
    let t = &trace[..out.trace_len];
    assert!(t.windows(2).all(|w| w[1] >= w[0] - 1e-12), "{t:?}");
}

/// A trace buffer that is too short loses entries visibly.
#[test]
fn short_trace_buffer_counts_dropped_entries() {
    let mut rng = Rng::new(7);
    let truth = random_truth(&mut rng);
    let (z, zs) = sample_set(&mut rng, &truth, 500, 0.2);
    let start = random_start(&mut rng, truth.max_range as f32);
    let cfg = EmConfig {
        max_iterations: 5,
        tolerance_nats: 0.0,
        ..EmConfig::default()
    };
    let mut trace = [0.0; 3];
    let out = fit(
        &cfg,
        start,
        || z.iter().copied().zip(zs.iter().copied()),
        &mut trace,
    )
    .unwrap();
    assert_eq!(
        out.trace_len + out.trace_dropped,
        out.iterations as usize + 1
    );
    assert_eq!(out.trace_len, 3);
}

/// Grouped EM: two groups with different z_rand share σ and λ; each group's weights are
/// recovered.
#[test]
fn grouped_fit_recovers_per_group_weights() {
    let mut rng = Rng::new(0x5EED_0003);
    let base = Intrinsics {
        z_hit: 0.8,
        z_short: 0.1,
        z_max: 0.05,
        z_rand: 0.05,
        sigma_hit: 0.1,
        lambda_short: 1.0,
        max_range: 5.0,
    };
    let noisy = Intrinsics {
        z_hit: 0.5,
        z_short: 0.1,
        z_max: 0.05,
        z_rand: 0.35,
        ..base
    };
    let mut data = Vec::new();
    for k in 0..20_000 {
        let g = k % 2;
        let p = if g == 0 { &base } else { &noisy };
        let s = rng.range(0.5, 5.0) as f32;
        data.push((g, sample_reading(&mut rng, p, f64::from(s)) as f32, s));
    }
    data.push((7, 1.0, 1.0)); // out-of-range group
    let start = BeamIntrinsics::amcl_defaults(5.0).unwrap();
    let mut trace = vec![0.0; 256];
    let out = fit_grouped::<2, _, _>(
        &EmConfig::default(),
        &start,
        [start.weights(); 2],
        || data.iter().copied(),
        &mut trace,
    )
    .unwrap();
    assert_eq!(out.counts.bad_group, 1);
    assert_eq!(out.used_per_group, [10_000, 10_000]);
    for (g, p) in [(0, &base), (1, &noisy)] {
        let i = out.intrinsics(g).unwrap().unwrap();
        assert!(
            (f64::from(i.z_rand()) - p.z_rand).abs() < 0.02,
            "group {g}: {i:?}"
        );
        assert!(
            (f64::from(i.z_hit()) - p.z_hit).abs() < 0.02,
            "group {g}: {i:?}"
        );
    }
    assert!((f64::from(out.sigma_hit_m) - 0.1).abs() < 0.005);
    assert!(out.intrinsics(2).is_none());
}

/// Why the EM module computes its densities in f64 rather than through the crate's f32
/// `BeamModel::components`: measured per-beam error of the f32 log-likelihood against the
/// reference, compared with what late EM iterations gain per beam.
#[test]
fn f32_components_are_too_coarse_for_late_em_steps() {
    let mut rng = Rng::new(0x5EED_0002);
    let truth = Intrinsics {
        z_hit: 0.7,
        z_short: 0.1,
        z_max: 0.05,
        z_rand: 0.15,
        sigma_hit: 0.2,
        lambda_short: 0.8,
        max_range: 10.0,
    };
    let (z, zs) = sample_set(&mut rng, &truth, 20_000, 0.5);
    let start = BeamIntrinsics::amcl_defaults(10.0).unwrap();
    let mut trace = vec![0.0; 256];
    let out = fit_slices(&EmConfig::default(), start, &z, &zs, &mut trace).unwrap();
    let fitted = out.intrinsics;
    let model = beamfield::BeamModel::new(fitted);
    let p = to_ref(&fitted);
    let (mut max_err, mut mean_f32, mut mean_ref) = (0.0f64, 0.0f64, 0.0f64);
    for (&a, &b) in z.iter().zip(&zs) {
        let l32 = f64::from(model.components(a, b).unwrap().mix(fitted.weights()).ln());
        let l64 = reference::beam_log_likelihood(&p, f64::from(a), f64::from(b)).unwrap();
        max_err = max_err.max((l32 - l64).abs());
        mean_f32 += l32;
        mean_ref += l64;
    }
    let n = z.len() as f64;
    let mean_err = (mean_f32 - mean_ref).abs() / n;
    let t = &trace[..out.trace_len];
    let late_gains: Vec<f64> = t.windows(2).rev().take(5).map(|w| w[1] - w[0]).collect();
    println!(
        "f32 per-beam LL error: max {max_err:.2e}, on the mean {mean_err:.2e}; last EM gains \
         per beam {late_gains:?}"
    );
    // The f32 mixture is accurate to single precision (≤ ~1e-6 nats per beam)...
    assert!(max_err < 1e-5, "{max_err}");
    // ...which is more than the last steps of EM gain: an f32 E-step could not tell them apart.
    assert!(late_gains.iter().any(|&g| g < max_err), "{late_gains:?}");
    // The f64 trace agrees with the reference (at the renormalized weights it evaluates) to
    // ~1e-13 on the mean.
    assert!((t[t.len() - 1] - ref_mean_ll(&p, &z, &zs)).abs() < 1e-10);
}
