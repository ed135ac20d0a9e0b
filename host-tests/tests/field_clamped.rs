//! A clamped tiled blob (`beamfield field build --encoding tiled --clamp-m 0.5`), the
//! bounded-lossy way to the compressed field's size goal (docs/blob-format.md, "Clamped tiled
//! blobs"): codes of distances up to the clamp distance unchanged, everything beyond it stored
//! as the clamp code. Checked here on the real maps against the default 2 m raw blob: the
//! codes cell by cell, the f64 bound on what the clamp can change in a likelihood term, the
//! Intel demo's scores and best poses, the ray caster's ranges (clamped codes are lower
//! bounds), and the bytes per cell.

use beamfield::field::{FieldView, LikelihoodField, LikelihoodParams, ENCODING_TILED};
use beamfield::{BeamLayout, CastTrace, Pose, RayCaster, Scan, SensorMount};
use beamfield_fixtures::demo_plan::{fine_search, COARSE, SIGMA_HIT_M, Z_HIT, Z_RAND};
use beamfield_tools::beam_fit::map_from_log;
use beamfield_tools::blob::{build_blob, build_blob_clamped};
use beamfield_tools::demo_assets::SCAN_INDICES;
use beamfield_tools::input::carmen::{CarmenLog, ReadOptions};
use beamfield_tools::input::map::load_map;

const N: usize = 180;
/// The clamp distance measured in docs/blob-format.md, metres.
const CLAMP_M: f32 = 0.5;
/// Its code at the default step of 2/255 m: round(0.5 · 255 / 2) = round(63.75).
const CLAMP_CODE: u8 = 64;
/// The default clamp distance, metres.
const FULL_M: f32 = 2.0;

fn intel_log() -> CarmenLog {
    CarmenLog::read_path(
        &host_tests::data_dir().join("laser_intel_lab/intel-corrected.log"),
        ReadOptions::default(),
    )
    .unwrap()
}

/// The Intel map's 2 m raw blob and its tiled blob clamped at 0.5 m, both built from the
/// log's map.
fn intel_blobs(log: &CarmenLog) -> (Vec<u8>, Vec<u8>) {
    let map = map_from_log(log, log.max_range.value_m().unwrap()).unwrap();
    (
        build_blob(&map, FULL_M).unwrap(),
        build_blob_clamped(&map, FULL_M, CLAMP_M).unwrap(),
    )
}

/// Every cell: the clamped blob's code is the 2 m blob's code, saturated at the clamp code;
/// the view reports the clamp distance.
#[test]
fn clamped_codes_are_saturated_codes() {
    let log = intel_log();
    let (full, clamped) = intel_blobs(&log);
    let (f, c) = (
        FieldView::parse(&full).unwrap(),
        FieldView::parse(&clamped).unwrap(),
    );
    assert_eq!(c.encoding(), ENCODING_TILED);
    assert_eq!(c.clamp_code(), Some(CLAMP_CODE));
    assert_eq!(c.clamp_m(), Some(f32::from(CLAMP_CODE) * (FULL_M / 255.0)));
    assert_eq!(f.clamp_code(), None);
    assert_eq!((f.width(), f.height()), (c.width(), c.height()));
    let (mut kept, mut clamped_cells) = (0usize, 0usize);
    for iy in 0..f.height() {
        for ix in 0..f.width() {
            let cf = f.code(ix, iy).unwrap();
            let cc = c.code(ix, iy).unwrap();
            if cf < CLAMP_CODE {
                assert_eq!(cc, cf, "cell ({ix}, {iy})");
                kept += 1;
            } else {
                assert_eq!(cc, CLAMP_CODE, "cell ({ix}, {iy}): code {cf}");
                clamped_cells += 1;
            }
        }
    }
    assert!(
        kept > 0 && clamped_cells > 0,
        "{kept} kept, {clamped_cells} clamped"
    );
}

/// The likelihood term of a clamped distance (`d_max`) against that of any farther one: the
/// largest change the clamp can make to one beam's log-likelihood, computed in f64 from Thrun
/// eq. 6.33's mixture, `ln(1 + z_hit·N(d_max; σ) / (z_rand / z_max))`.
fn clamp_bound(sigma_m: f64, z_hit: f64, z_rand: f64, max_range_m: f64, d_max_m: f64) -> f64 {
    let n = (-0.5 * (d_max_m / sigma_m).powi(2)).exp()
        / (sigma_m * (2.0 * std::f64::consts::PI).sqrt());
    (z_hit * n / (z_rand / max_range_m)).ln_1p()
}

/// The demo's eight scans on the 2 m raw blob and on the clamped tiled blob. At the demo's
/// σ_hit the clamp's f64 bound is below a unit in the last place of the far term, and the
/// table's terms from the clamp code up are one `f32`: so every score (prepared and per-pose
/// path) is bit for bit the same at every coarse pose, and so are the best and fine-best poses.
/// The ray casts from the logged poses agree bit for bit; the caster's work on both blobs is
/// printed.
#[test]
fn intel_demo_best_poses_unchanged() {
    let log = intel_log();
    let (full, clamped) = intel_blobs(&log);
    let max_range = log.max_range.value_m().unwrap();
    let params = LikelihoodParams::new(Z_HIT, Z_RAND, SIGMA_HIT_M, max_range).unwrap();
    let fields: Vec<LikelihoodField<'_>> = [&full[..], &clamped[..]]
        .iter()
        .map(|b| LikelihoodField::new(FieldView::parse(b).unwrap(), params))
        .collect();
    let far = [fields[0].table()[255], fields[1].table()[255]];
    let bound = clamp_bound(
        f64::from(SIGMA_HIT_M),
        f64::from(Z_HIT),
        f64::from(Z_RAND),
        f64::from(max_range),
        f64::from(CLAMP_M),
    );
    let ulp = f64::from(far[0].abs()) * f64::from(f32::EPSILON);
    assert!(bound < ulp, "bound {bound:e} vs ulp {ulp:e}");
    assert_eq!(far[0].to_bits(), far[1].to_bits(), "{far:?}");
    let table = fields[0].table();
    for c in CLAMP_CODE..=255 {
        assert_eq!(
            table[usize::from(c)].to_bits(),
            far[0].to_bits(),
            "code {c}"
        );
    }

    let layout: BeamLayout<N> = log.layout_with_mount(SensorMount::CENTERED).unwrap();
    let casters: Vec<RayCaster<'_>> = fields
        .iter()
        .map(|f| RayCaster::new(*f.view()).unwrap())
        .collect();
    let mut traces = [CastTrace::default(); 2];
    let mut compared = 0usize;
    for &i in SCAN_INDICES.iter() {
        let s = &log.scans[i];
        let scan: Scan<N> = s.to_scan().unwrap();
        let logged = s.pose;
        let prepared: Vec<_> = fields.iter().map(|f| f.prepare(&layout, &scan)).collect();
        let mut best = [(f32::NEG_INFINITY, 0usize); 2];
        for k in 0..COARSE.len() {
            let p: Pose = COARSE.pose(&logged, k);
            let a = prepared[0].score(&p).log_likelihood;
            let b = prepared[1].score(&p).log_likelihood;
            assert_eq!(a.to_bits(), b.to_bits(), "scan {i} pose {k}: {a} vs {b}");
            let a2 = fields[0].score(&layout, &scan, &p).log_likelihood;
            let b2 = fields[1].score(&layout, &scan, &p).log_likelihood;
            assert_eq!(
                a2.to_bits(),
                b2.to_bits(),
                "scan {i} pose {k} (per-pose path)"
            );
            for (j, ll) in [a, b].into_iter().enumerate() {
                if ll > best[j].0 {
                    best[j] = (ll, k);
                }
            }
            compared += 1;
        }
        assert_eq!(best[0].1, best[1].1, "scan {i}: best coarse pose");
        assert_eq!(
            fine_search(&prepared[0], &logged),
            fine_search(&prepared[1], &logged),
            "scan {i}: best fine pose"
        );
        for b in layout.beams() {
            let a = logged.theta_rad + b.bearing_rad;
            let (ux, uy) = (a.cos(), a.sin());
            let r: Vec<f32> = casters
                .iter()
                .zip(traces.iter_mut())
                .map(|(c, t)| c.cast_dir_traced(logged.x_m, logged.y_m, ux, uy, max_range, t))
                .collect();
            assert_eq!(r[0].to_bits(), r[1].to_bits(), "scan {i}: cast at {a} rad");
        }
    }
    assert_eq!(compared, SCAN_INDICES.len() * COARSE.len());
    eprintln!(
        "clamp {CLAMP_M} m: casts from the logged poses: jumps {} vs {}, cell steps {} vs {} \
         (2 m raw vs clamped)",
        traces[0].jumps, traces[1].jumps, traces[0].steps, traces[1].steps
    );
}

/// The size goal: mean bytes per cell at most 0.25 over TurtleBot3, Willow Garage and the
/// Intel lab (5 cm), none above 0.4, with the 0.5 m clamp (d_max 2 m) and the tiled encoding.
#[test]
fn clamped_tiled_blobs_meet_the_size_goal() {
    let log = intel_log();
    let mut per_cell = Vec::new();
    for rel in [
        "map_turtlebot3_world/map.yaml",
        "map_willow_garage/willow-full-0.05.yaml",
    ] {
        let map = load_map(&host_tests::data_dir().join(rel)).unwrap();
        let b = build_blob_clamped(&map, FULL_M, CLAMP_M).unwrap();
        let v = FieldView::parse(&b).unwrap();
        per_cell.push((rel, b.len() as f64 / f64::from(v.width() * v.height())));
    }
    let (_, clamped) = intel_blobs(&log);
    let v = FieldView::parse(&clamped).unwrap();
    per_cell.push((
        "intel (from the log)",
        clamped.len() as f64 / f64::from(v.width() * v.height()),
    ));
    let mean = per_cell.iter().map(|p| p.1).sum::<f64>() / 3.0;
    eprintln!("bytes per cell at {CLAMP_M} m, tiled: {per_cell:?}, mean {mean:.4}");
    assert!(mean <= 0.25, "mean {mean}");
    for (name, b) in &per_cell {
        assert!(*b <= 0.4, "{name}: {b}");
    }
}
