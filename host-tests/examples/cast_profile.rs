//! Runs the race's ray casts (`cast_layout` over the 91 Intel scans, 16,380 casts) a given
//! number of times, for instruction and branch counting under
//! `valgrind --tool=cachegrind --branch-sim=yes` (no timing of its own).
//!
//! `cargo build --profile profiling -p host-tests --example cast_profile`, then
//! `valgrind --tool=cachegrind --branch-sim=yes target/profiling/examples/cast_profile 3`;
//! `0` repetitions runs only the harness (its own count, to subtract). A second argument picks
//! what is cast: `crate` (default, `BeamFieldModel::cast_layout`), `one` (the crate's casts one
//! ray at a time, `RayCaster::cast_dir`) or `amcl` (the race's AMCL-style Bresenham baseline).
//! Prints the checksum of the ranges, so two builds can be checked to cast the same.

use host_workloads::intel_race;

use host_workloads::amcl_beam;

use beamfield::Stride;
use std::hint::black_box;

fn main() {
    let reps: usize = std::env::args()
        .nth(1)
        .map_or(3, |s| s.parse().expect("repetitions: a whole number"));
    let which = std::env::args().nth(2).unwrap_or_else(|| "crate".into());
    let data = intel_race::load();
    let (beam, _) = intel_race::models(&data);
    let amcl = amcl_beam::AmclBeam::like(&beam, &data.layout);
    let mut z_amcl = [0.0f64; intel_race::N];
    let max = data.max_range_m;
    let mut z_star = [0.0f32; intel_race::N];
    let mut sum = 0.0f64;
    for _ in 0..reps {
        for (_, _, pose) in &data.scans {
            let pose = black_box(pose);
            match which.as_str() {
                "crate" => beam.cast_layout(&data.layout, pose, Stride::ONE, &mut z_star),
                "one" => {
                    for (z, b) in z_star.iter_mut().zip(data.layout.beams()) {
                        *z = beam.caster().cast(
                            pose.x_m,
                            pose.y_m,
                            pose.theta_rad + b.bearing_rad,
                            max,
                        );
                    }
                }
                "amcl" => {
                    amcl.cast_scan(pose, &mut z_amcl);
                    for (z, &a) in z_star.iter_mut().zip(&z_amcl) {
                        *z = a as f32;
                    }
                }
                other => panic!("unknown caster {other}: crate, one or amcl"),
            }
            sum += z_star.iter().map(|&z| f64::from(z)).sum::<f64>();
        }
    }
    println!(
        "{which}: {reps} repetitions of {} casts; sum of ranges {sum:.6} m",
        data.scans.len() * intel_race::N
    );
}
