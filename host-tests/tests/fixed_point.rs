//! The fixed-point likelihood field against the f32 path on the TurtleBot3 map with ray-cast
//! scans: per-beam table index, scan log-likelihood difference within the bound derived from
//! the Q formats, same best pose of a grid; and the overflow bound of the sum.

use beamfield::field::{FieldView, LikelihoodField, LikelihoodParams};
use beamfield::fixed_point::{
    FixedField, FixedLayout, FixedPose, FixedScan, I16F16, MAX_FIXED_BEAMS,
};
use beamfield::{BeamLayout, Pose, Scan, SensorMount};
use beamfield_tools::blob::build_blob;
use beamfield_tools::input::map::{load_map, Occupancy};
use host_tests::field_reference::{ray_cast, Grid};

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

fn scan_at(grid: &Grid, layout: &BeamLayout<N>, p: (f32, f32, f32), z_max: f32) -> Scan<N> {
    let (px, py, pt) = p;
    let m = layout.mount();
    let (s, c) = f64::from(pt).sin_cos();
    let sx = f64::from(px) + f64::from(m.x_m) * c;
    let sy = f64::from(py) + f64::from(m.x_m) * s;
    let ranges: Vec<f32> = layout
        .beams()
        .iter()
        .map(|b| {
            ray_cast(
                grid,
                sx,
                sy,
                f64::from(pt) + f64::from(b.bearing_rad),
                f64::from(z_max),
            )
            .map_or(f32::INFINITY, |r| r as f32)
        })
        .collect();
    Scan::from_ranges(&ranges).unwrap()
}

/// Per pose and scan: beams whose table index agrees contribute at most the table rounding
/// (2⁻¹⁷ nats) each; beams whose endpoint falls in another cell (the endpoint differs by at
/// most ~1/256 cell of range rounding plus ~1.5·2⁻¹⁵·r of direction) contribute their exact term
/// difference. The f32 sum itself rounds by at most n·ε·Σ|term|. The test checks
/// |LL_fixed − LL_f32| against that bound, and that index flips are rare.
#[test]
fn matches_f32_path_on_turtlebot3_and_same_best_pose() {
    let (blob, grid) = turtlebot3();
    let view = FieldView::parse(&blob).unwrap();
    let z_max = 3.5f32;
    let lf = LikelihoodField::new(view, LikelihoodParams::amcl_defaults(z_max).unwrap());
    let ff = FixedField::new(&lf).unwrap();
    let mount = SensorMount {
        x_m: -0.032,
        y_m: 0.0,
        yaw_rad: 0.0,
    };
    let layout =
        BeamLayout::<N>::uniform(0.0, std::f32::consts::TAU / N as f32, N, z_max, mount).unwrap();
    let fl = FixedLayout::new(&layout).unwrap();
    let table = lf.table();
    let tbits = ff.table_bits();
    // Table rounding: each term within half an ulp of I16F16.
    for (t, q) in table.iter().zip(tbits) {
        assert!((f64::from(*t) - f64::from(*q) / 65_536.0).abs() <= 0.5 / 65_536.0 + 1e-9);
    }
    let (mut beams, mut flips, mut worst_diff) = (0usize, 0usize, 0.0f64);
    for truth in [
        (-1.6f32, -0.45f32, 0.7f32),
        (0.55, 0.6, -2.0),
        (1.7, -0.1, 3.0),
    ] {
        let scan = scan_at(&grid, &layout, truth, z_max);
        let fscan = FixedScan::from_scan(&scan, &ff);
        let mut best_f = (f32::NEG_INFINITY, (9, 9, 9));
        let mut best_x = (i64::MIN, (9, 9, 9));
        for i in -2i32..=2 {
            for j in -2i32..=2 {
                for k in -2i32..=2 {
                    let p = Pose::new(
                        truth.0 + 0.05 * i as f32,
                        truth.1 + 0.05 * j as f32,
                        truth.2 + (2.0 * k as f32).to_radians(),
                    );
                    let mut idx_f = vec![usize::MAX; N];
                    let sf = lf.score_with(&layout, &scan, &p, |b, d| {
                        idx_f[b] = (d / view.step_m()).round() as usize;
                    });
                    let mut idx_x = vec![usize::MAX; N];
                    let fp = FixedPose::from_pose(&p).unwrap();
                    let sx = ff.score_with(&fl, &fscan, &fp, |b, ix| idx_x[b] = ix);
                    assert_eq!(ff.score_sum(&fl, &fscan, &fp), sx.log_likelihood);
                    assert_eq!(
                        (sf.scored, sf.max_range, sf.invalid),
                        (sx.scored, sx.max_range, sx.invalid)
                    );
                    let mut bound = 0.0f64;
                    let mut abs_sum = 0.0f64;
                    for (a, b) in idx_f.iter().zip(&idx_x) {
                        assert_eq!(*a == usize::MAX, *b == usize::MAX);
                        if *a == usize::MAX {
                            continue;
                        }
                        beams += 1;
                        abs_sum += f64::from(table[*a]).abs();
                        if a == b {
                            bound += 0.5 / 65_536.0;
                        } else {
                            flips += 1;
                            // A neighbouring cell: distances differ by at most a cell diagonal
                            // (√2 · 6.375 code steps) plus one step of quantization each.
                            assert!(a.abs_diff(*b) <= 11, "codes {a} vs {b}");
                            // Off by one cell at most: codes of neighbours.
                            bound += (f64::from(table[*a]) - f64::from(tbits[*b]) / 65_536.0).abs()
                                + 0.5 / 65_536.0;
                        }
                    }
                    bound += N as f64 * f64::from(f32::EPSILON) * abs_sum;
                    let diff =
                        (f64::from(sf.log_likelihood) - sx.log_likelihood.to_num::<f64>()).abs();
                    assert!(diff <= bound, "pose {p:?}: diff {diff} > bound {bound}");
                    worst_diff = worst_diff.max(diff);
                    if sf.log_likelihood > best_f.0 {
                        best_f = (sf.log_likelihood, (i, j, k));
                    }
                    let lx = sx.log_likelihood.to_bits();
                    if lx > best_x.0 {
                        best_x = (lx, (i, j, k));
                    }
                }
            }
        }
        assert_eq!(best_f.1, best_x.1, "best pose differs at {truth:?}");
        assert_eq!(best_x.1, (0, 0, 0));
    }
    // Ray-cast endpoints lie exactly on cell boundaries, so flips are common here (~8%); each
    // one is checked above to stay within the derived bound, and is a move to a neighbouring
    // cell (checked in the loop).
    assert!(flips < beams);
    eprintln!("turtlebot3: {beams} beams, {flips} index flips, max |ΔLL| = {worst_diff:.6} nats");
}

/// The overflow bound of `MAX_FIXED_BEAMS`: the largest scan with every term at the most
/// negative `I16F16` sums exactly, in the fixed path and tempered.
#[test]
fn largest_scan_with_extreme_terms_does_not_overflow() {
    // The 65 535-beam layouts and scans live on the stack: give the thread room.
    std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(largest_scan_body)
        .unwrap()
        .join()
        .unwrap();
}

fn largest_scan_body() {
    // A 1-cell map whose only code's term is pushed to the I16F16 limit: z_hit = 1, z_rand
    // = 0 and a tiny σ make every term about −32 767 nats.
    let h = beamfield::field::FieldHeader::new(1, 1, 1.0, 0.0, 0.0);
    let mut b = vec![0u8; h.required_len().unwrap()];
    beamfield::field::emit_blob(&h, &[255], &mut b).unwrap();
    let view = FieldView::parse(&b).unwrap();
    // term(d = 2 m) = ln(1/(σ√2π)) − ½(2/σ)² ≈ −32 767 for σ ≈ 0.011 05.
    let sigma = 2.0 / (2.0f32 * 32_760.0).sqrt();
    let lf = LikelihoodField::new(view, LikelihoodParams::new(1.0, 0.0, sigma, 3.0).unwrap());
    let ff = FixedField::new(&lf).unwrap();
    let t = ff.table_bits()[255];
    assert!(t < -(32_000 << 16), "term {t}");
    let layout = BeamLayout::<MAX_FIXED_BEAMS>::uniform(
        0.0,
        1e-4,
        MAX_FIXED_BEAMS,
        3.0,
        SensorMount::CENTERED,
    )
    .unwrap();
    let fl = FixedLayout::new(&layout).unwrap();
    let ranges = vec![1.0f32; MAX_FIXED_BEAMS];
    let scan = Scan::<MAX_FIXED_BEAMS>::from_ranges(&ranges).unwrap();
    let fs = FixedScan::from_scan(&scan, &ff);
    let p = FixedPose::from_pose(&Pose::new(0.5, 0.5, 0.0)).unwrap();
    let s = ff.score(&fl, &fs, &p);
    let want = i128::from(t) * MAX_FIXED_BEAMS as i128;
    assert_eq!(i128::from(s.log_likelihood.to_bits()), want);
    assert_eq!(usize::from(s.scored), MAX_FIXED_BEAMS);
    // κ = 1 keeps it; κ = 1/2 halves it exactly (the sum is even).
    assert_eq!(s.tempered(I16F16::ONE), s.log_likelihood);
    assert_eq!(
        i128::from(s.tempered(I16F16::from_num(0.5)).to_bits()),
        want / 2
    );
    // The worst case of the bound itself: 65 535 terms of −2³¹ raw.
    let worst = -(1i128 << 31) * MAX_FIXED_BEAMS as i128;
    assert!(worst > i128::from(i64::MIN) >> 16);
}

/// Integer millimetre ranges give the same score as the f32 ranges they round from.
#[test]
fn millimetre_ranges_match_metre_ranges() {
    let (blob, grid) = turtlebot3();
    let view = FieldView::parse(&blob).unwrap();
    let lf = LikelihoodField::new(view, LikelihoodParams::amcl_defaults(3.5).unwrap());
    let ff = FixedField::new(&lf).unwrap();
    let layout = BeamLayout::<N>::uniform(
        0.0,
        std::f32::consts::TAU / N as f32,
        N,
        3.5,
        SensorMount::CENTERED,
    )
    .unwrap();
    let fl = FixedLayout::new(&layout).unwrap();
    let scan = scan_at(&grid, &layout, (0.55, 0.6, -2.0), 3.5);
    let mm: Vec<u16> = scan
        .ranges_m()
        .iter()
        .map(|r| {
            if r.is_finite() {
                (r * 1000.0).round() as u16
            } else {
                3500
            }
        })
        .collect();
    let rounded: Vec<f32> = mm.iter().map(|&m| f32::from(m) / 1000.0).collect();
    let a = FixedScan::from_scan(&Scan::<N>::from_ranges(&rounded).unwrap(), &ff);
    let b = FixedScan::from_ranges_mm(&mm, &ff);
    let p = FixedPose::from_pose(&Pose::new(0.55, 0.6, -2.0)).unwrap();
    let (sa, sb) = (ff.score(&fl, &a, &p), ff.score(&fl, &b, &p));
    assert_eq!((sa.scored, sa.max_range), (sb.scored, sb.max_range));
    // Same Q11.8 ranges up to one rounding step.
    for (x, y) in a.ranges_q8().iter().zip(b.ranges_q8()) {
        assert!((x - y).abs() <= 1, "{x} vs {y}");
    }
    let finite = scan.ranges_m().iter().filter(|r| r.is_finite()).count();
    assert_eq!(usize::from(sb.scored), finite);
    assert_eq!(usize::from(sb.max_range), N - finite);
}
