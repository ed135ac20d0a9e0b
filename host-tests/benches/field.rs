//! Likelihood field ns/beam next to an AMCL-style f64 loop on the same distance data, the exact
//! transform on a 400 × 400 grid and on the Willow map, and blob bytes per cell.
//!
//! Run: `cargo bench -p host-tests --bench field -- --warm-up-time 1 --measurement-time 3`
//! (`-- exact_edt ...` for the transform alone, `-- blob_build` for the raw and tiled builds of
//! the Willow blob). Each transform runs next to a baseline of two
//! plain passes over the same grid (copy, then sum), so its time is also a ratio to that.
//! Per-beam figures: criterion's "thrpt" line is in beams per second (elements); ns/beam is its
//! inverse. The ratio to report is the AMCL-style time over the likelihood-field time, for the
//! per-pose path (`LikelihoodField::score`) and the prepared one (`PreparedScan::score`, the
//! scan prepared once per 200 poses, inside the timed region).

use beamfield::field::{edt_scratch_len, squared_edt, EdtScratch, FieldView, EDT_INFINITY};
use beamfield::{BeamLayout, LikelihoodField, LikelihoodParams, Pose, Scan, SensorMount};
use beamfield_tools::blob::{build_blob, edt_seeds};
use beamfield_tools::input::map::load_map;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;

const BEAMS: usize = 360;
const POSES: usize = 200;

fn lcg(s: &mut u64) -> f64 {
    *s = s
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*s >> 11) as f64 / (1u64 << 53) as f64
}

/// AMCL's `LikelihoodFieldModel` inner loop (amcl_laser.cpp), f64: per beam a cos and a sin
/// of the beam's world angle, a projection, a map lookup of a f64 distance, an exp, and the
/// `p += pz³` accumulation. Distances are the same (decoded) values the blob stores.
struct AmclStyle {
    dist: Vec<f64>,
    width: i64,
    height: i64,
    res: f64,
    origin: (f64, f64),
    max_occ_dist: f64,
}

impl AmclStyle {
    fn score(&self, ranges: &[f32], bearings: &[f64], pose: (f64, f64, f64), z_max: f64) -> f64 {
        let (z_hit, z_rand, sigma) = (0.95, 0.05, 0.2);
        let z_hit_denom = 2.0 * sigma * sigma;
        let z_rand_mult = 1.0 / z_max;
        let mut p = 1.0;
        for (&r, &b) in ranges.iter().zip(bearings) {
            let r = f64::from(r);
            if r >= z_max || r.is_nan() {
                continue;
            }
            let hx = pose.0 + r * (pose.2 + b).cos();
            let hy = pose.1 + r * (pose.2 + b).sin();
            let mi = ((hx - self.origin.0) / self.res).floor() as i64;
            let mj = ((hy - self.origin.1) / self.res).floor() as i64;
            let z = if mi < 0 || mj < 0 || mi >= self.width || mj >= self.height {
                self.max_occ_dist
            } else {
                self.dist[(mj * self.width + mi) as usize]
            };
            let mut pz = 0.0;
            pz += z_hit * (-(z * z) / z_hit_denom).exp();
            pz += z_rand * z_rand_mult;
            p += pz * pz * pz;
        }
        p
    }
}

fn likelihood(c: &mut Criterion) {
    let m = load_map(&host_tests::data_dir().join("map_turtlebot3_world/map.yaml")).unwrap();
    let blob = build_blob(&m, 2.0).unwrap();
    let view = FieldView::parse(&blob).unwrap();
    eprintln!(
        "blob bytes per cell: TurtleBot3 {} bytes / {} cells = {:.5}",
        blob.len(),
        m.width * m.height,
        blob.len() as f64 / f64::from(m.width * m.height)
    );
    let z_max = 3.5f32;
    let lf = LikelihoodField::new(view, LikelihoodParams::amcl_defaults(z_max).unwrap());
    let layout = BeamLayout::<BEAMS>::uniform(
        -std::f32::consts::PI,
        std::f32::consts::TAU / BEAMS as f32,
        BEAMS,
        z_max,
        SensorMount::CENTERED,
    )
    .unwrap();
    let mut s = 7u64;
    let ranges: Vec<f32> = (0..BEAMS)
        .map(|_| (0.2 + lcg(&mut s) * 3.2) as f32)
        .collect();
    let scan = Scan::<BEAMS>::from_ranges(&ranges).unwrap();
    let poses: Vec<Pose> = (0..POSES)
        .map(|_| {
            Pose::new(
                (lcg(&mut s) * 4.0 - 2.0) as f32,
                (lcg(&mut s) * 4.0 - 2.0) as f32,
                ((lcg(&mut s) - 0.5) * std::f64::consts::TAU) as f32,
            )
        })
        .collect();
    let amcl = AmclStyle {
        dist: blob[beamfield::field::BLOB_HEADER_LEN..]
            .iter()
            .map(|&c| f64::from(c) * 2.0 / 255.0)
            .collect(),
        width: i64::from(m.width),
        height: i64::from(m.height),
        res: m.resolution_m,
        origin: (m.origin_x_m, m.origin_y_m),
        max_occ_dist: 2.0,
    };
    let bearings: Vec<f64> = layout
        .beams()
        .iter()
        .map(|b| f64::from(b.bearing_rad))
        .collect();
    let mut g = c.benchmark_group("per_beam");
    g.throughput(Throughput::Elements((BEAMS * POSES) as u64));
    g.bench_function("likelihood_field_f32_table", |b| {
        b.iter(|| {
            let mut acc = 0.0f32;
            for p in &poses {
                acc += lf.score(&layout, &scan, black_box(p)).log_likelihood;
            }
            acc
        })
    });
    // The prepared path: the scan is prepared once per iteration (one scan, 200 poses), inside
    // the timed region, so its cost is included.
    g.bench_function("likelihood_field_prepared", |b| {
        b.iter(|| {
            let prep = lf.prepare(&layout, black_box(&scan));
            let mut acc = 0.0f32;
            for p in &poses {
                acc += prep.score(black_box(p)).log_likelihood;
            }
            acc
        })
    });
    g.bench_function("amcl_style_f64_cos_sin_exp", |b| {
        b.iter(|| {
            let mut acc = 0.0f64;
            for p in &poses {
                let p = black_box(p);
                acc += amcl.score(
                    &ranges,
                    &bearings,
                    (f64::from(p.x_m), f64::from(p.y_m), f64::from(p.theta_rad)),
                    f64::from(z_max),
                );
            }
            acc
        })
    });
    g.finish();
}

fn transform(c: &mut Criterion) {
    let mut g = c.benchmark_group("exact_edt");
    // 400 × 400 with ~3 % occupied cells (random).
    let (w, h) = (400usize, 400usize);
    let mut s = 11u64;
    let seeds400: Vec<u32> = (0..w * h)
        .map(|_| if lcg(&mut s) < 0.03 { 0 } else { EDT_INFINITY })
        .collect();
    let willow =
        load_map(&host_tests::data_dir().join("map_willow_garage/willow-full-0.05.yaml")).unwrap();
    let seeds_willow = edt_seeds(&willow);
    let wb = build_blob(&willow, 2.0).unwrap();
    eprintln!(
        "blob bytes per cell: Willow {} bytes / {} cells = {:.5}",
        wb.len(),
        willow.width * willow.height,
        wb.len() as f64 / f64::from(willow.width * willow.height)
    );
    for (name, seeds, w, h) in [
        ("400x400", &seeds400, w, h),
        (
            "willow_1165x945",
            &seeds_willow,
            willow.width as usize,
            willow.height as usize,
        ),
    ] {
        let n = edt_scratch_len(w, h);
        let (mut a, mut bb, mut l) = (vec![0u32; n], vec![0i64; n], vec![0u32; n]);
        let mut grid = seeds.clone();
        g.throughput(Throughput::Elements((w * h) as u64));
        // Baseline for the ratio: the same copy of the seeds each iteration does, plus one
        // read of every cell (a wrapping sum), i.e. two passes over the grid in memory order.
        g.bench_function(format!("{name}_copy_sum_baseline"), |b| {
            b.iter(|| {
                grid.copy_from_slice(seeds);
                black_box(grid.iter().fold(0u32, |a, &v| a.wrapping_add(v)))
            })
        });
        g.bench_function(name, |b| {
            b.iter(|| {
                grid.copy_from_slice(seeds);
                squared_edt(
                    &mut grid,
                    w,
                    h,
                    EdtScratch {
                        sites: &mut a,
                        bounds: &mut bb,
                        heights: &mut l,
                    },
                )
                .unwrap();
                black_box(grid[0])
            })
        });
    }
    g.finish();
}

/// Building the Willow Garage blob from the loaded map, raw (transform + encode) and tiled
/// (the same, then deduplicated 4 × 4 tiles): the ratio to report is tiled over raw.
/// `-- blob_build` runs these alone.
fn blob_build(c: &mut Criterion) {
    use beamfield_tools::blob::{build_blob_encoded, Encoding};
    let map = load_map(&host_tests::data_dir().join("map_willow_garage/willow-full-0.05.yaml"))
        .expect("Willow map");
    let mut g = c.benchmark_group("blob_build");
    g.sample_size(10);
    for (name, enc) in [
        ("willow_raw", Encoding::Raw),
        ("willow_tiled", Encoding::Tiled),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| build_blob_encoded(black_box(&map), 2.0, enc).expect("blob"))
        });
    }
    g.finish();
}

criterion_group!(benches, likelihood, transform, blob_build);
criterion_main!(benches);
