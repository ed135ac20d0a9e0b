//! Runs the race's ray casts (`cast_layout` over the 91 Intel scans, 16,380 casts) a given
//! number of times, for instruction and branch counting under
//! `valgrind --tool=cachegrind --branch-sim=yes` (no timing of its own).
//!
//! `cargo build --release -p host-tests --example cast_profile`, then
//! `valgrind --tool=cachegrind --branch-sim=yes target/release/examples/cast_profile 3`;
//! `0` repetitions runs only the harness (its own count, to subtract). Prints the checksum of
//! the ranges, so two builds can be checked to cast the same.

#[path = "../common/intel_race.rs"]
mod intel_race;

use beamfield::Stride;
use std::hint::black_box;

fn main() {
    let reps: usize = std::env::args()
        .nth(1)
        .map_or(3, |s| s.parse().expect("repetitions: a whole number"));
    let data = intel_race::load();
    let (beam, _) = intel_race::models(&data);
    let mut z_star = [0.0f32; intel_race::N];
    let mut sum = 0.0f64;
    for _ in 0..reps {
        for (_, _, pose) in &data.scans {
            beam.cast_layout(&data.layout, black_box(pose), Stride::ONE, &mut z_star);
            sum += z_star.iter().map(|&z| f64::from(z)).sum::<f64>();
        }
    }
    println!(
        "{reps} repetitions of {} casts; sum of ranges {sum:.6} m",
        data.scans.len() * intel_race::N
    );
}
