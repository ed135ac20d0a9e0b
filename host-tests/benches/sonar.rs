//! Cost of crosstalk-aware sonar scoring (one `BeamModel` per transducer) relative to the plain
//! beam model with one weight set, on the same 24-beam scan, measured in the same run. Report
//! the ratio, not the absolute times.

use beamfield::sonar::{CrosstalkModel, Ring, Schedule, SonarModel};
use beamfield::{BeamIntrinsics, BeamModel, Scan};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let ring = Ring::<24>::uniform(24, 0.0, -15f32.to_radians(), 0.25, 0.2, 5.0).unwrap();
    let groups: Vec<Vec<usize>> = (0..8).map(|g| vec![g, g + 8, g + 16]).collect();
    let slices: Vec<&[usize]> = groups.iter().map(|g| g.as_slice()).collect();
    let sched = Schedule::<24, 8>::new(&ring, &slices, 0.012, 343.0).unwrap();
    let base = BeamIntrinsics::new(0.8, 0.08, 0.07, 0.05, 0.08, 2.0, 5.0).unwrap();
    let model = CrosstalkModel::gaussian(0.3, 45f32.to_radians()).unwrap();
    let sonar = SonarModel::new(&ring, &sched, &base, &model).unwrap();
    let plain = BeamModel::new(base);
    let ranges: Vec<f32> = (0..24).map(|i| 0.5 + 0.17 * i as f32).collect();
    let z_star: Vec<f32> = (0..24).map(|i| 0.52 + 0.165 * i as f32).collect();
    let scan = Scan::<24>::from_ranges(&ranges).unwrap();
    let mut g = c.benchmark_group("sonar_scan_24");
    g.bench_function("baseline_beam_model", |b| {
        b.iter(|| plain.scan_log_likelihood(black_box(&scan), black_box(&z_star)))
    });
    g.bench_function("sonar_model_per_beam_weights", |b| {
        b.iter(|| sonar.scan_log_likelihood(black_box(&scan), black_box(&z_star)))
    });
    g.bench_function("sonar_model_build_once_per_schedule", |b| {
        b.iter(|| SonarModel::new(black_box(&ring), &sched, &base, &model).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
