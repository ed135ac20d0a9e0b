//! The prepared likelihood-field path ([`PreparedScan`]) against the per-pose path
//! ([`LikelihoodField::score`]) on real maps and real scans, and against the independent f64
//! reference.
//!
//! # Why the two paths can differ, and by how much
//! Both compute a beam's endpoint in grid cells from the same `f32` inputs (sensor grid
//! position `(ax, ay)`, `cos θ`, `sin θ`, the bearing's unit vector, the range, `1/cell`), in a
//! different order: `score` in `f32` (`ax + r·(c·cos β − s·sin β)`, five roundings), the prepared
//! path in fixed point with `F` fractional bits (stored endpoint rounded once in `f32` and to
//! `2^−(F+2)`, `cos θ`/`sin θ` to `2^−30`, two floored products, `ax` rounded to `2^−F`). Each
//! lands within
//!
//! ```text
//! b = 4·2^−F + 2^−21·(|ax| + |ay| + 4R + 4)   cells   (R = r / cell)
//! ```
//!
//! of the exact endpoint (the `f32` part: at most ~6 roundings of magnitude ≤ |ax| + |ay| + 2R,
//! each ≤ 2^−24 of it, doubled for the two paths), plus, when the math backend's `sin_cos` is
//! less accurate than one rounding, its excess error turned into cells ([`trig_cells`]: the
//! two paths compose the mount's yaw with the heading differently). So the paths read different cells only
//! when the exact endpoint is within `b` of a cell edge, or, off the map, when the charged
//! distance in code steps is within `b·cell/step` of a rounding boundary. For endpoints spread
//! over cells, the chance is at most `2·2b` per beam (two coordinates, a band of width `2b`
//! around each edge). The test checks each differing beam against that rule (its f64 endpoint
//! moved by at most `b` gives both codes) and the count against `Σ 4b` (over all beams scored).
//! Where no beam differs, the scores must be bit for bit equal: same terms, same order.

use beamfield::field::{FieldView, LikelihoodField, LikelihoodParams, PreparedScan};
use beamfield::{math, BeamLayout, Pose, Scan, SensorMount, Stride};
use beamfield_tools::blob::build_blob;
use beamfield_tools::input::carmen::{CarmenLog, ReadOptions};
use beamfield_tools::input::map::load_map;

const N: usize = 180;

use beamfield::mcl::XorShift64 as Rng;

/// The likelihood field with AMCL's default parameters over `blob`.
fn amcl_field(blob: &[u8], z_max: f32) -> LikelihoodField<'_> {
    LikelihoodField::new(
        FieldView::parse(blob).unwrap(),
        LikelihoodParams::amcl_defaults(z_max).unwrap(),
    )
}

fn blob_of(rel: &str) -> Vec<u8> {
    build_blob(&load_map(&host_tests::data_dir().join(rel)).unwrap(), 2.0).unwrap()
}

fn intel() -> CarmenLog {
    CarmenLog::read_path(
        &host_tests::data_dir().join("laser_intel_lab/intel-corrected.log"),
        ReadOptions::default(),
    )
    .unwrap()
}

/// The table index the view's semantics give at an f64 point (docs/models.md#field): the cell's
/// code on the map; off it, the nearest cell's code plus the distance to the map in code
/// steps, rounded, clamped at 255.
fn code64(view: &FieldView<'_>, gx: f64, gy: f64) -> u8 {
    let (w, h) = (f64::from(view.width()), f64::from(view.height()));
    if (0.0..w).contains(&gx) && (0.0..h).contains(&gy) {
        return view.code(gx as u32, gy as u32).unwrap();
    }
    let (cx, cy) = (gx.clamp(0.0, w), gy.clamp(0.0, h));
    let (ix, iy) = (
        (cx as u32).min(view.width() - 1),
        (cy as u32).min(view.height() - 1),
    );
    let spc = f64::from(view.cell_size_m()) / f64::from(view.step_m());
    let off = ((gx - cx).powi(2) + (gy - cy).powi(2)).sqrt();
    let extra = (off * spc + 0.5).min(255.0).floor();
    (f64::from(view.code(ix, iy).unwrap()) + extra).min(255.0) as u8
}

#[derive(Default)]
struct Tally {
    beams: usize,
    differing: usize,
    /// Σ 4b over the beams scored: the derived bound on the expected count of differing beams.
    bound: f64,
    equal_scores: usize,
    poses: usize,
    fallback_poses: usize,
}

/// The part of the two paths' difference that comes from the math backend's `sin_cos`, per
/// axis, in cells, for a beam of `r` cells (module docs): `score` turns the beam's unit vector
/// by the sensor heading's (cos, sin) `R'(θ + ψ)`, the prepared path by the robot heading's
/// times the mount yaw's, `R'(θ)·R'(ψ)`. With each cosine and sine off the exact value by at
/// most `ε` beyond one f32 rounding (already counted in `b`), each matrix differs from the
/// exact rotation by at most `2ε` in the row-sum norm, so the two products differ by at most
/// `2ε·√2 + √2·2ε + 4ε² + 2ε`. `ε` is the backend's documented error less a rounding
/// (`host_tests::reference_backend::SIN_COS_EXCESS`): about 4e-9 for the default backend
/// (3e-5 cells at 1,000 cells' range), 1.1e-3 for micromath (up to 8 cells at 1,000 cells,
/// which is why this test failed under micromath with the rounding bound alone).
fn trig_cells(r: f64) -> f64 {
    let e = host_tests::reference_backend::SIN_COS_EXCESS;
    r * ((4.0 * std::f64::consts::SQRT_2 + 2.0) * e + 4.0 * e * e)
}

/// Scores `scan` at `pose` both ways and checks everything the module docs promise.
fn compare(
    lf: &LikelihoodField<'_>,
    prep: &PreparedScan<'_, N>,
    layout: &BeamLayout<N>,
    scan: &Scan<N>,
    pose: &Pose,
    stride: Stride,
    t: &mut Tally,
) {
    let view = lf.view();
    let step = f64::from(view.step_m());
    let mut old = Vec::new();
    let a = lf.score_strided_with(layout, scan, pose, stride, |k, d| old.push((k, d)));
    let mut new = Vec::new();
    let b = prep.score_with(pose, |j, d| new.push((j, d)));
    assert_eq!(
        (a.scored, a.max_range, a.invalid, a.unpaired),
        (b.scored, b.max_range, b.invalid, b.unpaired)
    );
    assert_eq!(old.len(), new.len());
    assert!(b.log_likelihood.is_finite());
    // The f64 endpoint from the same f32 inputs the two paths use.
    let sensor = layout.mount().sensor_pose(pose);
    let (sin_t, cos_t) = math::sin_cos(sensor.theta_rad);
    let (ax, ay) = view.to_grid(sensor.x_m, sensor.y_m);
    let inv = f64::from(1.0f32 / view.cell_size_m());
    let frac = 2f64.powi(-(prep.frac_bits() as i32));
    let (ax, ay, c, s) = (
        f64::from(ax),
        f64::from(ay),
        f64::from(cos_t),
        f64::from(sin_t),
    );
    t.fallback_poses += usize::from(!prep.uses_fixed_point(pose));
    let mut diff_terms = 0.0f64;
    let mut sum = 0.0f32;
    for (n, (&(k, d_old), &(j, d_new))) in old.iter().zip(&new).enumerate() {
        assert_eq!(j, n);
        let code_old = (f64::from(d_old) / step).round() as u8;
        let code_new = (f64::from(d_new) / step).round() as u8;
        sum += lf.table()[usize::from(code_new)];
        let beam = layout.beams()[k];
        let r = f64::from(scan.ranges_m()[k]) * inv;
        let (bc, bs) = (f64::from(beam.cos), f64::from(beam.sin));
        let gx = ax + r * (c * bc - s * bs);
        let gy = ay + r * (s * bc + c * bs);
        let bound =
            4.0 * frac + 2f64.powi(-21) * (ax.abs() + ay.abs() + 4.0 * r + 4.0) + trig_cells(r);
        t.beams += 1;
        t.bound += 4.0 * bound;
        if code_old != code_new {
            t.differing += 1;
            diff_terms += f64::from(
                (lf.table()[usize::from(code_old)] - lf.table()[usize::from(code_new)]).abs(),
            );
            // The codes at points of the box ±bound around the f64 endpoint: its corners, edge
            // midpoints and centre, and for a box wider than 0.2 cells (a backend with coarse
            // trig) a 0.1-cell lattice, fine enough to land in every cell the box covers and in
            // every off-map code band (each is step/cell ≈ 0.16 cells wide here).
            let n = (2.0 * bound / bound.min(0.1)).ceil() as usize;
            let mut seen = Vec::new();
            for i in 0..=n {
                for j in 0..=n {
                    let dx = -bound + 2.0 * bound * i as f64 / n as f64;
                    let dy = -bound + 2.0 * bound * j as f64 / n as f64;
                    seen.push(code64(view, gx + dx, gy + dy));
                }
            }
            assert!(
                seen.contains(&code_old) && seen.contains(&code_new),
                "beam {k} at ({gx}, {gy}): codes {code_old} vs {code_new}, not within {bound} cells of a boundary ({seen:?})"
            );
        }
    }
    // The prepared score is the in-order f32 sum of the terms it reports.
    assert_eq!(b.log_likelihood.to_bits(), sum.to_bits());
    if diff_terms == 0.0 {
        assert_eq!(a.log_likelihood.to_bits(), b.log_likelihood.to_bits());
        t.equal_scores += 1;
    } else {
        // Past the first differing beam the partial sums round differently: at most one
        // rounding of the running sum per beam.
        let slack = old.len() as f64 * f64::from(a.log_likelihood.abs().max(1.0)) * 2f64.powi(-23);
        let gap = f64::from(a.log_likelihood - b.log_likelihood).abs();
        assert!(gap <= diff_terms + slack, "{gap} > {diff_terms} + {slack}");
    }
    t.poses += 1;
}

/// Real Intel scans (with their max-range readings) at random poses on the TurtleBot3 and
/// Willow maps, with a mounting offset: many endpoints on and off each map.
#[test]
fn prepared_matches_score_on_real_maps_and_scans() {
    let log = intel();
    let z_max = log.max_range.value_m().unwrap();
    let mount = SensorMount {
        x_m: 0.12,
        y_m: -0.04,
        yaw_rad: 0.03,
    };
    let layout: BeamLayout<N> = log.layout_with_mount(mount).unwrap();
    let mut rng = Rng::new(0x05EE_D0FF_1E1D);
    for (name, rel, half_span) in [
        ("turtlebot3", "map_turtlebot3_world/map.yaml", 3.0),
        ("willow", "map_willow_garage/willow-full-0.05.yaml", 30.0),
    ] {
        let blob = blob_of(rel);
        let view = FieldView::parse(&blob).unwrap();
        let (cx, cy) = (
            view.header().origin_x_m + view.width() as f32 * view.cell_size_m() / 2.0,
            view.header().origin_y_m + view.height() as f32 * view.cell_size_m() / 2.0,
        );
        let lf = LikelihoodField::new(
            view,
            LikelihoodParams::new(0.95, 0.05, 0.05, z_max).unwrap(),
        );
        let mut t = Tally::default();
        for scan_i in (0..log.scans.len()).step_by(log.scans.len() / 40) {
            let scan = log.scans[scan_i].to_scan::<N>().unwrap();
            let prep = lf.prepare(&layout, &scan);
            assert_eq!(prep.frac_bits(), 16, "{name}");
            for _ in 0..50 {
                let pose = Pose::new(
                    cx + ((rng.uniform() * 2.0 - 1.0) * half_span) as f32,
                    cy + ((rng.uniform() * 2.0 - 1.0) * half_span) as f32,
                    ((rng.uniform() - 0.5) * std::f64::consts::TAU) as f32,
                );
                compare(&lf, &prep, &layout, &scan, &pose, Stride::ONE, &mut t);
            }
        }
        eprintln!(
            "{name}: {} poses, {} beams; {} beams read a different code ({:.2e} of beams; derived bound on the expected count {:.1}); {} poses with bit-equal scores",
            t.poses,
            t.beams,
            t.differing,
            t.differing as f64 / t.beams as f64,
            t.bound,
            t.equal_scores
        );
        assert!(t.beams > 100_000, "{name}: only {} beams", t.beams);
        assert!(
            (t.differing as f64) <= t.bound,
            "{name}: {} differing beams, more than the derived {:.1}",
            t.differing,
            t.bound
        );
    }
}

/// Poses the fixed-point path cannot take (far off the map) go through the f32 path and still
/// agree with `score`; NaN and infinite poses score NaN on both; a stride keeps the same beams and counts as `score_strided`.
#[test]
fn fallback_poses_and_stride() {
    let log = intel();
    let z_max = log.max_range.value_m().unwrap();
    let layout: BeamLayout<N> = log.layout().unwrap();
    let blob = blob_of("map_turtlebot3_world/map.yaml");
    let lf = amcl_field(&blob, z_max);
    let scan = log.scans[300].to_scan::<N>().unwrap();
    let prep = lf.prepare(&layout, &scan);
    let mut t = Tally::default();
    for pose in [
        Pose::new(5.0e3, 0.0, 0.3),
        Pose::new(0.0, -3.0e4, 2.0),
        Pose::new(-1.0e6, 1.0e6, -1.0),
    ] {
        compare(&lf, &prep, &layout, &scan, &pose, Stride::ONE, &mut t);
    }
    assert_eq!(t.fallback_poses, 3);
    // NaN or infinite: no place on the map, NaN on both paths (it used to be the finite sum of
    // code 255 on every beam), with the same counts; no beam is passed to `each`.
    for nowhere in [
        Pose::new(f32::NAN, 0.0, 0.0),
        Pose::new(0.0, f32::INFINITY, 0.0),
        Pose::new(0.0, 0.0, f32::NAN),
    ] {
        let (a, b) = (lf.score(&layout, &scan, &nowhere), prep.score(&nowhere));
        assert!(
            a.log_likelihood.is_nan() && b.log_likelihood.is_nan(),
            "{nowhere:?}"
        );
        assert_eq!(
            (a.scored, a.max_range, a.invalid),
            (b.scored, b.max_range, b.invalid)
        );
    }
    let mut codes = 0;
    prep.score_with(&Pose::new(f32::NAN, 0.0, 0.0), |_, _| codes += 1);
    assert_eq!(codes, 0);
    for s in [2, 3, 7] {
        let stride = Stride::new(s).unwrap();
        let ps = lf.prepare_strided(&layout, &scan, stride);
        for pose in [Pose::new(0.3, -0.2, 1.0), Pose::new(-1.1, 0.7, -2.5)] {
            compare(&lf, &ps, &layout, &scan, &pose, stride, &mut t);
        }
        let a = lf.score_strided_with(&layout, &scan, &Pose::default(), stride, |_, _| {});
        assert_eq!(ps.len(), usize::from(a.scored));
        assert!(a.scored > 0 && usize::from(a.scored) <= N.div_ceil(s));
    }
}

/// A map wider than 2^14 cells: the prepared path uses fewer fractional bits (F < 16) and
/// still agrees with `score`.
#[test]
fn wide_map_uses_fewer_fraction_bits() {
    use beamfield::field::{emit_blob, FieldHeader};
    let (w, h) = (20_000u32, 3u32);
    let header = FieldHeader::new(w, h, 0.05, -500.0, -0.075);
    let codes: Vec<u8> = (0..w * h).map(|i| ((i * 37) % 251) as u8).collect();
    let mut blob = vec![0u8; header.required_len().unwrap()];
    emit_blob(&header, &codes, &mut blob).unwrap();
    let lf = amcl_field(&blob, 10.0);
    let layout =
        BeamLayout::<N>::uniform(-1.5, 3.0 / N as f32, N, 10.0, SensorMount::CENTERED).unwrap();
    let mut rng = Rng::new(77);
    let ranges: Vec<f32> = (0..N).map(|_| (rng.uniform() * 9.0) as f32).collect();
    let scan = Scan::<N>::from_ranges(&ranges).unwrap();
    let prep = lf.prepare(&layout, &scan);
    assert_eq!(prep.frac_bits(), 15);
    let mut t = Tally::default();
    for _ in 0..400 {
        let pose = Pose::new(
            ((rng.uniform() * 2.0 - 1.0) * 520.0) as f32,
            ((rng.uniform() * 2.0 - 1.0) * 0.3) as f32,
            ((rng.uniform() - 0.5) * std::f64::consts::TAU) as f32,
        );
        compare(&lf, &prep, &layout, &scan, &pose, Stride::ONE, &mut t);
    }
    assert!((t.differing as f64) <= t.bound);
    assert_eq!(t.fallback_poses, 0);
}

/// The robot x (or y, `along_y`) in metres, on the side `sign`, up to which the fixed-point path
/// is taken: bisected on `uses_fixed_point` to 1 mm.
fn fixed_point_edge(prep: &PreparedScan<'_, N>, along_y: bool, sign: f64) -> f64 {
    let at = |d: f64| {
        let v = (sign * d) as f32;
        let pose = if along_y {
            Pose::new(0.0, v, 0.0)
        } else {
            Pose::new(v, 0.0, 0.0)
        };
        prep.uses_fixed_point(&pose)
    };
    let (mut lo, mut hi) = (0.0f64, 1.0e7f64);
    assert!(at(lo) && !at(hi));
    while hi - lo > 1e-3 {
        let mid = 0.5 * (lo + hi);
        if at(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    sign * lo
}

/// Right at the edge of the fixed-point region (the integer overflow bound, or the bound under
/// which the u32 cell index cannot wrap back onto the map), at every heading, the prepared
/// score still agrees with `score`: the bounds computed at preparation are on the safe side.
/// And at the places just outside it where integer arithmetic would alias back onto the map
/// (a grid coordinate 2^(32−F) cells away, where the fixed-point sum wraps; a row whose u32
/// index wraps to the map's first row) the two scores agree too, which they would not if the
/// fixed-point path were taken there.
/// Three maps: TurtleBot3 (F = 16), a 20,000-cell-wide strip (F = 15) and a 140,000-cell-wide
/// strip, where `2^32 / width` rows is below the overflow bound, so the wrap bound decides in y.
#[test]
fn poses_at_the_edge_of_the_fixed_point_region_agree_with_score() {
    use beamfield::field::{emit_blob, FieldHeader};
    let log = intel();
    let z_max = log.max_range.value_m().unwrap();
    let layout: BeamLayout<N> = log.layout().unwrap();
    let scan = log.scans[300].to_scan::<N>().unwrap();
    let strip = |w: u32| {
        let header = FieldHeader::new(w, 2, 0.05, -10.0, -0.05);
        let codes: Vec<u8> = (0..w * 2).map(|i| ((i * 37) % 251) as u8).collect();
        let mut blob = vec![0u8; header.required_len().unwrap()];
        emit_blob(&header, &codes, &mut blob).unwrap();
        blob
    };
    let blobs = [
        (blob_of("map_turtlebot3_world/map.yaml"), 16),
        (strip(20_000), 15),
        (strip(140_000), 12),
    ];
    for (blob, want_f) in &blobs {
        let lf = amcl_field(blob, z_max);
        let prep = lf.prepare(&layout, &scan);
        assert_eq!(prep.frac_bits(), *want_f);
        let mut t = Tally::default();
        for (along_y, sign) in [(false, 1.0), (false, -1.0), (true, 1.0), (true, -1.0)] {
            let edge = fixed_point_edge(&prep, along_y, sign);
            for k in 0..16 {
                let theta = (f64::from(k) / 16.0 * std::f64::consts::TAU - 3.0) as f32;
                let (x, y) = if along_y { (0.0, edge) } else { (edge, 0.0) };
                let pose = Pose::new(x as f32, y as f32, theta);
                assert!(prep.uses_fixed_point(&pose));
                compare(&lf, &prep, &layout, &scan, &pose, Stride::ONE, &mut t);
            }
        }
        assert_eq!(t.fallback_poses, 0);
        assert!((t.differing as f64) <= t.bound);

        // Where wrapping integers would read the map again.
        let view = lf.view();
        let (w, h) = (u64::from(view.width()), u64::from(view.height()));
        let cell = f64::from(view.cell_size_m());
        let hd = view.header();
        let at_cell = |cx: f64, cy: f64| {
            (
                (f64::from(hd.origin_x_m) + (cx + 0.5) * cell) as f32,
                (f64::from(hd.origin_y_m) + (cy + 0.5) * cell) as f32,
            )
        };
        let period = f64::from(1u32 << (32 - prep.frac_bits()));
        // The first row above the map whose u32 index wraps into the map's first row.
        let wrap_row = (1..=u64::from(u32::MAX))
            .find(|&r| (r * w) % (1 << 32) < w / 2)
            .unwrap();
        let places = [
            at_cell(period + (w / 2) as f64, (h / 2) as f64),
            at_cell((w / 2) as f64 - period, (h / 2) as f64),
            at_cell((w / 2) as f64, period + (h / 2) as f64),
            at_cell(10.0, wrap_row as f64),
        ];
        let before = t.fallback_poses;
        for (x, y) in places {
            for theta in [0.0f32, 0.4, 1.6, 3.1, -1.6] {
                compare(
                    &lf,
                    &prep,
                    &layout,
                    &scan,
                    &Pose::new(x, y, theta),
                    Stride::ONE,
                    &mut t,
                );
            }
        }
        assert_eq!(t.fallback_poses - before, places.len() * 5);
    }
}

/// `Tempered::prepare`: the wrapper's stride is applied at preparation and 1/κ at every score,
/// so a `TemperedScan` scores exactly `PreparedScan::score` over the stride times `1/κ`, and
/// equals the wrapper's own `SensorModel::score` wherever the untempered paths agree bit for
/// bit (no beam in a neighbouring cell).
#[test]
fn tempered_prepare_matches_the_tempered_model() {
    use beamfield::{SensorModel, Tempered};
    let log = intel();
    let z_max = log.max_range.value_m().unwrap();
    let layout: BeamLayout<N> = log.layout().unwrap();
    let blob = blob_of("map_turtlebot3_world/map.yaml");
    let lf = amcl_field(&blob, z_max);
    let mut rng = Rng::new(5);
    let (mut equal, mut poses) = (0usize, 0usize);
    for (kappa, stride) in [(1.0f32, 1usize), (8.25, 1), (4.0, 3)] {
        let tempered = Tempered::new(lf.clone(), kappa, stride).unwrap();
        for i in [40usize, 300, 610] {
            let scan = log.scans[i].to_scan::<N>().unwrap();
            let ts = tempered.prepare(&layout, &scan);
            let plain = lf.prepare_strided(&layout, &scan, Stride::new(stride).unwrap());
            assert_eq!(ts.prepared().len(), plain.len());
            for _ in 0..30 {
                let pose = Pose::new(
                    ((rng.uniform() * 2.0 - 1.0) * 1.5) as f32,
                    ((rng.uniform() * 2.0 - 1.0) * 1.5) as f32,
                    ((rng.uniform() - 0.5) * std::f64::consts::TAU) as f32,
                );
                let t = ts.score(&pose);
                let p = plain.score(&pose);
                // `Tempered` multiplies by its stored `1/κ` (not a division by κ).
                assert_eq!(
                    t.log_likelihood.to_bits(),
                    (p.log_likelihood * (1.0 / kappa)).to_bits()
                );
                assert_eq!(
                    (t.scored, t.max_range, t.invalid),
                    (p.scored, p.max_range, p.invalid)
                );
                let m = tempered.score(&layout, &scan, &pose);
                assert_eq!(
                    (m.scored, m.max_range, m.invalid),
                    (t.scored, t.max_range, t.invalid)
                );
                let untempered = lf.score_strided_with(
                    &layout,
                    &scan,
                    &pose,
                    Stride::new(stride).unwrap(),
                    |_, _| {},
                );
                if untempered.log_likelihood.to_bits() == p.log_likelihood.to_bits() {
                    assert_eq!(m.log_likelihood.to_bits(), t.log_likelihood.to_bits());
                    equal += 1;
                }
                poses += 1;
            }
        }
    }
    // Most poses have no beam in a neighbouring cell.
    assert!(equal * 10 >= poses * 9, "{equal} of {poses}");
}
