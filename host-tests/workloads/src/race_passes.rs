//! One pass of each variant the race times, over all of the race's scans (91 Intel scans, 16,380
//! beams): shared by `benches/race.rs` (criterion) and `examples/race_timing.rs` (alternated
//! rounds), so both time the same code. Each returns a sum of what it computed, for
//! `black_box`.

use crate::amcl_beam::AmclBeam;
use crate::intel_race::{RaceData, N};
use beamfield::{BeamFieldModel, LikelihoodField, SensorModel, Stride};
use std::hint::black_box;

/// Baseline: one `f32::ln` per reading (readings clamped to the range limit).
pub fn ln_per_beam(data: &RaceData) -> f32 {
    let max = data.max_range_m;
    let mut acc = 0.0f32;
    for (_, scan, _) in black_box(&data.scans) {
        acc += scan
            .ranges_m()
            .iter()
            .map(|&z| z.min(max).ln())
            .sum::<f32>();
    }
    acc
}

/// The likelihood field's per-pose path (`score`) at each logged pose.
pub fn likelihood_field(field: &LikelihoodField<'_>, data: &RaceData) -> f32 {
    let mut acc = 0.0f32;
    for (_, scan, pose) in &data.scans {
        acc += field
            .score(&data.layout, scan, black_box(pose))
            .log_likelihood;
    }
    acc
}

/// The crate's beam model, z* cast through the blob, at each logged pose.
pub fn beam_model(beam: &BeamFieldModel<'_>, data: &RaceData) -> f32 {
    let mut acc = 0.0f32;
    for (_, scan, pose) in &data.scans {
        acc += beam
            .score(&data.layout, scan, black_box(pose))
            .log_likelihood;
    }
    acc
}

/// The crate's casts alone (`cast_layout`), summed.
pub fn casts(beam: &BeamFieldModel<'_>, data: &RaceData) -> f32 {
    let mut z_star = [0.0f32; N];
    let mut acc = 0.0f32;
    for (_, _, pose) in &data.scans {
        beam.cast_layout(&data.layout, black_box(pose), Stride::ONE, &mut z_star);
        acc += z_star.iter().sum::<f32>();
    }
    acc
}

/// The AMCL-style beam model's weight factors, summed.
pub fn amcl_beam_model(amcl: &AmclBeam, data: &RaceData) -> f64 {
    let mut acc = 0.0f64;
    for (_, scan, pose) in &data.scans {
        acc += amcl.score(scan.ranges_m(), black_box(pose));
    }
    acc
}

/// The AMCL-style casts alone, summed.
pub fn amcl_casts(amcl: &AmclBeam, data: &RaceData) -> f64 {
    let mut z_star = [0.0f64; N];
    let mut acc = 0.0f64;
    for (_, _, pose) in &data.scans {
        amcl.cast_scan(black_box(pose), &mut z_star);
        acc += z_star.iter().sum::<f64>();
    }
    acc
}
