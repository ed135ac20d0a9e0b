//! f64 / brute-force references of the distance field and likelihood field (docs/models.md#field).
//!
//! Written from the definitions, sharing no code with the crate: the distance of a cell is the
//! minimum over every occupied cell of the Euclidean distance between cell indices (no
//! transform), the likelihood term is the formula in f64 (std's `exp`/`ln`), and ray casting
//! marches in small steps through the grid.

/// An occupancy grid, row 0 = lowest y, with its geometry (metres).
#[derive(Clone, Debug)]
pub struct Grid {
    /// Cells per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Cell size, m.
    pub res: f64,
    /// Lower-left corner of cell (0, 0), m.
    pub origin: (f64, f64),
    /// Row-major occupancy, row 0 = lowest y.
    pub occupied: Vec<bool>,
}

impl Grid {
    /// The occupied cells' `(ix, iy)`.
    pub fn seeds(&self) -> Vec<(i64, i64)> {
        let mut v = Vec::new();
        for iy in 0..self.height {
            for ix in 0..self.width {
                if self.occupied[iy * self.width + ix] {
                    v.push((ix as i64, iy as i64));
                }
            }
        }
        v
    }

    /// Whether cell `(ix, iy)` is occupied (false off the grid).
    pub fn is_occupied(&self, ix: i64, iy: i64) -> bool {
        ix >= 0
            && iy >= 0
            && (ix as usize) < self.width
            && (iy as usize) < self.height
            && self.occupied[iy as usize * self.width + ix as usize]
    }
}

/// Brute-force squared distance (cell units) from `(ix, iy)` to the nearest seed; `None` if
/// there is no seed.
pub fn brute_squared(seeds: &[(i64, i64)], ix: i64, iy: i64) -> Option<u64> {
    seeds
        .iter()
        .map(|&(sx, sy)| ((sx - ix).pow(2) + (sy - iy).pow(2)) as u64)
        .min()
}

/// The quantized distance (metres) the blob should answer at a map point: the exact distance
/// of the cell under the point (clamped at d_max, rounded to a step of d_max/255), plus the
/// Euclidean distance from the point to the map rectangle when off the map.
///
/// Also returns the unquantized value (exact cell distance clamped at d_max, plus off-map).
pub fn expected_distance(
    grid: &Grid,
    seeds: &[(i64, i64)],
    x: f64,
    y: f64,
    max_dist: f64,
) -> (f64, f64) {
    let gx = (x - grid.origin.0) / grid.res;
    let gy = (y - grid.origin.1) / grid.res;
    let (w, h) = (grid.width as f64, grid.height as f64);
    let cx = gx.clamp(0.0, w);
    let cy = gy.clamp(0.0, h);
    let off_cells = ((gx - cx).powi(2) + (gy - cy).powi(2)).sqrt();
    let ix = (cx.floor() as i64).min(grid.width as i64 - 1);
    let iy = (cy.floor() as i64).min(grid.height as i64 - 1);
    let exact =
        brute_squared(seeds, ix, iy).map_or(f64::INFINITY, |s| (s as f64).sqrt() * grid.res);
    let clamped = exact.min(max_dist);
    let step = max_dist / 255.0;
    let code = (clamped / step).round().min(255.0);
    (
        code * step + off_cells * grid.res,
        clamped + off_cells * grid.res,
    )
}

/// The likelihood-field beam term `ln(z_hit·N(d; 0, σ²) + z_rand/z_max)`, f64.
pub fn lf_term(d: f64, z_hit: f64, z_rand: f64, sigma: f64, z_max: f64) -> f64 {
    let g = (-0.5 * (d / sigma).powi(2)).exp() / (sigma * (2.0 * std::f64::consts::PI).sqrt());
    (z_hit * g + z_rand / z_max).ln()
}

/// Ray-cast range from `(x, y)` along `angle` (radians) to the first occupied cell, by
/// marching in steps of `res / 200`; `None` past `max_range`. The returned range ends just
/// inside the occupied cell.
pub fn ray_cast(grid: &Grid, x: f64, y: f64, angle: f64, max_range: f64) -> Option<f64> {
    let (c, s) = (angle.cos(), angle.sin());
    let dr = grid.res / 200.0;
    let mut r = 0.0;
    while r < max_range {
        let px = x + r * c;
        let py = y + r * s;
        let ix = ((px - grid.origin.0) / grid.res).floor() as i64;
        let iy = ((py - grid.origin.1) / grid.res).floor() as i64;
        if grid.is_occupied(ix, iy) {
            return Some(r);
        }
        r += dr;
    }
    None
}
