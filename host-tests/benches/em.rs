//! EM time: 24 iterations over 4,500 beams (the chapter quotes ≈ 50 ms; the target is ≤ 5 ms),
//! textbook and both truncation-aware updates, against a baseline measured in the same run: one pass of the
//! crate's f32 mixture (`BeamModel::beam_likelihood`) over the same 4,500 beams.
//!
//! Run: `cargo bench -p host-tests --bench em`. Quote the ratios, not the absolute times.

use beamfield::em::{fit_slices, EmConfig, ShapeUpdate};
use beamfield::{BeamIntrinsics, BeamModel};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

const BEAMS: usize = 4_500;
const ITERATIONS: u32 = 24;

/// SplitMix64, for a reproducible data set.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// 4,500 readings from a lidar-like mixture (z_max 30 m, z* in [0.5, 30], σ = 0.15 m,
/// λ = 0.5/m, weights 0.75/0.1/0.05/0.1).
fn data() -> (Vec<f32>, Vec<f32>) {
    let mut rng = Rng(42);
    let zmax = 30.0f64;
    let (mut z, mut zs) = (Vec::new(), Vec::new());
    for _ in 0..BEAMS {
        let s = 0.5 + (zmax - 0.5) * rng.uniform();
        let u = rng.uniform();
        let r = if u < 0.75 {
            let g = (-2.0 * (1.0 - rng.uniform()).ln()).sqrt()
                * (2.0 * std::f64::consts::PI * rng.uniform()).cos();
            (s + 0.15 * g).clamp(0.0, zmax)
        } else if u < 0.85 {
            let m = 1.0 - (-0.5 * s).exp();
            -(1.0 - rng.uniform() * m).ln() / 0.5
        } else if u < 0.9 {
            zmax
        } else {
            rng.uniform() * zmax
        };
        z.push(r as f32);
        zs.push(s as f32);
    }
    (z, zs)
}

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
