//! The likelihood field (Table 6.3), per pose and prepared ([`beamfield::PreparedScan`]),
//! against an independent f64 computation, and the best pose
//! of a small grid on a synthetic scan ray-cast in the TurtleBot3 map.

use beamfield::field::{FieldView, LikelihoodField, LikelihoodParams};
use beamfield::{BeamLayout, Pose, Scan, SensorMount};
use beamfield_tools::blob::build_blob;
use beamfield_tools::input::map::{load_map, Occupancy};
use host_tests::field_reference::{expected_distance, lf_term, ray_cast, Grid};

const N: usize = 360;

fn turtlebot3() -> (Vec<u8>, Grid) {
    let m = load_map(&host_tests::data_dir().join("map_turtlebot3_world/map.yaml")).unwrap();
    let blob = build_blob(&m, 2.0).unwrap();
    let g = Grid {
        width: m.width as usize,
        height: m.height as usize,
        res: m.resolution_m,
        origin: (m.origin_x_m, m.origin_y_m),
        occupied: m.cells.iter().map(|c| *c == Occupancy::Occupied).collect(),
    };
    (blob, g)
}

use beamfield::mcl::XorShift64 as Rng;

/// f64 endpoint of beam k (grid units), as docs/models.md#field writes it.
fn endpoint(
    grid: &Grid,
    pose: (f64, f64, f64),
    mount: (f64, f64, f64),
    bearing: f64,
    r: f64,
) -> (f64, f64) {
    let (x, y, t) = pose;
    let (xs, ys, ts) = mount;
    let xz = x + xs * t.cos() - ys * t.sin() + r * (t + ts + bearing).cos();
    let yz = y + ys * t.cos() + xs * t.sin() + r * (t + ts + bearing).sin();
    (xz, yz).into_grid(grid)
}

trait IntoGrid {
    fn into_grid(self, g: &Grid) -> (f64, f64);
}
impl IntoGrid for (f64, f64) {
    fn into_grid(self, g: &Grid) -> (f64, f64) {
        ((self.0 - g.origin.0) / g.res, (self.1 - g.origin.1) / g.res)
    }
}

/// Within this many cells of a cell edge, the f32 rounding of the projection may pick a
/// different cell than the f64 one.
const EDGE_CELLS: f64 = 2e-3;

/// How far, per axis and in metres, the crate's endpoint can be from the exact one because of
/// the math backend's `sin_cos` error `ε` (`host_tests::reference_backend`): the mount offset
/// is rotated by the heading's (cos, sin) (error ≤ `ε·(|x_s| + |y_s|)`), and the beam's unit
/// vector is the product of the sensor heading's and the bearing's (cos, sin), each component
/// off by ≤ `ε`, so `c·cos β − s·sin β` is off by ≤ `ε(|cos β| + |sin β|) + ε(|c| + |s|) + 2ε²
/// ≤ 2√2·ε + 2ε²`, times the range. With libm's 6.4e-8 this is ~1e-5 cells here, far inside
/// [`EDGE_CELLS`]; micromath's 1.1e-3 makes it up to ~0.2 cells at 3.5 m on 5 cm cells, which
/// is why beams 2e-3 cells from an edge could land in the next cell under that backend.
fn trig_error_m(mount: (f64, f64, f64), r: f64) -> f64 {
    let e = host_tests::reference_backend::SIN_COS_ABS_ERROR;
    e * (mount.0.abs() + mount.1.abs()) + r * (2.0 * std::f64::consts::SQRT_2 * e + 2.0 * e * e)
}

/// Whether the exact endpoint is within `EDGE_CELLS + trig` cells of a cell edge.
fn near_edge(g: (f64, f64), trig_cells: f64) -> bool {
    let f = |v: f64| {
        let d = v - v.round();
        d.abs() < EDGE_CELLS + trig_cells
    };
    f(g.0) || f(g.1)
}

/// Random scans at random poses, with a mounting offset, max-range and invalid readings mixed
/// in. Per beam, the scored distance must equal the reference's quantized distance; the scan
/// log-likelihood must match the f64 sum within 2e-6 relative + 1e-4 nats (f32 table entries
/// are within 1 ulp-ish of f64, and the f32 sum of 360 terms of magnitude ≤ 10 accumulates at
/// most ~360·10·6e-8 ≈ 2e-4 in the worst case, ~1e-5 typically).
#[test]
fn score_matches_f64_reference() {
    let (blob, grid) = turtlebot3();
    let view = FieldView::parse(&blob).unwrap();
    let seeds = grid.seeds();
    let (z_hit, z_rand, sigma, z_max) = (0.9f32, 0.1f32, 0.15f32, 3.5f32);
    let lf = LikelihoodField::new(
        view,
        LikelihoodParams::new(z_hit, z_rand, sigma, z_max).unwrap(),
    );
    let mount = SensorMount {
        x_m: 0.1,
        y_m: -0.03,
        yaw_rad: 0.05,
    };
    let layout = BeamLayout::<N>::uniform(
        -std::f32::consts::PI,
        std::f32::consts::TAU / N as f32,
        N,
        z_max,
        mount,
    )
    .unwrap();
    let mut rng = Rng::new(0x1234_5678_9ABC_DEF1);
    let mut worst_rel = 0.0f64;
    let mut off_map = 0usize;
    for trial in 0..40 {
        // Half the poses in the arena, half anywhere on (or just off) the 19.2 m map, so that
        // endpoints off the map are exercised too.
        let span = if trial % 2 == 0 { 5.0 } else { 22.0 };
        let pose = Pose::new(
            (rng.uniform() * span - span / 2.0) as f32,
            (rng.uniform() * span - span / 2.0) as f32,
            (rng.uniform() * 7.0 - 3.5) as f32,
        );
        let pose64 = (
            f64::from(pose.x_m),
            f64::from(pose.y_m),
            f64::from(pose.theta_rad),
        );
        let mount64 = (
            f64::from(mount.x_m),
            f64::from(mount.y_m),
            f64::from(mount.yaw_rad),
        );
        let mut ranges = Vec::with_capacity(N);
        for k in 0..N {
            let u = rng.uniform();
            let r = if u < 0.03 {
                f32::NAN
            } else if u < 0.05 {
                -0.5
            } else if u < 0.10 {
                z_max + 1.0
            } else if u < 0.12 {
                f32::INFINITY
            } else {
                loop {
                    let r = (rng.uniform() * f64::from(z_max)) as f32;
                    let b = f64::from(layout.beams()[k].bearing_rad);
                    let trig_cells = trig_error_m(mount64, f64::from(r)) / grid.res;
                    if !near_edge(
                        endpoint(&grid, pose64, mount64, b, f64::from(r)),
                        trig_cells,
                    ) {
                        break r;
                    }
                }
            };
            ranges.push(r);
        }
        let scan = Scan::<N>::from_ranges(&ranges).unwrap();
        let mut dist = vec![0.0f32; N];
        let got = lf.score_into(&layout, &scan, &pose, &mut dist);
        // The prepared path (fixed point) on the same scan: the kept beams' distances in order.
        let prep = lf.prepare(&layout, &scan);
        let mut prep_dist = Vec::new();
        let prep_got = prep.score_with(&pose, |_, d| prep_dist.push(d));
        let mut prep_dist = prep_dist.into_iter();

        let mut want = 0.0f64;
        let (mut scored, mut maxr, mut invalid) = (0, 0, 0);
        for k in 0..N {
            let r = ranges[k];
            if r.is_nan() || r < 0.0 {
                invalid += 1;
                assert!(dist[k].is_nan());
                continue;
            }
            if r >= z_max {
                maxr += 1;
                assert!(dist[k].is_nan());
                continue;
            }
            scored += 1;
            let b = f64::from(layout.beams()[k].bearing_rad);
            let (gx, gy) = endpoint(&grid, pose64, mount64, b, f64::from(r));
            let (x, y) = (grid.origin.0 + gx * grid.res, grid.origin.1 + gy * grid.res);
            let (d_ref, _) = expected_distance(&grid, &seeds, x, y, 2.0);
            let on_map =
                (0.0..grid.width as f64).contains(&gx) && (0.0..grid.height as f64).contains(&gy);
            off_map += usize::from(!on_map);
            // Off the map the reference adds the exact distance; the scorer adds it in
            // rounded steps and clamps at d_max.
            let step = 2.0 / 255.0;
            let d_ref = ((d_ref / step).round() * step).min(2.0);
            assert!(
                (f64::from(dist[k]) - d_ref).abs() < 1e-6,
                "trial {trial} beam {k}: scored d {} vs reference {d_ref}",
                dist[k]
            );
            let d_prep = prep_dist.next().unwrap();
            assert!(
                (f64::from(d_prep) - d_ref).abs() < 1e-6,
                "trial {trial} beam {k}: prepared d {d_prep} vs reference {d_ref}"
            );
            want += lf_term(
                d_ref,
                f64::from(z_hit),
                f64::from(z_rand),
                f64::from(sigma),
                f64::from(z_max),
            );
        }
        assert_eq!(
            (got.scored, got.max_range, got.invalid, got.unpaired),
            (scored, maxr, invalid, 0)
        );
        assert_eq!(prep_dist.next(), None);
        assert_eq!(
            (
                prep_got.scored,
                prep_got.max_range,
                prep_got.invalid,
                prep_got.unpaired
            ),
            (scored, maxr, invalid, 0)
        );
        let prep_diff = (f64::from(prep_got.log_likelihood) - want).abs();
        assert!(
            prep_diff <= 2e-6 * want.abs() + 1e-4,
            "trial {trial}: prepared {} vs {want}",
            prep_got.log_likelihood
        );
        let diff = (f64::from(got.log_likelihood) - want).abs();
        assert!(
            diff <= 2e-6 * want.abs() + 1e-4,
            "trial {trial}: {} vs {want}",
            got.log_likelihood
        );
        worst_rel = worst_rel.max(diff / want.abs());
    }
    eprintln!("worst relative difference of the scan log-likelihood: {worst_rel:.2e}; {off_map} endpoints off the map");
    assert!(
        off_map > 100,
        "the off-map path was not exercised ({off_map})"
    );
}

/// A 360-beam scan ray-cast in the TurtleBot3 map at a known pose: the best pose of a
/// 5 × 5 × 5 grid (±10 cm in 5 cm steps, ±4° in 2° steps) around it is the true one.
#[test]
fn best_grid_pose_is_the_true_pose() {
    let (blob, grid) = turtlebot3();
    let view = FieldView::parse(&blob).unwrap();
    let z_max = 3.5f32;
    let lf = LikelihoodField::new(view, LikelihoodParams::amcl_defaults(z_max).unwrap());
    let mount = SensorMount {
        x_m: -0.032,
        y_m: 0.0,
        yaw_rad: 0.0,
    };
    let layout =
        BeamLayout::<N>::uniform(0.0, std::f32::consts::TAU / N as f32, N, z_max, mount).unwrap();
    for (px, py, pt) in [
        (-1.6f32, -0.45f32, 0.7f32),
        (0.55, 0.6, -2.0),
        (1.7, -0.1, 3.0),
    ] {
        let (gx, gy) = ((f64::from(px) + 10.0) / 0.05, (f64::from(py) + 10.0) / 0.05);
        assert!(
            !grid.is_occupied(gx as i64, gy as i64),
            "pose inside a wall"
        );
        let (s, c) = f64::from(pt).sin_cos();
        let sx = f64::from(px) + f64::from(mount.x_m) * c;
        let sy = f64::from(py) + f64::from(mount.x_m) * s;
        let ranges: Vec<f32> = layout
            .beams()
            .iter()
            .map(|b| {
                ray_cast(
                    &grid,
                    sx,
                    sy,
                    f64::from(pt) + f64::from(b.bearing_rad),
                    f64::from(z_max),
                )
                .map_or(f32::INFINITY, |r| r as f32)
            })
            .collect();
        let hits = ranges.iter().filter(|r| r.is_finite()).count();
        assert!(hits > 300, "only {hits} hits");
        let scan = Scan::<N>::from_ranges(&ranges).unwrap();
        let mut best = (f32::NEG_INFINITY, (9, 9, 9));
        for i in -2i32..=2 {
            for j in -2i32..=2 {
                for k in -2i32..=2 {
                    let p = Pose::new(
                        px + 0.05 * i as f32,
                        py + 0.05 * j as f32,
                        pt + (2.0 * k as f32).to_radians(),
                    );
                    let l = lf.score(&layout, &scan, &p).log_likelihood;
                    if l > best.0 {
                        best = (l, (i, j, k));
                    }
                }
            }
        }
        assert_eq!(
            best.1,
            (0, 0, 0),
            "pose ({px}, {py}, {pt}): best offset {:?}",
            best.1
        );
    }
}
