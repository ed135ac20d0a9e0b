//! The demo's device numbers against an independent f64 computation.
//!
//! `demo_ref` recomputes the demo with the same crate on the host, so it cannot see a bug that
//! the device and the host share. This module scores every hypothesis of the coarse grid again
//! in f64, from the definitions and without the crate's scoring code: the beam endpoint
//! `x + r·cos(θ + β)` in f64, the cell under it (or, off the map, the nearest cell plus the
//! distance to the map in code steps, rounded: docs/blob-format.md), the likelihood-field term
//! `ln(z_hit·N(d; 0, σ²) + z_rand/z_max)` (Thrun Table 6.3) at the stored distance, and the
//! tempered sum `(1/κ)·Σ` (docs/models.md#tempering). Only the map's stored codes are read
//! through the crate (`FieldView::code`: the blob is data, not computation).
//!
//! The device computes in f32 (the prepared fixed-point path for endpoints), so each pose's
//! log-likelihood is bracketed, not matched: per beam, the f32 endpoint lies within `δ` cells of
//! the exact one (`δ` below), so the device's term lies between the smallest and largest f64
//! term over the codes inside the box `±δ` around the exact endpoint; the f32 table entries and
//! the f32 sum add their own rounding. From the per-pose brackets `c_i ± e_i` follow brackets on
//! what the device prints: the best pose must be a possible maximum, its weight and the
//! effective sample size must lie inside the bounds the brackets give (plus the printed digits'
//! half unit).

use crate::error::{Error, Result};
use beamfield::{FieldView, Pose};
use beamfield_fixtures::demo_plan::{COARSE, KAPPA, POSES, SIGMA_HIT_M, Z_HIT, Z_RAND};
use beamfield_fixtures::demo_scans::{MAX_RANGE_M, SCANS};

/// Beams per scan and the layout's first bearing and step, as the demo builds them (f32).
const BEAMS: usize = 180;
const FIRST_RAD: f32 = -core::f32::consts::FRAC_PI_2;
const STEP_RAD: f32 = core::f32::consts::PI / BEAMS as f32;

/// The map as the f64 computation needs it.
struct Map<'a> {
    view: FieldView<'a>,
    width: f64,
    height: f64,
    cell_m: f64,
    origin: (f64, f64),
    step_m: f64,
    /// Cells per code step (`cell / step`), for the off-map charge.
    steps_per_cell: f64,
}

impl Map<'_> {
    /// The table index at grid point `(gx, gy)` (cells), by docs/blob-format.md's rule.
    fn code(&self, gx: f64, gy: f64) -> u8 {
        if (0.0..self.width).contains(&gx) && (0.0..self.height).contains(&gy) {
            return self.view.code(gx as u32, gy as u32).unwrap_or(255);
        }
        let cx = gx.clamp(0.0, self.width);
        let cy = gy.clamp(0.0, self.height);
        let ix = (cx.floor() as u32).min(self.width as u32 - 1);
        let iy = (cy.floor() as u32).min(self.height as u32 - 1);
        let off = ((gx - cx).powi(2) + (gy - cy).powi(2)).sqrt();
        let extra = (off * self.steps_per_cell + 0.5).floor().min(255.0);
        (f64::from(self.view.code(ix, iy).unwrap_or(255)) + extra).min(255.0) as u8
    }
}

/// The term of code `c`, f64.
fn term(c: u8, step_m: f64) -> f64 {
    let d = f64::from(c) * step_m;
    let s = f64::from(SIGMA_HIT_M);
    let g = (-0.5 * (d / s).powi(2)).exp() / (s * (2.0 * std::f64::consts::PI).sqrt());
    (f64::from(Z_HIT) * g + f64::from(Z_RAND) / f64::from(MAX_RANGE_M)).ln()
}

/// Per-beam bound, in cells, on the distance between the device's endpoint and the exact one
/// for a beam of `r` cells from a sensor at grid position `(ax, ay)`: the prepared path's
/// fixed-point and f32 roundings (`4·2^−F + 2^−21·(|ax| + |ay| + 4R + 4)` with F ≥ 14
/// fractional bits; host-tests/tests/field_prepared.rs derives it), plus the bearing's f32
/// rounding (one ulp of π/2, 1.2e-7 rad) and the sine and cosine errors of the heading and the
/// bearing (6.4e-8 each, src/math.rs; at most 2√2 of them in the rotated unit vector), both
/// times the range.
fn delta_cells(ax: f64, ay: f64, r: f64) -> f64 {
    let sin_cos = 6.4e-8;
    4.0 * 2f64.powi(-14)
        + 2f64.powi(-21) * (ax.abs() + ay.abs() + 4.0 * r + 4.0)
        + r * (1.2e-7 + 2.0 * std::f64::consts::SQRT_2 * sin_cos)
}

/// A pose's tempered log-likelihood bracket: centre (the exact f64 value) and half-width.
#[derive(Clone, Copy)]
struct Bracket {
    c: f64,
    e: f64,
}

fn score(map: &Map<'_>, ranges: &[f32; BEAMS], pose: &Pose, terms: &[f64; 256]) -> Bracket {
    let (x, y, th) = (
        f64::from(pose.x_m),
        f64::from(pose.y_m),
        f64::from(pose.theta_rad),
    );
    let ax = (x - map.origin.0) / map.cell_m;
    let ay = (y - map.origin.1) / map.cell_m;
    let (mut sum, mut spread, mut abs_sum, mut n) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    for (k, &r32) in ranges.iter().enumerate() {
        // The crate's reading policy for the likelihood field: scored if 0 ≤ r < z_max.
        if !(0.0..MAX_RANGE_M).contains(&r32) {
            continue;
        }
        let r = f64::from(r32) / map.cell_m;
        let b = f64::from(FIRST_RAD) + k as f64 * f64::from(STEP_RAD);
        let (s, c) = (th + b).sin_cos();
        let (gx, gy) = (ax + r * c, ay + r * s);
        let centre = terms[usize::from(map.code(gx, gy))];
        let d = delta_cells(ax, ay, r);
        let (mut lo, mut hi) = (centre, centre);
        // The box's corners, edge midpoints and centre: δ is far below a cell and below an
        // off-map code band (cell/step ≈ 6.4 steps per cell: a band is 0.16 cells), so the box
        // crosses at most one edge per axis and every code in it is at one of these points.
        for dx in [-d, 0.0, d] {
            for dy in [-d, 0.0, d] {
                let t = terms[usize::from(map.code(gx + dx, gy + dy))];
                lo = lo.min(t);
                hi = hi.max(t);
            }
        }
        sum += centre;
        spread += hi - lo;
        abs_sum += centre.abs();
        n += 1;
    }
    // Device roundings: each f32 table entry (the term's f32 evaluation: ln to 3.8e-6
    // absolute, src/math.rs, plus a few roundings: 1e-5 per entry), the f32 sum (n roundings
    // of at most Σ|term|·2^−24 each) and the division by κ.
    let f32_err = n as f64 * 1e-5 + n as f64 * abs_sum * 2f64.powi(-24);
    let kappa = f64::from(KAPPA);
    let c = sum / kappa;
    Bracket {
        c,
        e: (spread + f32_err) / kappa + c.abs() * 2f64.powi(-23),
    }
}

/// What the device printed for one scan.
struct Printed {
    best: [f64; 3],
    weight: f64,
    ess: f64,
}

fn between<'a>(line: &'a str, start: &str, end: &str) -> Option<&'a str> {
    let from = line.find(start)? + start.len();
    let rest = line.get(from..)?;
    rest.get(..rest.find(end)?)
}

fn printed(out: &str, log_index: u32) -> Result<Printed> {
    let head = format!("scan {log_index}: best (");
    let line = out
        .lines()
        .find(|l| l.starts_with(&head))
        .ok_or_else(|| Error::Output(format!("the device printed no line for scan {log_index}")))?;
    let bad =
        |what: &str| Error::Output(format!("scan {log_index}: cannot read {what} in {line:?}"));
    let pose: Vec<f64> = between(line, "best (", " deg)")
        .ok_or_else(|| bad("the best pose"))?
        .split(", ")
        .filter_map(|p| p.trim().parse().ok())
        .collect();
    let best: [f64; 3] = pose.try_into().map_err(|_| bad("the best pose"))?;
    let num = |key: &str| -> Result<f64> {
        between(line, key, " ")
            .and_then(|t| t.parse().ok())
            .ok_or_else(|| bad(key.trim()))
    };
    Ok(Printed {
        best,
        weight: num("weight ")?,
        ess: num("ESS ")?,
    })
}

/// One scan's verdict: the f64 values and whether the device's lie inside the brackets.
pub struct ScanCheck {
    /// Log index of the scan.
    pub log_index: u32,
    /// The f64 weight of the device's best pose, and its bounds.
    pub weight: (f64, f64, f64),
    /// The f64 effective sample size, and its bounds.
    pub ess: (f64, f64, f64),
    /// The largest per-pose bracket half-width over the grid, nats (tempered).
    pub worst_e: f64,
}

/// Checks the device's report `out` against the f64 computation over `blob`.
///
/// # Errors
/// A scan whose printed best pose cannot be a maximum of the f64 brackets, or whose printed
/// weight or ESS lies outside the bounds, or a report that cannot be read.
pub fn check(out: &str, blob: &[u8]) -> Result<Vec<ScanCheck>> {
    let view = FieldView::parse(blob).map_err(|e| Error::Host(format!("demo blob: {e}")))?;
    let h = *view.header();
    let step_m = f64::from(h.max_dist_m) / 255.0;
    let map = Map {
        view,
        width: f64::from(h.width),
        height: f64::from(h.height),
        cell_m: f64::from(h.cell_size_m),
        origin: (f64::from(h.origin_x_m), f64::from(h.origin_y_m)),
        step_m,
        steps_per_cell: f64::from(h.cell_size_m) / step_m,
    };
    let terms: [f64; 256] = std::array::from_fn(|c| term(c as u8, map.step_m));
    let mut checks = Vec::new();
    for demo in SCANS.iter() {
        let s = demo.log_index;
        let p = printed(out, s)?;
        let logged = Pose::new(demo.pose[0], demo.pose[1], demo.pose[2]);
        let brackets: Vec<Bracket> = (0..POSES)
            .map(|i| score(&map, &demo.ranges_m, &COARSE.pose(&logged, i), &terms))
            .collect();
        // The device's best pose in the grid: printed to 1 mm and 0.1°, grid spacing 2.5 cm
        // and 0.5°, so exactly one pose matches.
        let best = (0..POSES)
            .find(|&i| {
                let q = COARSE.pose(&logged, i);
                (f64::from(q.x_m) - p.best[0]).abs() <= 0.0006
                    && (f64::from(q.y_m) - p.best[1]).abs() <= 0.0006
                    && (f64::from(q.theta_rad.to_degrees()) - p.best[2]).abs() <= 0.06
            })
            .ok_or_else(|| {
                Error::Mismatch(format!(
                    "scan {s}: the printed best pose is not a grid pose"
                ))
            })?;
        let top_lo = brackets
            .iter()
            .map(|b| b.c - b.e)
            .fold(f64::NEG_INFINITY, f64::max);
        let b = brackets[best];
        if b.c + b.e < top_lo {
            return Err(Error::Mismatch(format!(
                "scan {s}: the device's best pose scores {:.4} ± {:.4} in f64, below another \
                 pose's lower bound {top_lo:.4}",
                b.c, b.e
            )));
        }
        // Weights relative to the f64 maximum, and their brackets.
        let m = brackets
            .iter()
            .map(|b| b.c)
            .fold(f64::NEG_INFINITY, f64::max);
        let (mut s0, mut s_lo, mut s_hi) = (0.0, 0.0, 0.0);
        let (mut q0, mut q_lo, mut q_hi) = (0.0, 0.0, 0.0);
        let mut worst_e = 0.0f64;
        for br in &brackets {
            let w = (br.c - m).exp();
            s0 += w;
            s_lo += w * (-br.e).exp();
            s_hi += w * br.e.exp();
            q0 += w * w;
            q_lo += w * w * (-2.0 * br.e).exp();
            q_hi += w * w * (2.0 * br.e).exp();
            worst_e = worst_e.max(br.e);
        }
        let wb = (b.c - m).exp();
        let weight = (
            wb / s0,
            wb * (-b.e).exp() / s_hi - 0.0005,
            wb * b.e.exp() / s_lo + 0.0005,
        );
        let ess = (
            s0 * s0 / q0,
            s_lo * s_lo / q_hi - 0.05,
            s_hi * s_hi / q_lo + 0.05,
        );
        if !(weight.1..=weight.2).contains(&p.weight) {
            return Err(Error::Mismatch(format!(
                "scan {s}: the device's weight {} is outside the f64 bounds [{:.4}, {:.4}] (f64 {:.4})",
                p.weight, weight.1, weight.2, weight.0
            )));
        }
        if !(ess.1..=ess.2).contains(&p.ess) {
            return Err(Error::Mismatch(format!(
                "scan {s}: the device's ESS {} is outside the f64 bounds [{:.2}, {:.2}] (f64 {:.2})",
                p.ess, ess.1, ess.2, ess.0
            )));
        }
        checks.push(ScanCheck {
            log_index: s,
            weight,
            ess,
            worst_e,
        });
    }
    Ok(checks)
}

#[cfg(test)]
mod tests {
    use super::{delta_cells, printed, term};

    #[test]
    fn reads_the_device_line() {
        let out = "scan 50: best (9.909, -18.937, 179.5 deg) offset 2.5 cm 0.0 deg; weight 0.038 ESS 59.0 of 6069; lag-1 0.31 over 171 beams\n";
        let p = printed(out, 50).unwrap();
        assert_eq!(p.best, [9.909, -18.937, 179.5]);
        assert_eq!((p.weight, p.ess), (0.038, 59.0));
        assert!(printed(out, 51).is_err());
    }

    /// The term at distance 0 is `ln(z_hit/(σ√(2π)) + z_rand/z_max)` and falls with the
    /// distance; the endpoint box stays far below a cell at the longest Intel range (81.83 m,
    /// 1,637 cells), so the 9-point box search is enough.
    #[test]
    fn terms_and_box() {
        let step = 2.0 / 255.0;
        let want0 = (0.95 / (0.0588f64 * (2.0 * std::f64::consts::PI).sqrt()) + 0.05 / 81.83).ln();
        assert!((term(0, step) - want0).abs() < 1e-6, "{}", term(0, step));
        assert!((1..=255).all(|c| term(c, step) <= term(c - 1, step)));
        assert!(term(255, step) < term(0, step) - 5.0);
        let d = delta_cells(1000.0, 1000.0, 1637.0);
        assert!(d < 0.01, "{d}");
    }
}
