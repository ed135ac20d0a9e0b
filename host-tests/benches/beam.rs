//! Host cost of the beam mixture per beam, given z* (no ray casting), against a baseline
//! measured in the same run: one `f32::ln` per beam. Compare the two (a ratio), not absolute
//! numbers across machines.
//!
//! Run: `cargo bench -p host-tests --bench beam`. Criterion reports the time per 360-beam scan
//! and, from `Throughput::Elements`, beams per second; ns per beam = time / 360.
//! The same scan mix is measured in instructions on a Cortex-M4F by `cargo xtask insns`.

use beamfield::{BeamIntrinsics, BeamModel, Scan};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;

const BEAMS: usize = 360;
const MAX_RANGE_M: f32 = 30.0;

/// xorshift32, as in `firmware/src/bin/insns.rs`: the same mix of readings, ~85% hits within
/// ±0.2 m of the wall, ~8% short, ~4% max range, ~3% uniform.
fn synthetic() -> ([f32; BEAMS], [f32; BEAMS]) {
    let mut s = 0x1234_5678u32;
    let mut unit = move || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        (s >> 8) as f32 / (1u32 << 24) as f32
    };
    let mut ranges = [0.0f32; BEAMS];
    let mut z_star = [0.0f32; BEAMS];
    for (z, zs) in ranges.iter_mut().zip(z_star.iter_mut()) {
        let wall = 0.5 + 28.5 * unit();
        let kind = unit();
        *zs = wall;
        *z = if kind < 0.85 {
            wall + 0.4 * (unit() - 0.5)
        } else if kind < 0.93 {
            wall * unit()
        } else if kind < 0.97 {
            f32::INFINITY
        } else {
            MAX_RANGE_M * unit()
        };
    }
    (ranges, z_star)
}

fn beam(c: &mut Criterion) {
    let (ranges, z_star) = synthetic();
    let scan = Scan::<BEAMS>::from_ranges(&ranges).unwrap();
    let model = BeamModel::new(BeamIntrinsics::amcl_defaults(MAX_RANGE_M).unwrap());
    let mut g = c.benchmark_group("beam_360");
    g.throughput(Throughput::Elements(BEAMS as u64));
    g.bench_function("baseline_ln_per_beam", |b| {
        b.iter(|| {
            black_box(&ranges)
                .iter()
                .map(|&z| z.min(MAX_RANGE_M).ln())
                .sum::<f32>()
        })
    });
    g.bench_function("beam_mixture_given_zstar", |b| {
        b.iter(|| model.scan_log_likelihood(black_box(&scan), black_box(&z_star[..])))
    });
    g.finish();
}

criterion_group!(benches, beam);
criterion_main!(benches);
