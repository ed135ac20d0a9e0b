//! The race's host timings with the variants alternated, for a machine whose speed drifts
//! between criterion runs: in each round every variant runs [`BLOCK`] passes in a row (a pass =
//! the race's 91 Intel scans, 16,380 beams); the first pass of a block is dropped (the variant
//! before it has evicted its data: the AMCL-style map alone is 12.5 MB), the others are kept.
//! Reported per variant: the fastest kept pass and the quartiles, in ns per beam, and as ratios
//! to the crate's beam model. No assertions: timings are reported, not tested.
//!
//! `cargo run --release -p host-tests --example race_timing [ROUNDS]` (default 50 rounds).

use host_workloads::intel_race;

use host_workloads::amcl_beam;

use host_workloads::race_passes;

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
    let amcl = amcl_beam::AmclBeam::like(&beam, &data.layout);
    let beams = (data.scans.len() * N) as f64;

    type Variant<'a> = (&'a str, Box<dyn Fn() -> f64 + 'a>);
    let variants: Vec<Variant<'_>> = vec![
        (
            "baseline: one f32 ln per beam",
            Box::new(|| f64::from(race_passes::ln_per_beam(&data))),
        ),
        (
            "likelihood field (score)",
            Box::new(|| f64::from(race_passes::likelihood_field(&field, &data))),
        ),
        (
            "beam model, casts through the blob",
            Box::new(|| f64::from(race_passes::beam_model(&beam, &data))),
        ),
        (
            "casts alone (cast_layout)",
            Box::new(|| f64::from(race_passes::casts(&beam, &data))),
        ),
        (
            "AMCL-style beam model (Bresenham, f64)",
            Box::new(|| race_passes::amcl_beam_model(&amcl, &data)),
        ),
        (
            "AMCL-style casts alone",
            Box::new(|| race_passes::amcl_casts(&amcl, &data)),
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
