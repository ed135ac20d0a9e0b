//! Runs the `em` bench's fit (24 iterations over the same 4,500 beams) a given number of times,
//! for instruction counting under `valgrind --tool=cachegrind` (no timing of its own).
//!
//! `cargo build --profile profiling -p host-tests --example em_profile`, then
//! `valgrind --tool=cachegrind target/profiling/examples/em_profile truncated 10` (or `textbook`,
//! `exact`); `skip` as the update runs everything but the fits (the harness's own count).
//! Prints the passes of one fit, so a count can be divided per pass and per reading.

use host_workloads::em_data;

use beamfield::em::{fit_slices, EmConfig, ShapeUpdate};
use beamfield::BeamIntrinsics;
use em_data::{data, BEAMS, ITERATIONS};
use std::hint::black_box;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map_or("truncated", String::as_str);
    let reps: usize = args.get(2).map_or(10, |s| s.parse().unwrap());
    let shape = match which {
        "textbook" => Some(ShapeUpdate::Textbook),
        "truncated" => Some(ShapeUpdate::Truncated),
        "exact" => Some(ShapeUpdate::TruncatedExact),
        "skip" => None,
        other => panic!("unknown update {other}"),
    };
    let (z, zs) = data();
    let start = BeamIntrinsics::amcl_defaults(30.0).unwrap();
    let mut trace = [0.0f64; 32];
    let mut passes = 0;
    let mut acc = 0.0f64;
    for _ in 0..reps {
        let Some(shape) = shape else {
            acc += black_box(&z).iter().map(|&v| f64::from(v)).sum::<f64>();
            continue;
        };
        let cfg = EmConfig {
            max_iterations: ITERATIONS,
            tolerance_nats: 0.0,
            shape_update: shape,
            ..EmConfig::default()
        };
        let out = fit_slices(&cfg, black_box(start), &z, &zs, &mut trace).unwrap();
        passes = out.passes;
        acc += f64::from(out.intrinsics.sigma_hit_m()) + trace[out.trace_len - 1];
    }
    println!("{which} x{reps}: {passes} passes of {BEAMS} readings per fit, checksum {acc}");
}
