//! Weight normalization on adversarial inputs, against an f64 log-sum-exp.

use beamfield::{normalize_log_weights, NormalizeError};
use proptest::prelude::*;

/// f64 reference: weights and ESS.
fn reference(l: &[f32]) -> (Vec<f64>, f64) {
    let m = l
        .iter()
        .map(|&x| f64::from(x))
        .fold(f64::NEG_INFINITY, f64::max);
    let e: Vec<f64> = l.iter().map(|&x| (f64::from(x) - m).exp()).collect();
    let s: f64 = e.iter().sum();
    let w: Vec<f64> = e.iter().map(|x| x / s).collect();
    let ess = 1.0 / w.iter().map(|x| x * x).sum::<f64>();
    (w, ess)
}

fn check(l: &[f32]) {
    let mut w = l.to_vec();
    let n = normalize_log_weights(&mut w).expect("finite input normalizes");
    let (want, ess) = reference(l);
    assert!(
        w.iter().all(|x| x.is_finite() && *x >= 0.0),
        "{l:?} -> {w:?}"
    );
    assert!(w.iter().any(|&x| x > 0.0), "all zero for {l:?}");
    let sum: f32 = w.iter().sum();
    // Each weight carries ≤ 3 roundings (exp, one product, the shared 1/sum): 4e-7 relative;
    // the f32 sum of n terms adds n·6e-8.
    assert!(
        (sum - 1.0).abs() <= 4e-7 + w.len() as f32 * 6e-8,
        "sum {sum}"
    );
    for (g, r) in w.iter().zip(&want) {
        assert!(
            (f64::from(*g) - r).abs() <= 4e-7 * r + 1e-38,
            "{g} vs {r} in {l:?}"
        );
    }
    // ESS: each w² carries ≤ 8e-7 relative error, the compensated sum ≤ 2 ulp, the
    // reciprocal 1 ulp: 1.1e-6 relative in all.
    assert!(
        (f64::from(n.ess) - ess).abs() <= 1.1e-6 * ess,
        "ess {} vs {ess}",
        n.ess
    );
    assert!(n.ess >= 1.0 - 1e-5 && n.ess <= w.len() as f32 * (1.0 + 1e-5));
}

#[test]
fn adversarial_inputs() {
    let big = f32::MAX;
    check(&[big, big, big]);
    check(&[-big, -big]);
    check(&[big, -big, 0.0]);
    check(&[f32::MIN_POSITIVE, -f32::MIN_POSITIVE, 1e-45]);
    check(&[-1e30, -1e30 + 1e24, -1.0000001e30]);
    check(&[-88.0, -104.0, -150.0, 0.0]); // differences that underflow exp in f32
    check(&[0.0; 1]);
    check(&vec![-3.5e4; 10_000]);
    // The log-likelihoods of a raw 360-beam scan: thousands of nats apart. Exponentiating
    // them directly gives all zeros; normalization gives a proper distribution.
    check(&[-4510.3, -4498.7, -4620.0, -4499.2]);
    assert!([-4510.3f32, -4498.7].iter().all(|x| x.exp() == 0.0));
}

#[test]
fn minus_infinity_entries() {
    let ninf = f32::NEG_INFINITY;
    let mut w = [ninf, ninf, -7.0, ninf];
    let n = normalize_log_weights(&mut w).unwrap();
    assert_eq!(w, [0.0, 0.0, 1.0, 0.0]);
    assert_eq!((n.best, n.ess), (2, 1.0));
    assert_eq!(n.log_total, -7.0);
    let mut w = [ninf; 5];
    assert_eq!(
        normalize_log_weights(&mut w),
        Err(NormalizeError::AllImpossible)
    );
    assert!(w.iter().all(|&x| x == ninf), "left unchanged");
}

proptest! {
    #[test]
    fn random_finite_inputs(l in prop::collection::vec(prop_oneof![
        4 => -1e4f32..1e4,
        1 => -3e38f32..3e38,
        1 => Just(0.0f32),
    ], 1..500)) {
        check(&l);
    }
}
