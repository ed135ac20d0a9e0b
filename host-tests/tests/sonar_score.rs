//! Scoring a sonar scan with crosstalk-aware per-beam weights against the f64 reference of the
//! beam mixture (`host_tests::reference`) with per-beam weights computed in f64 from
//! docs/models.md#sonar. The same inputs are the ones an on-target (QEMU) check should reproduce.

use beamfield::sonar::{CrosstalkModel, Ring, Schedule, SonarModel};
use beamfield::{BeamIntrinsics, Scan};
use host_tests::reference;
use host_tests::sonar_sim::reference_c;

/// The SCITOS-like ring: 24 transducers, 15° apart clockwise, 5 m.
fn ring() -> Ring<24> {
    Ring::uniform(
        24,
        0.0,
        -15f32.to_radians(),
        0.25,
        12.5f32.to_radians(),
        5.0,
    )
    .unwrap()
}

const RANGES_M: [f32; 24] = [
    1.20,
    1.31,
    5.0,
    2.05,
    0.40,
    2.90,
    3.10,
    f32::INFINITY,
    2.2,
    1.9,
    1.75,
    0.2, //
    1.1,
    1.15,
    4.2,
    0.8,
    0.75,
    0.74,
    f32::NAN,
    0.9,
    1.0,
    1.3,
    1.25,
    1.22,
];
const Z_STAR_M: [f32; 24] = [
    1.21, 1.30, 3.9, 2.0, 2.4, 2.95, 3.05, 4.5, 2.25, 1.95, 1.70, 1.6, //
    1.12, 1.18, 1.5, 0.82, 0.74, 0.73, 0.8, 0.88, 1.02, 1.28, 1.26, 1.2,
];

#[test]
fn scan_score_matches_the_f64_reference() {
    let ring = ring();
    // Groups of 3 spread around the ring (120° apart), 12 ms apart: echoes of the two previous
    // groups still linger (lifetime 29.15 ms).
    let groups: Vec<Vec<usize>> = (0..8).map(|g| vec![g, g + 8, g + 16]).collect();
    let slices: Vec<&[usize]> = groups.iter().map(|g| g.as_slice()).collect();
    let sched = Schedule::<24, 8>::new(&ring, &slices, 0.012, 343.0).unwrap();
    let base = BeamIntrinsics::new(0.8, 0.08, 0.07, 0.05, 0.08, 2.0, 5.0).unwrap();
    let model = CrosstalkModel::gaussian(0.3, 45f32.to_radians()).unwrap();
    let sonar = SonarModel::new(&ring, &sched, &base, &model).unwrap();
    let scan = Scan::<24>::from_ranges(&RANGES_M).unwrap();
    let got = sonar.scan_log_likelihood(&scan, &Z_STAR_M);
    assert_eq!((got.scored, got.invalid, got.unpaired), (23, 1, 0));

    let bearings: Vec<f64> = ring
        .transducers()
        .iter()
        .map(|t| f64::from(t.bearing_rad))
        .collect();
    let lifetime = 2.0 * 5.0 / 343.0;
    let q = |d: f64| 0.3 * (-0.5 * (d / 45f64.to_radians()).powi(2)).exp();
    let mut want = 0.0;
    for i in 0..24 {
        let c = reference_c(&bearings, &groups, 0.012, lifetime, &q, i);
        let p = reference::Intrinsics {
            z_hit: 0.8 * (1.0 - c),
            z_short: 0.08 * (1.0 - c),
            z_max: 0.07 * (1.0 - c),
            z_rand: 0.05 + 0.95 * c,
            sigma_hit: 0.08,
            lambda_short: 2.0,
            max_range: 5.0,
        };
        if let Some(l) =
            reference::beam_log_likelihood(&p, f64::from(RANGES_M[i]), f64::from(Z_STAR_M[i]))
        {
            want += l;
        }
        // Every beam has co-fired or lingering neighbours in this schedule.
        assert!(c > 0.0, "beam {i}");
        assert!(
            (f64::from(sonar.crosstalk()[i]) - c).abs() < 1e-6,
            "beam {i}"
        );
    }
    println!(
        "sonar scan log-likelihood: crate {} vs f64 reference {want}",
        got.log_likelihood
    );
    assert!((f64::from(got.log_likelihood) - want).abs() < 1e-4 * want.abs().max(1.0));
}
