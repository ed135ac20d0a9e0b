//! The race of the chapter (§6.4) on a real map and real scans: the beam model with on-device
//! ray casting (`BeamFieldModel`) against the likelihood field (`LikelihoodField::score`), both
//! scoring whole scans of the Intel lab log at their logged poses, against the demo firmware's
//! blob of the Intel map. Baselines measured in the same run over the same readings: a loop
//! that only sums the ranges, one `f32::ln` per beam (as `benches/beam.rs`), and an AMCL-style
//! beam model (`workloads/src/amcl_beam.rs`: Bresenham casts, f64 mixture, `p += pz³`) on the same
//! walls, whole and its casts alone.
//!
//! Run: `cargo bench -p host-tests --bench race`. One iteration scores all 91 scans (every 10th
//! of the 910, 16,380 beams): criterion's "thrpt" is in scan evaluations per second (÷1000:
//! evaluations per ms); ns/beam = time per iteration / 16,380. Quote ratios to the baselines,
//! not absolute times across machines.
//!
//! Also measured: the ray casts alone (`BeamFieldModel::cast_layout`), to split the beam
//! model's cost into z* and mixture, and the batch cast `RayCaster::cast_dirs_lanes` over whole
//! scans with 1 (one ray at a time), 2, 4 and 8 (the default, `CAST_LANES`) interleaved rays.

use host_workloads::intel_race;

use host_workloads::amcl_beam;

use host_workloads::race_passes;

use beamfield::{SensorModel, Stride};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use intel_race::N;
use std::hint::black_box;

fn race(c: &mut Criterion) {
    let data = intel_race::load();
    let (beam, field) = intel_race::models(&data);
    let scans = &data.scans;
    let layout = &data.layout;
    let max = data.max_range_m;
    let beams = scans.len() * N;
    // Both models' totals once, so a reader sees what is being computed (and that it is finite).
    let (mut ll_beam, mut ll_field) = (0.0f64, 0.0f64);
    for (_, scan, pose) in scans {
        ll_beam += f64::from(beam.score(layout, scan, pose).log_likelihood);
        ll_field += f64::from(field.score(layout, scan, pose).log_likelihood);
    }
    eprintln!(
        "race: {} scans x {N} beams = {beams} beams per iteration; total log-likelihood: beam model {ll_beam:.1}, likelihood field {ll_field:.1}",
        scans.len()
    );

    cast_work_histogram(&beam, &data);

    // The AMCL-style baseline (Bresenham casts, f64 mixture, `p += pz³`) on the same walls;
    // `tests/race_amcl_baseline.rs` checks that it sees them.
    let amcl = amcl_beam::AmclBeam::like(&beam, layout);

    for min_jump in [1.0f32, 3.0, 5.0, 8.0, 12.0] {
        let tuned = beamfield::BeamFieldModel::new(
            *beam.model(),
            beam.caster().with_min_jump_cells(min_jump),
        );
        let (mut jumps, mut steps, mut moved) = (0u64, 0u64, 0usize);
        let (mut z0, mut z1) = ([0.0f32; N], [0.0f32; N]);
        for (_, _, pose) in scans {
            let mut traces = [beamfield::CastTrace::default(); N];
            tuned.cast_layout_traced(layout, pose, &mut z1, &mut traces);
            beam.cast_layout(layout, pose, Stride::ONE, &mut z0);
            jumps += traces.iter().map(|t| u64::from(t.jumps)).sum::<u64>();
            steps += traces.iter().map(|t| u64::from(t.steps)).sum::<u64>();
            moved += z0
                .iter()
                .zip(&z1)
                .filter(|(a, b)| (*a - *b).abs() > 1e-4)
                .count();
        }
        eprintln!(
            "race: min jump {min_jump} cells: mean jumps {:.2}, steps {:.2} per cast; {moved} casts differ from the default by > 0.1 mm",
            jumps as f64 / beams as f64,
            steps as f64 / beams as f64
        );
    }

    let mut g = c.benchmark_group("race_intel");
    g.throughput(Throughput::Elements(scans.len() as u64));
    g.bench_function("baseline_sum_ranges", |b| {
        b.iter(|| {
            let mut acc = 0.0f32;
            for (_, scan, _) in black_box(scans) {
                acc += scan.ranges_m().iter().map(|&z| z.min(max)).sum::<f32>();
            }
            acc
        })
    });
    g.bench_function("baseline_ln_per_beam", |b| {
        b.iter(|| race_passes::ln_per_beam(&data))
    });
    g.bench_function("likelihood_field", |b| {
        b.iter(|| race_passes::likelihood_field(&field, &data))
    });
    g.bench_function("beam_model_raycast", |b| {
        b.iter(|| race_passes::beam_model(&beam, &data))
    });
    g.bench_function("amcl_style_beam_model", |b| {
        b.iter(|| race_passes::amcl_beam_model(&amcl, &data))
    });
    g.bench_function("amcl_style_raycast_only", |b| {
        b.iter(|| race_passes::amcl_casts(&amcl, &data))
    });
    g.bench_function("raycast_only", |b| {
        b.iter(|| race_passes::casts(&beam, &data))
    });
    let mut z_star = [0.0f32; N];
    // The batch cast (`RayCaster::cast_dirs`) with other lane counts than the default, whole
    // scans at once (the model casts blocks of `CAST_BLOCK` beams); 1 lane = one ray at a time.
    let dirs_of = |pose: &beamfield::Pose| -> [[f32; 2]; N] {
        let (s, c) = beamfield::math::sin_cos(pose.theta_rad);
        let mut d = [[0.0f32; 2]; N];
        for (d, b) in d.iter_mut().zip(layout.beams()) {
            *d = [c * b.cos - s * b.sin, s * b.cos + c * b.sin];
        }
        d
    };
    macro_rules! lanes {
        ($($k:literal),*) => {$(
            g.bench_function(concat!("raycast_lanes_", $k), |b| {
                b.iter(|| {
                    let mut acc = 0.0f32;
                    for (_, _, pose) in scans {
                        let pose = black_box(pose);
                        let dirs = dirs_of(pose);
                        beam.caster().cast_dirs_lanes::<$k>(pose.x_m, pose.y_m, &dirs, max, &mut z_star);
                        acc += z_star.iter().sum::<f32>();
                    }
                    acc
                })
            });
        )*};
    }
    lanes!(1, 2, 4, 8);
    // The same casts with other thresholds for taking a sphere-tracing jump (default 2 cells).
    for min_jump in [1.0f32, 3.0, 5.0, 8.0, 12.0] {
        let tuned = beamfield::BeamFieldModel::new(
            *beam.model(),
            beam.caster().with_min_jump_cells(min_jump),
        );
        g.bench_function(format!("raycast_only_min_jump_{min_jump}"), |b| {
            b.iter(|| race_passes::casts(&tuned, &data))
        });
    }
    g.finish();
}

/// Where the ray casting's time goes: per cast (the bench's 16,380), the sphere-tracing jumps
/// and the cell-by-cell steps of the grid traversal, as histograms, split by whether the
/// reading is a max-range one.
fn cast_work_histogram(beam: &beamfield::BeamFieldModel<'_>, data: &intel_race::RaceData) {
    let mut z_star = [0.0f32; N];
    let mut all: Vec<(beamfield::CastTrace, bool)> = Vec::new();
    for (_, scan, pose) in &data.scans {
        let mut traces = [beamfield::CastTrace::default(); N];
        beam.cast_layout_traced(&data.layout, pose, &mut z_star, &mut traces);
        for (t, &z) in traces.iter().zip(scan.ranges_m()) {
            all.push((*t, z >= data.max_range_m));
        }
    }
    let edges = [0u32, 1, 2, 4, 8, 16, 32, 64, 128, 256, 512, u32::MAX];
    let hist = |f: &dyn Fn(&beamfield::CastTrace) -> u32, max_only: Option<bool>| {
        let mut counts = vec![0usize; edges.len() - 1];
        let (mut n, mut sum) = (0usize, 0u64);
        for (t, is_max) in &all {
            if max_only.is_some_and(|m| m != *is_max) {
                continue;
            }
            let v = f(t);
            n += 1;
            sum += u64::from(v);
            if let Some(b) = edges.windows(2).position(|w| v >= w[0] && v < w[1]) {
                counts[b] += 1;
            }
        }
        let bins: Vec<String> = edges
            .windows(2)
            .zip(&counts)
            .map(|(w, c)| {
                let hi = if w[1] == u32::MAX {
                    "inf".to_string()
                } else {
                    w[1].to_string()
                };
                format!("[{},{}):{}", w[0], hi, c)
            })
            .collect();
        format!(
            "n {n}, mean {:.2}; {}",
            sum as f64 / n.max(1) as f64,
            bins.join(" ")
        )
    };
    let steps = |t: &beamfield::CastTrace| t.steps;
    let jumps = |t: &beamfield::CastTrace| t.jumps;
    for (label, sel) in [
        ("all", None),
        ("non-max", Some(false)),
        ("max-range", Some(true)),
    ] {
        eprintln!("race: cast steps per cast ({label}): {}", hist(&steps, sel));
        eprintln!("race: cast jumps per cast ({label}): {}", hist(&jumps, sel));
    }
}

criterion_group!(benches, race);
criterion_main!(benches);
