//! The race's host timings with the variants alternated, for a machine whose speed drifts
//! between criterion runs: in each round every variant runs [`BLOCK`] passes in a row (a pass =
//! the race's 91 Intel scans, 16,380 beams); the first pass of a block is dropped (the variant
//! before it has evicted its data: the AMCL-style map alone is 12.5 MB), the others are kept.
//! Reported per variant: the fastest kept pass and the quartiles, in ns per beam, and as ratios
//! to the crate's beam model. No assertions: timings are reported, not tested.
//!
//! `cargo run --release -p host-tests --example race_timing [ROUNDS]` (default 50 rounds).

#[path = "../common/intel_race.rs"]
mod intel_race;

#[path = "../common/amcl_beam.rs"]
mod amcl_beam;

use beamfield::{SensorModel, Stride};
use intel_race::N;
use std::hint::black_box;
use std::time::Instant;

/// Passes of one variant in a row per round; the first is dropped.
const BLOCK: usize = 4;

fn main() {
    let rounds: usize = std::env::args()
        .nth(1)
        .map_or(50, |s| s.parse().expect("rounds: a whole number"));
    let data = intel_race::load();
    let (beam, field) = intel_race::models(&data);
    let amcl = amcl_beam::AmclBeam::new(beam.caster().view(), beam.model().intrinsics());
    let layout = &data.layout;
    let scans = &data.scans;
    let max = data.max_range_m;
    let bearings: Vec<f64> = layout
        .beams()
        .iter()
        .map(|b| f64::from(b.bearing_rad))
        .collect();
    let beams = (scans.len() * N) as f64;

    type Variant<'a> = (&'a str, Box<dyn Fn() -> f64 + 'a>);
    let variants: Vec<Variant<'_>> = vec![
        (
            "baseline: one f32 ln per beam",
            Box::new(|| {
                let mut acc = 0.0f32;
                for (_, scan, _) in black_box(scans) {
                    acc += scan
                        .ranges_m()
                        .iter()
                        .map(|&z| z.min(max).ln())
                        .sum::<f32>();
                }
                f64::from(acc)
            }),
        ),
        (
            "likelihood field (score)",
            Box::new(|| {
                let mut acc = 0.0f32;
                for (_, scan, pose) in scans {
                    acc += field.score(layout, scan, black_box(pose)).log_likelihood;
                }
                f64::from(acc)
            }),
        ),
        (
            "beam model, casts through the blob",
            Box::new(|| {
                let mut acc = 0.0f32;
                for (_, scan, pose) in scans {
                    acc += beam.score(layout, scan, black_box(pose)).log_likelihood;
                }
                f64::from(acc)
            }),
        ),
        (
            "casts alone (cast_layout)",
            Box::new(|| {
                let mut z_star = [0.0f32; N];
                let mut acc = 0.0f32;
                for (_, _, pose) in scans {
                    beam.cast_layout(layout, black_box(pose), Stride::ONE, &mut z_star);
                    acc += z_star.iter().sum::<f32>();
                }
                f64::from(acc)
            }),
        ),
        (
            "AMCL-style beam model (Bresenham, f64)",
            Box::new(|| {
                let mut acc = 0.0f64;
                for (_, scan, pose) in scans {
                    let b = scan
                        .ranges_m()
                        .iter()
                        .copied()
                        .zip(bearings.iter().copied());
                    acc += amcl.score(b, black_box(pose));
                }
                acc
            }),
        ),
        (
            "AMCL-style casts alone",
            Box::new(|| {
                let mut acc = 0.0f64;
                for (_, _, pose) in scans {
                    let pose = black_box(pose);
                    let (x, y, t) = (
                        f64::from(pose.x_m),
                        f64::from(pose.y_m),
                        f64::from(pose.theta_rad),
                    );
                    acc += bearings
                        .iter()
                        .map(|&b| amcl.calc_range(x, y, t + b))
                        .sum::<f64>();
                }
                acc
            }),
        ),
    ];

    let mut times: Vec<Vec<f64>> = vec![Vec::with_capacity(rounds * BLOCK); variants.len()];
    let mut sink = 0.0f64;
    let step = (rounds / 10).max(1);
    for r in 0..rounds {
        for ((_, f), t) in variants.iter().zip(times.iter_mut()) {
            for k in 0..BLOCK {
                let start = Instant::now();
                sink += black_box(f());
                if k > 0 {
                    t.push(start.elapsed().as_secs_f64() * 1e9 / beams);
                }
            }
        }
        if (r + 1) % step == 0 || r + 1 == rounds {
            eprintln!("round {} of {rounds}", r + 1);
        }
    }
    for t in &mut times {
        t.sort_by(f64::total_cmp);
    }
    let q = |t: &[f64], f: f64| t[((t.len() - 1) as f64 * f).round() as usize];
    let beam_min = q(&times[2], 0.0);
    let beam_med = q(&times[2], 0.5);
    println!(
        "{rounds} rounds of {BLOCK} passes per variant (first of each dropped), {beams} beams per pass; ns per beam (ratio to the crate's beam model: fastest / median)"
    );
    println!(
        "{:<40} {:>9} {:>9} {:>9} {:>15}",
        "variant", "fastest", "25th pct", "median", "ratio"
    );
    for ((name, _), t) in variants.iter().zip(&times) {
        println!(
            "{:<40} {:>9.1} {:>9.1} {:>9.1} {:>7.2} / {:<5.2}",
            name,
            q(t, 0.0),
            q(t, 0.25),
            q(t, 0.5),
            q(t, 0.0) / beam_min,
            q(t, 0.5) / beam_med
        );
    }
    eprintln!("(checksum {sink:.3})");
}
