//! An AMCL-style beam model, as a same-run baseline for the race (`host-tests/benches/race.rs`) and checked
//! against the crate's ray caster (`host-tests/tests/race_smoothness.rs`): written here from the algorithm
//! AMCL documents, not from its source.
//!
//! What it does per beam, as AMCL's `BeamModel` does: cast with Bresenham's line algorithm from
//! the start cell towards the cell at `max_range` (f64 `cos`/`sin` of the beam's world angle),
//! stopping at the first occupied or off-map cell and returning the centre-to-centre distance;
//! then the unnormalized mixture
//! `pz = z_hit·e^{−(z−z*)²/2σ²} + [z < z*]·z_short·λe^{−λz} + [z = z_max]·z_max_w + [z < z_max]·z_rand/z_max`
//! and the `p += pz³` accumulation.
//!
//! The map is one 16-byte cell per grid cell (an `i32` state and an `f64` distance), like
//! AMCL's map cells, built from the blob: occupied = code 0. AMCL also stops at unknown cells;
//! the blob does not keep them (unknown is not occupied there), so both models see the same
//! walls.

use beamfield::{BeamFieldModel, BeamIntrinsics, BeamLayout, FieldView, Pose};

/// One grid cell as AMCL stores it: occupancy state (−1 free, +1 occupied) and the distance to
/// the nearest occupied cell (unused by the beam model; it is there for the memory layout).
#[derive(Clone, Copy)]
#[allow(dead_code)]
struct Cell {
    state: i32,
    dist: f64,
}

/// The map, the beams' bearings and the beam model's parameters, f64 throughout.
pub struct AmclBeam {
    cells: Vec<Cell>,
    /// Bearing of each beam of the layout, radians (the layout's, widened).
    bearings: Vec<f64>,
    width: i64,
    height: i64,
    res: f64,
    origin: (f64, f64),
    z_hit: f64,
    z_short: f64,
    z_max_w: f64,
    z_rand: f64,
    sigma: f64,
    lambda: f64,
    max_range: f64,
}

impl AmclBeam {
    /// The blob's walls, the layout's bearings and the beam model's intrinsics.
    pub fn new<const N: usize>(
        view: &FieldView<'_>,
        layout: &BeamLayout<N>,
        intr: &BeamIntrinsics,
    ) -> Self {
        let h = view.header();
        let cells = view
            .codes()
            .iter()
            .map(|&c| Cell {
                state: if c == 0 { 1 } else { -1 },
                dist: f64::from(c) * f64::from(view.step_m()),
            })
            .collect();
        let w = intr.weights();
        Self {
            cells,
            bearings: layout
                .beams()
                .iter()
                .map(|b| f64::from(b.bearing_rad))
                .collect(),
            width: i64::from(h.width),
            height: i64::from(h.height),
            res: f64::from(h.cell_size_m),
            origin: (f64::from(h.origin_x_m), f64::from(h.origin_y_m)),
            z_hit: f64::from(w[0]),
            z_short: f64::from(w[1]),
            z_max_w: f64::from(w[2]),
            z_rand: f64::from(w[3]),
            sigma: f64::from(intr.sigma_hit_m()),
            lambda: f64::from(intr.lambda_short_per_m()),
            max_range: f64::from(intr.max_range_m()),
        }
    }

    /// The same walls (the caster's blob), layout and intrinsics as the crate's `beam`.
    pub fn like<const N: usize>(beam: &BeamFieldModel<'_>, layout: &BeamLayout<N>) -> Self {
        Self::new(beam.caster().view(), layout, beam.model().intrinsics())
    }

    /// The cell holding world point `(x, y)`: `floor((x − origin)/res)`.
    fn to_cell(&self, x: f64, y: f64) -> (i64, i64) {
        (
            ((x - self.origin.0) / self.res).floor() as i64,
            ((y - self.origin.1) / self.res).floor() as i64,
        )
    }

    /// Whether the ray stops in cell `(x, y)`: occupied, or off the map.
    fn stops(&self, x: i64, y: i64) -> bool {
        if x < 0 || y < 0 || x >= self.width || y >= self.height {
            return true;
        }
        self.cells
            .get((y * self.width + x) as usize)
            .is_none_or(|c| c.state > -1)
    }

    /// Bresenham from the cell of `(ox, oy)` towards the cell at `max_range` along `angle`:
    /// the centre-to-centre distance (metres) to the first cell that stops the ray, or
    /// `max_range` when none does.
    pub fn calc_range(&self, ox: f64, oy: f64, angle: f64) -> f64 {
        let (mut x0, mut y0) = self.to_cell(ox, oy);
        let (mut x1, mut y1) = self.to_cell(
            ox + self.max_range * angle.cos(),
            oy + self.max_range * angle.sin(),
        );
        let steep = (y1 - y0).abs() > (x1 - x0).abs();
        if steep {
            std::mem::swap(&mut x0, &mut y0);
            std::mem::swap(&mut x1, &mut y1);
        }
        let dx = (x1 - x0).abs();
        let dy = (y1 - y0).abs();
        let xstep = if x1 > x0 { 1 } else { -1 };
        let ystep = if y1 > y0 { 1 } else { -1 };
        let (sx, sy) = (x0, y0);
        let dist = |x: i64, y: i64| {
            let (ex, ey) = ((x - sx) as f64, (y - sy) as f64);
            (ex * ex + ey * ey).sqrt() * self.res
        };
        let (mut x, mut y) = (x0, y0);
        let mut err = 0i64;
        loop {
            let hit = if steep {
                self.stops(y, x)
            } else {
                self.stops(x, y)
            };
            if hit {
                return dist(x, y);
            }
            if x == x1 {
                return self.max_range;
            }
            x += xstep;
            err += dy;
            if 2 * err >= dx {
                y += ystep;
                err -= dx;
            }
        }
    }

    /// `z*` (metres) of every beam of the layout from `pose` (the laser's pose; no mount
    /// offset) into `out` (a shorter `out` receives what fits).
    pub fn cast_scan(&self, pose: &Pose, out: &mut [f64]) {
        let (x, y, t) = (
            f64::from(pose.x_m),
            f64::from(pose.y_m),
            f64::from(pose.theta_rad),
        );
        for (o, &b) in out.iter_mut().zip(&self.bearings) {
            *o = self.calc_range(x, y, t + b);
        }
    }

    /// The scan's AMCL weight factor `Σ pz³` over the readings `ranges_m` (beam `k` of the
    /// layout) at `pose` (the laser's pose; no mount offset).
    pub fn score(&self, ranges_m: &[f32], pose: &Pose) -> f64 {
        let (px, py, pa) = (
            f64::from(pose.x_m),
            f64::from(pose.y_m),
            f64::from(pose.theta_rad),
        );
        let denom = 2.0 * self.sigma * self.sigma;
        let mut p = 0.0;
        for (&r, &bearing) in ranges_m.iter().zip(&self.bearings) {
            let obs = f64::from(r).min(self.max_range);
            if obs.is_nan() || obs < 0.0 {
                continue;
            }
            let map_range = self.calc_range(px, py, pa + bearing);
            let z = obs - map_range;
            let mut pz = self.z_hit * (-(z * z) / denom).exp();
            if z < 0.0 {
                pz += self.z_short * self.lambda * (-self.lambda * obs).exp();
            }
            if obs >= self.max_range {
                pz += self.z_max_w;
            } else {
                pz += self.z_rand / self.max_range;
            }
            p += pz * pz * pz;
        }
        p
    }
}
