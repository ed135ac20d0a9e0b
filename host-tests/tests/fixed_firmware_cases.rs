//! Generates (with `BEAMFIELD_WRITE_FIXED_CASES=1`) or checks the reference data of the
//! fixed-point firmware program `firmware/src/bin/fixed_m0.rs`: a 120 × 120-cell crop of the
//! TurtleBot3 map as a blob, a 180-beam ray-cast scan, a 3 × 3 × 3 pose grid, and for each
//! pose the bounds its two scores must lie in. Without the variable, the test fails when the
//! committed files are stale.
//!
//! # Expected values: an f64 reference with the formats' error bounds
//! The bounds come from the definitions, not from the crate: the distance of every cell by
//! brute force over the occupied cells (`host_tests::field_reference`), its code as the blob
//! stores it (clamped at d_max, rounded to d_max/255), the off-map charge (nearest cell's code
//! plus the distance to the map in code steps, rounded, at most 255: docs/blob-format.md), the
//! term `ln(z_hit·N(d; 0, σ²) + z_rand/z_max)` (Thrun Table 6.3) in f64, and the endpoint
//! `x + r·cos(θ + β)` in f64. Each path's endpoint is within `δ` cells of the exact one
//! (below), so each beam's term is bracketed by the smallest and largest f64 term over the box
//! `±δ` around the exact endpoint; the sums of those brackets, widened by each path's own
//! rounding (the fixed path's terms rounded to `I16F16`, ≤ 2⁻¹⁷ each, src/fixed_point; the f32
//! path's table entries and sum), are the bounds. Ray-cast endpoints sit on cell edges (the
//! scan ends just inside a wall), so near the true pose many beams are ambiguous and the
//! brackets are wide there: the bounds are what the formats guarantee, not a snapshot.
//!
//! `δ` for the fixed path, per axis, from the Q formats of src/fixed_point (module docs): the
//! sensor position and endpoint in Q.8 cells and the range in Q11.8 (half a 1/256 cell each),
//! the two partial products rounded to nearest (half a 1/256 cell each), the direction's error
//! (Q1.15 vectors and heading: under 2·2⁻¹⁵ rad, docs/fixed-point.md measures 1.5·2⁻¹⁵) times
//! the range, and the map origin's `I16F16` rounding (2⁻¹⁷ m) in cells. For the f32 path:
//! `2⁻²¹·(|ax| + |ay| + 4R + 4)` (host-tests/tests/field_prepared.rs), plus the bearing's
//! rounding and the sine/cosine error times the range.

use beamfield::field::{FieldView, LikelihoodField, LikelihoodParams};
use beamfield::fixed_point::{FixedField, FixedLayout, FixedPose, FixedScan, I16F16};
use beamfield::{BeamLayout, Pose, Scan, SensorMount};
use beamfield_tools::blob::build_blob;
use beamfield_tools::input::map::{load_map, Occupancy, OccupancyMap};
use host_tests::field_reference::{brute_squared, lf_term, ray_cast, Grid};
use std::fmt::Write;

const N: usize = 180;
const CROP: (u32, u32, u32) = (140, 140, 120);
const Z_MAX: f32 = 3.5;
const TRUTH: (f32, f32, f32) = (-1.6, -0.45, 0.7);

fn crop() -> OccupancyMap {
    let m = load_map(&host_tests::data_dir().join("map_turtlebot3_world/map.yaml")).unwrap();
    let (x0, y0, n) = CROP;
    let mut cells = Vec::new();
    for iy in y0..y0 + n {
        for ix in x0..x0 + n {
            cells.push(m.get(ix, iy).unwrap());
        }
    }
    OccupancyMap {
        width: n,
        height: n,
        resolution_m: m.resolution_m,
        origin_x_m: m.origin_x_m + f64::from(x0) * m.resolution_m,
        origin_y_m: m.origin_y_m + f64::from(y0) * m.resolution_m,
        cells,
    }
}

/// Which path's endpoint error to bracket.
#[derive(Clone, Copy, PartialEq)]
enum Path {
    Fixed,
    F32,
}

/// The f64 reference of the likelihood field on the crop (module docs).
struct Reference<'a> {
    grid: &'a Grid,
    /// Each cell's code by brute force: `round(min(d, d_max) / step)`.
    codes: Vec<u8>,
    step: f64,
    /// The 256 terms, f64, with the AMCL defaults (z_hit 0.95, z_rand 0.05, σ 0.2 m).
    terms: Vec<f64>,
}

impl<'a> Reference<'a> {
    fn new(grid: &'a Grid, d_max: f64) -> Self {
        let seeds = grid.seeds();
        let step = d_max / 255.0;
        let mut codes = Vec::with_capacity(grid.width * grid.height);
        for iy in 0..grid.height as i64 {
            for ix in 0..grid.width as i64 {
                let d = brute_squared(&seeds, ix, iy).map_or(f64::INFINITY, |s| (s as f64).sqrt());
                codes.push(((d * grid.res).min(d_max) / step).round().min(255.0) as u8);
            }
        }
        let terms = (0..256)
            .map(|c| lf_term(f64::from(c) * step, 0.95, 0.05, 0.2, f64::from(Z_MAX)))
            .collect();
        Reference {
            grid,
            codes,
            step,
            terms,
        }
    }

    /// The table index at grid point `(gx, gy)`, cells (docs/blob-format.md).
    fn code(&self, gx: f64, gy: f64) -> u8 {
        let (w, h) = (self.grid.width as f64, self.grid.height as f64);
        let cx = gx.clamp(0.0, w);
        let cy = gy.clamp(0.0, h);
        let ix = (cx.floor() as usize).min(self.grid.width - 1);
        let iy = (cy.floor() as usize).min(self.grid.height - 1);
        let c = f64::from(self.codes[iy * self.grid.width + ix]);
        let off = ((gx - cx).powi(2) + (gy - cy).powi(2)).sqrt();
        let extra = (off * self.grid.res / self.step + 0.5).floor();
        (c + extra).min(255.0) as u8
    }

    /// `(centre, half-width)` of the scan log-likelihood at `pose` (x m, y m, θ rad) for `path`.
    fn score(
        &self,
        layout: &BeamLayout<N>,
        ranges: &[f32],
        pose: (f64, f64, f64),
        path: Path,
    ) -> (f64, f64) {
        let res = self.grid.res;
        let ax = (pose.0 - self.grid.origin.0) / res;
        let ay = (pose.1 - self.grid.origin.1) / res;
        let step_rad = f64::from(std::f32::consts::TAU / N as f32);
        let (mut sum, mut spread, mut abs_sum, mut n) = (0.0, 0.0, 0.0f64, 0usize);
        for (k, &r32) in ranges.iter().enumerate().take(layout.beams().len()) {
            if !(0.0..Z_MAX).contains(&r32) {
                continue;
            }
            let r = f64::from(r32) / res;
            let (s, c) = (pose.2 + k as f64 * step_rad).sin_cos();
            let (gx, gy) = (ax + r * c, ay + r * s);
            // Endpoint error per axis, cells (module docs). The bearing's f32 rounding is half
            // an ulp of 2π (2.4e-7 rad), doubled for margin.
            let d = match path {
                Path::Fixed => {
                    4.0 * 2f64.powi(-9) + r * (2.0 * 2f64.powi(-15) + 4.8e-7) + 2f64.powi(-17) / res
                }
                Path::F32 => {
                    2f64.powi(-21) * (ax.abs() + ay.abs() + 4.0 * r + 4.0)
                        + r * (4.8e-7 + 2.0 * std::f64::consts::SQRT_2 * 6.4e-8)
                }
            };
            let centre = self.terms[usize::from(self.code(gx, gy))];
            let (mut lo, mut hi) = (centre, centre);
            // δ is below 0.05 cells here and an off-map code band is 0.16 cells wide, so the
            // box crosses at most one edge or band per axis: its corners, edge midpoints and
            // centre see every code in it.
            for dx in [-d, 0.0, d] {
                for dy in [-d, 0.0, d] {
                    let t = self.terms[usize::from(self.code(gx + dx, gy + dy))];
                    lo = lo.min(t);
                    hi = hi.max(t);
                }
            }
            sum += centre;
            spread += hi - lo;
            abs_sum += centre.abs();
            n += 1;
        }
        let own = match path {
            // Each term rounded to I16F16 (≤ 2⁻¹⁷); the sum is exact in I48F16.
            Path::Fixed => n as f64 * 2f64.powi(-17),
            // Each f32 table entry (ln to 3.8e-6 absolute, src/math/mod.rs, and a few roundings:
            // 1e-5) and the f32 sum (n roundings of at most Σ|term|·2⁻²⁴).
            Path::F32 => n as f64 * 1e-5 + n as f64 * abs_sum * 2f64.powi(-24),
        };
        (sum, spread + own)
    }
}

/// The next f32 below `x`.
fn next_down(x: f32) -> f32 {
    if x > 0.0 {
        f32::from_bits(x.to_bits() - 1)
    } else if x == 0.0 {
        -f32::from_bits(1)
    } else {
        f32::from_bits(x.to_bits() + 1)
    }
}

/// The next f32 above `x`.
fn next_up(x: f32) -> f32 {
    -next_down(-x)
}

type CaseRow = ((f32, f32, f32), (i32, i32, i32), (i64, i64), (f32, f32));

fn generate() -> (Vec<u8>, String, Vec<CaseRow>, Vec<f32>) {
    let m = crop();
    let blob = build_blob(&m, 2.0).unwrap();
    let grid = Grid {
        width: m.width as usize,
        height: m.height as usize,
        res: m.resolution_m,
        origin: (m.origin_x_m, m.origin_y_m),
        occupied: m.cells.iter().map(|c| *c == Occupancy::Occupied).collect(),
    };
    let layout = BeamLayout::<N>::uniform(
        0.0,
        std::f32::consts::TAU / N as f32,
        N,
        Z_MAX,
        SensorMount::CENTERED,
    )
    .unwrap();
    let ranges: Vec<f32> = layout
        .beams()
        .iter()
        .map(|b| {
            ray_cast(
                &grid,
                f64::from(TRUTH.0),
                f64::from(TRUTH.1),
                f64::from(TRUTH.2) + f64::from(b.bearing_rad),
                f64::from(Z_MAX),
            )
            .map_or(f32::INFINITY, |r| r as f32)
        })
        .collect();
    let mut src = String::new();
    writeln!(src, "//! Generated by `BEAMFIELD_WRITE_FIXED_CASES=1 cargo test -p host-tests --test fixed_firmware_cases`: do not edit.").unwrap();
    writeln!(src, "//! TurtleBot3 crop (cells {CROP:?}), {N}-beam scan ray-cast at {TRUTH:?}, AMCL defaults, z_max {Z_MAX} m.").unwrap();
    writeln!(src, "\n/// Beams.\npub const BEAMS: usize = {N};").unwrap();
    writeln!(
        src,
        "/// Max range, metres.\npub const Z_MAX_M: f32 = {Z_MAX:?};"
    )
    .unwrap();
    write!(
        src,
        "/// The scan, metres (`f32::INFINITY`: no return).\npub const RANGES_M: [f32; BEAMS] = ["
    )
    .unwrap();
    for r in &ranges {
        if r.is_finite() {
            write!(src, "{r:?}, ").unwrap();
        } else {
            write!(src, "f32::INFINITY, ").unwrap();
        }
    }
    writeln!(src, "];").unwrap();
    writeln!(src, "/// `(pose (x, y, θ) f32, pose I16F16 bits, fixed sum bounds (I48F16 bits, inclusive), f32 log-likelihood bounds (inclusive))`, from the f64 reference (see the generator).").unwrap();
    writeln!(
        src,
        "pub const CASES: [((f32, f32, f32), (i32, i32, i32), (i64, i64), (f32, f32)); 27] = ["
    )
    .unwrap();
    let reference = Reference::new(&grid, 2.0);
    let mut centres = Vec::new();
    let mut rows = Vec::new();
    for i in -1i32..=1 {
        for j in -1i32..=1 {
            for k in -1i32..=1 {
                let p = Pose::new(
                    TRUTH.0 + 0.05 * i as f32,
                    TRUTH.1 + 0.05 * j as f32,
                    TRUTH.2 + (2.0 * k as f32).to_radians(),
                );
                let q = (
                    I16F16::from_num(p.x_m),
                    I16F16::from_num(p.y_m),
                    I16F16::from_num(p.theta_rad),
                );
                // The fixed path scores the I16F16 pose, the f32 path the f32 one.
                let qf = (
                    q.0.to_num::<f64>(),
                    q.1.to_num::<f64>(),
                    q.2.to_num::<f64>(),
                );
                let pf = (f64::from(p.x_m), f64::from(p.y_m), f64::from(p.theta_rad));
                let (xc, xe) = reference.score(&layout, &ranges, qf, Path::Fixed);
                let (fc, fe) = reference.score(&layout, &ranges, pf, Path::F32);
                centres.push(fc);
                let lo_bits = ((xc - xe) * 65_536.0).floor() as i64;
                let hi_bits = ((xc + xe) * 65_536.0).ceil() as i64;
                // Outward to the next f32, so the f32 bounds contain the f64 ones.
                let f_lo = next_down((fc - fe) as f32);
                let f_hi = next_up((fc + fe) as f32);
                rows.push((
                    (p.x_m, p.y_m, p.theta_rad),
                    (q.0.to_bits(), q.1.to_bits(), q.2.to_bits()),
                    (lo_bits, hi_bits),
                    (f_lo, f_hi),
                ));
                writeln!(
                    src,
                    "    (({:?}, {:?}, {:?}), ({}, {}, {}), ({lo_bits}, {hi_bits}), ({f_lo:?}, {f_hi:?})),",
                    p.x_m,
                    p.y_m,
                    p.theta_rad,
                    q.0.to_bits(),
                    q.1.to_bits(),
                    q.2.to_bits()
                )
                .unwrap();
            }
        }
    }
    writeln!(src, "];").unwrap();
    // The true pose is the middle case by construction (the scan is ray-cast there); the f64
    // reference agrees that it scores highest.
    let best = (
        0,
        centres
            .iter()
            .enumerate()
            .fold(
                (0, f64::NEG_INFINITY),
                |b, (i, &c)| if c > b.1 { (i, c) } else { b },
            )
            .0,
    );
    writeln!(
        src,
        "/// Index of the best case (the true pose).\npub const BEST: usize = {};",
        best.1
    )
    .unwrap();
    assert_eq!(best.1, 13, "the true pose is the middle case");
    (blob, src, rows, ranges)
}

#[test]
fn firmware_fixed_cases_are_current() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware/src");
    let (blob, src, _, _) = generate();
    let (bp, sp) = (dir.join("fixed_blob.bin"), dir.join("fixed_cases.rs"));
    if std::env::var_os("BEAMFIELD_WRITE_FIXED_CASES").is_some() {
        std::fs::write(&bp, &blob).unwrap();
        std::fs::write(&sp, &src).unwrap();
    }
    assert!(
        std::fs::read(&bp).unwrap() == blob,
        "stale {}",
        bp.display()
    );
    assert!(
        std::fs::read_to_string(&sp).unwrap() == src,
        "stale {}",
        sp.display()
    );
}

/// The crate meets the bounds on the host too (the firmware repeats this on a Cortex-M0 and
/// M3 under QEMU): both paths within each case's bounds, both best at the true pose.
#[test]
fn crate_meets_the_fixed_cases_on_the_host() {
    let (blob, _, rows, ranges) = generate();
    let view = FieldView::parse(&blob).unwrap();
    let lf = LikelihoodField::new(view, LikelihoodParams::amcl_defaults(Z_MAX).unwrap());
    let ff = FixedField::new(&lf).unwrap();
    let layout = BeamLayout::<N>::uniform(
        0.0,
        std::f32::consts::TAU / N as f32,
        N,
        Z_MAX,
        SensorMount::CENTERED,
    )
    .unwrap();
    let fl = FixedLayout::new(&layout).unwrap();
    let scan = Scan::<N>::from_ranges(&ranges).unwrap();
    let fscan = FixedScan::from_scan(&scan, &ff);
    let (mut best_x, mut best_f) = ((i64::MIN, 0), (f32::NEG_INFINITY, 0));
    for (i, (p, q, (lo, hi), (flo, fhi))) in rows.iter().enumerate() {
        let fp = FixedPose::new(
            I16F16::from_bits(q.0),
            I16F16::from_bits(q.1),
            I16F16::from_bits(q.2),
        );
        let x = ff.score_sum(&fl, &fscan, &fp).to_bits();
        let f = lf
            .score(&layout, &scan, &Pose::new(p.0, p.1, p.2))
            .log_likelihood;
        println!(
            "case {i}: fixed {:.4} in [{:.4}, {:.4}], f32 {f:.4} in [{flo:.4}, {fhi:.4}]",
            x as f64 / 65_536.0,
            *lo as f64 / 65_536.0,
            *hi as f64 / 65_536.0
        );
        assert!(
            (*lo..=*hi).contains(&x),
            "case {i}: fixed {x} not in [{lo}, {hi}]"
        );
        assert!(
            (*flo..=*fhi).contains(&f),
            "case {i}: f32 {f} not in [{flo}, {fhi}]"
        );
        if x > best_x.0 {
            best_x = (x, i);
        }
        if f > best_f.0 {
            best_f = (f, i);
        }
    }
    assert_eq!((best_x.1, best_f.1), (13, 13));
}
