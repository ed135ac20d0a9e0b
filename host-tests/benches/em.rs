//! EM time: 24 iterations over 4,500 beams (the chapter quotes ≈ 50 ms; the target is ≤ 5 ms),
//! textbook and both truncation-aware updates, against a baseline measured in the same run: one pass of the
//! crate's f32 mixture (`BeamModel::beam_likelihood`) over the same 4,500 beams.
//!
//! Run: `cargo bench -p host-tests --bench em`. Quote the ratios, not the absolute times.

use beamfield::em::{fit_slices, EmConfig, ShapeUpdate};
use beamfield::{BeamIntrinsics, BeamModel};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

use host_workloads::em_data;

use em_data::{data, ITERATIONS};

fn bench(c: &mut Criterion) {
    let (z, zs) = data();
    let start = BeamIntrinsics::amcl_defaults(30.0).unwrap();
    let model = BeamModel::new(start);
    let mut g = c.benchmark_group("em_4500_beams");
    g.bench_function("baseline_one_mixture_pass_f32", |b| {
        b.iter(|| {
            let s: f32 = z
                .iter()
                .zip(&zs)
                .map(|(&a, &s)| model.beam_likelihood(black_box(a), s))
                .sum();
            black_box(s)
        })
    });
    for (name, shape) in [
        ("textbook_24_iterations", ShapeUpdate::Textbook),
        ("truncated_24_iterations", ShapeUpdate::Truncated),
        ("truncated_exact_24_iterations", ShapeUpdate::TruncatedExact),
    ] {
        let cfg = EmConfig {
            max_iterations: ITERATIONS,
            tolerance_nats: 0.0,
            shape_update: shape,
            ..EmConfig::default()
        };
        let mut trace = [0.0f64; 32];
        let out = fit_slices(&cfg, start, &z, &zs, &mut trace).unwrap();
        println!(
            "{name}: {} iterations, {} passes, stop {:?}, fitted {:?}",
            out.iterations, out.passes, out.stop, out.intrinsics
        );
        g.bench_function(name, |b| {
            b.iter(|| {
                let out = fit_slices(&cfg, black_box(start), &z, &zs, &mut trace).unwrap();
                black_box(out)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
