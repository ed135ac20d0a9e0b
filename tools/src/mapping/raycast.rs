//! Exact grid traversal (Amanatides & Woo, "A fast voxel traversal algorithm for ray tracing",
//! Eurographics 1987) and the host-side reference ray cast for the beam model's `z*`.
//!
//! The traversal visits, in order, every cell whose interior the segment crosses, each with the
//! distance (metres from the start) at which the segment enters it. Conventions for the
//! measure-zero cases: where the segment passes exactly through a cell corner it steps
//! diagonally (the two cells it only touches at that point are not visited); a segment lying
//! exactly on a grid line is taken to run through the cells on its non-negative side; a start
//! point exactly on a cell boundary belongs to the cell the segment goes into. Computation is in
//! f64, in cell units.

use super::grid::{GridGeometry, OccupiedCells};
use std::ops::ControlFlow;

/// Visits the cells crossed by the segment from `(x0, y0)` to `(x1, y1)` (world metres), clipped
/// to the grid, calling `visit(col, row, enter_m)` with the distance along the segment (metres
/// from `(x0, y0)`) at which it enters each cell. `visit` returns [`ControlFlow::Break`] to stop.
/// Non-finite input visits nothing.
pub fn traverse<F>(geometry: &GridGeometry, x0_m: f64, y0_m: f64, x1_m: f64, y1_m: f64, visit: F)
where
    F: FnMut(usize, usize, f64) -> ControlFlow<()>,
{
    let dx_m = x1_m - x0_m;
    let dy_m = y1_m - y0_m;
    let length_m = dx_m.hypot(dy_m);
    if !(length_m.is_finite() && x0_m.is_finite() && y0_m.is_finite()) {
        return;
    }
    if length_m == 0.0 {
        if let Some((c, r)) = geometry.cell_of(x0_m, y0_m) {
            let mut visit = visit;
            let _ = visit(c, r, 0.0);
        }
        return;
    }
    let _ = traverse_ray(
        geometry,
        x0_m,
        y0_m,
        dx_m / length_m,
        dy_m / length_m,
        length_m,
        visit,
    );
}

/// As [`traverse`], for a ray from `(x0, y0)` with unit direction `(ux, uy)`, up to `length_m`.
fn traverse_ray<F>(
    g: &GridGeometry,
    x0_m: f64,
    y0_m: f64,
    ux: f64,
    uy: f64,
    length_m: f64,
    mut visit: F,
) -> ControlFlow<()>
where
    F: FnMut(usize, usize, f64) -> ControlFlow<()>,
{
    if !(x0_m.is_finite() && y0_m.is_finite() && ux.is_finite() && uy.is_finite())
        || length_m.is_nan()
    {
        return ControlFlow::Continue(());
    }
    let res = g.resolution_m;
    // Cell units: the grid is the box [0, W] × [0, H]; distances along the ray scale by 1/res.
    let px = (x0_m - g.origin_x_m) / res;
    let py = (y0_m - g.origin_y_m) / res;
    let len = length_m / res;
    let (w, h) = (g.width as f64, g.height as f64);
    // Clip to the box (slab method).
    let (mut s_in, mut s_out) = (0.0f64, len);
    for (p, u, hi) in [(px, ux, w), (py, uy, h)] {
        if u == 0.0 {
            if !(0.0..=hi).contains(&p) {
                return ControlFlow::Continue(());
            }
        } else {
            let a = (0.0 - p) / u;
            let b = (hi - p) / u;
            s_in = s_in.max(a.min(b));
            s_out = s_out.min(a.max(b));
        }
    }
    if s_in >= s_out {
        return ControlFlow::Continue(());
    }
    let sx = px + s_in * ux;
    let sy = py + s_in * uy;
    // The cell the ray goes into from the start point.
    let first = |p: f64, u: f64, n: usize| -> usize {
        let c = if u < 0.0 { p.ceil() - 1.0 } else { p.floor() };
        (c.max(0.0) as usize).min(n - 1)
    };
    let mut col = first(sx, ux, g.width);
    let mut row = first(sy, uy, g.height);
    let step = |u: f64| if u > 0.0 { 1i64 } else { -1 };
    // Ray distance (cell units, from the original start) to the next vertical / horizontal line.
    let next = |c: usize, p0: f64, u: f64| -> f64 {
        if u > 0.0 {
            (c as f64 + 1.0 - p0) / u
        } else if u < 0.0 {
            (c as f64 - p0) / u
        } else {
            f64::INFINITY
        }
    };
    let mut t_x = next(col, px, ux);
    let mut t_y = next(row, py, uy);
    let dt_x = if ux == 0.0 {
        f64::INFINITY
    } else {
        1.0 / ux.abs()
    };
    let dt_y = if uy == 0.0 {
        f64::INFINITY
    } else {
        1.0 / uy.abs()
    };
    let mut s = s_in;
    loop {
        visit(col, row, s * res)?;
        let (nc, nr);
        if t_x < t_y {
            s = t_x;
            t_x += dt_x;
            nc = col as i64 + step(ux);
            nr = row as i64;
        } else if t_y < t_x {
            s = t_y;
            t_y += dt_y;
            nc = col as i64;
            nr = row as i64 + step(uy);
        } else {
            // Exactly through a corner: diagonal step.
            s = t_x;
            t_x += dt_x;
            t_y += dt_y;
            nc = col as i64 + step(ux);
            nr = row as i64 + step(uy);
        }
        if s >= s_out || nc < 0 || nr < 0 || nc >= g.width as i64 || nr >= g.height as i64 {
            return ControlFlow::Continue(());
        }
        col = nc as usize;
        row = nr as usize;
    }
}

/// The host-side reference ray cast: distance (metres) from `(x, y)` along `angle_rad` (world
/// frame, counter-clockwise from +x) to the boundary of the first occupied cell, or `max_range_m`
/// when no occupied cell is entered within it.
///
/// Exact up to f64 rounding (a grid traversal, not sampling): this is the reference for the
/// beam model's `z*` on the device. Only occupied cells stop the ray: free and unknown cells,
/// and everything off the grid, are transparent (AMCL's `map_calc_range` also stops at unknown
/// and off-map cells; the distance-field blob only knows occupied cells, so this matches what
/// the device can compute). A start inside an occupied cell gives 0. Non-finite input gives
/// `max_range_m`.
pub fn ray_cast_grid<G: OccupiedCells + ?Sized>(
    grid: &G,
    x_m: f64,
    y_m: f64,
    angle_rad: f64,
    max_range_m: f64,
) -> f32 {
    let g = grid.geometry();
    let mut hit = max_range_m;
    if angle_rad.is_finite() && max_range_m > 0.0 {
        let (uy, ux) = angle_rad.sin_cos();
        let _ = traverse_ray(&g, x_m, y_m, ux, uy, max_range_m, |c, r, enter_m| {
            if grid.is_occupied(c, r) {
                hit = enter_m.min(max_range_m);
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
    }
    hit as f32
}

#[cfg(test)]
mod tests {
    use super::super::grid::OccupancyGrid;
    use super::*;
    use proptest::prelude::*;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

    /// 10 × 10 cells of 0.1 m, origin (−0.5, −0.5): cell (c, r) has its centre at
    /// (−0.45 + 0.1c, −0.45 + 0.1r).
    fn room() -> OccupancyGrid {
        OccupancyGrid::from_ascii(
            &[
                "##########",
                "#........#",
                "#........#",
                "#........#",
                "#....#...#",
                "#........#",
                "#........#",
                "#........#",
                "#........#",
                "##########",
            ],
            0.1,
            (-0.5, -0.5),
        )
        .unwrap()
    }

    fn center(c: usize, r: usize) -> (f64, f64) {
        room().geometry().cell_center(c, r)
    }

    #[test]
    fn hand_made_room_known_answers() {
        let g = room();
        // (start cell, angle, expected distance in metres), worked out by hand: from a cell
        // centre the ray leaves its cell after 0.05 m and crosses 0.1 m per free cell.
        let (x, y) = center(2, 2);
        let cases = [
            // East: free cells 3..=8, wall at col 9 → 0.05 + 6·0.1.
            (x, y, 0.0, 0.65),
            // West: wall at col 0 → 0.05 + 1·0.1.
            (x, y, PI, 0.15),
            // North: free rows 3..=8, wall at row 9.
            (x, y, FRAC_PI_2, 0.65),
            // South: wall at row 0.
            (x, y, -FRAC_PI_2, 0.15),
            // North-east diagonal from (2,2): through corners to the pillar at (5,5), entered at
            // its corner (5,5) → 2.5·√2 cells.
            (x, y, FRAC_PI_4, 0.25 * 2f64.sqrt()),
        ];
        for (x, y, a, want) in cases {
            let got = ray_cast_grid(&g, x, y, a, 5.0);
            assert!(
                (f64::from(got) - want).abs() < 1e-6,
                "from ({x}, {y}) at {a}: {got}, want {want}"
            );
        }
        // A shallow angle: from (2,2)'s centre at atan2(0.5, 3) (a rise of half a cell over
        // three) the ray reaches the east wall's inner face x = 0.4 (0.65 m further in x) at
        // y = y0 + 0.65·(0.5/3) ≈ 0.108 m higher, inside row 3: it hits the wall face there.
        let a = 0.5f64.atan2(3.0);
        let got = f64::from(ray_cast_grid(&g, x, y, a, 5.0));
        let want = 0.65 / a.cos();
        assert!((got - want).abs() < 1e-6, "{got} vs {want}");
    }

    #[test]
    fn start_and_range_edge_cases() {
        let g = room();
        let (x, y) = center(2, 2);
        // Capped by the max range.
        assert_eq!(ray_cast_grid(&g, x, y, 0.0, 0.3), 0.3);
        // Inside an occupied cell: zero.
        let (wx, wy) = center(0, 4);
        assert_eq!(ray_cast_grid(&g, wx, wy, 0.0, 5.0), 0.0);
        // From outside the grid, aimed at it: enters the west wall at x = −0.5.
        let got = ray_cast_grid(&g, -1.5, y, 0.0, 5.0);
        assert!((f64::from(got) - 1.0).abs() < 1e-6, "{got}");
        // From outside, aimed away: nothing.
        assert_eq!(ray_cast_grid(&g, -1.5, y, PI, 5.0), 5.0);
        // Off-map is transparent: a grid with no walls gives max range.
        let open = OccupancyGrid::from_ascii(&["...", "..."], 1.0, (0.0, 0.0)).unwrap();
        assert_eq!(ray_cast_grid(&open, 0.5, 0.5, 0.3, 9.0), 9.0);
        // Unknown cells are transparent too.
        let unknown = OccupancyGrid::from_ascii(&["??#"], 1.0, (0.0, 0.0)).unwrap();
        assert_eq!(ray_cast_grid(&unknown, 0.5, 0.5, 0.0, 9.0), 1.5);
        // Non-finite input: max range.
        assert_eq!(ray_cast_grid(&g, f64::NAN, y, 0.0, 5.0), 5.0);
        assert_eq!(ray_cast_grid(&g, x, y, f64::NAN, 5.0), 5.0);
    }

    #[test]
    fn start_on_a_boundary_goes_into_the_next_cell() {
        // Start exactly on the line between col 1 (free) and col 0 (occupied), heading west:
        // distance 0; heading east: the wall at col 3, 2 cells away.
        let g = OccupancyGrid::from_ascii(&["#..#"], 1.0, (0.0, 0.0)).unwrap();
        assert_eq!(ray_cast_grid(&g, 1.0, 0.5, PI, 9.0), 0.0);
        assert_eq!(ray_cast_grid(&g, 1.0, 0.5, 0.0, 9.0), 2.0);
    }

    #[test]
    fn traversal_visits_a_connected_chain_in_order() {
        let g = room().geometry();
        let mut cells = Vec::new();
        traverse(&g, -0.43, -0.41, 0.37, 0.2, |c, r, s| {
            cells.push((c, r, s));
            ControlFlow::Continue(())
        });
        assert_eq!(cells.first().map(|c| (c.0, c.1)), Some((0, 0)));
        assert_eq!(cells.last().map(|c| (c.0, c.1)), g.cell_of(0.37, 0.2));
        for w in cells.windows(2) {
            let (a, b) = (w[0], w[1]);
            assert_eq!(a.0.abs_diff(b.0) + a.1.abs_diff(b.1), 1, "{a:?} → {b:?}");
            assert!(b.2 > a.2);
        }
    }

    /// Entry distance (cell units) of the ray into the closed box `[c, c+1] × [r, r+1]` when the
    /// intersection has positive length, by the slab method: the brute-force reference.
    fn slab_entry(px: f64, py: f64, ux: f64, uy: f64, c: f64, r: f64) -> Option<f64> {
        let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
        for (p, u, a) in [(px, ux, c), (py, uy, r)] {
            if u == 0.0 {
                if p <= a || p >= a + 1.0 {
                    return None;
                }
            } else {
                let t0 = (a - p) / u;
                let t1 = (a + 1.0 - p) / u;
                lo = lo.max(t0.min(t1));
                hi = hi.min(t0.max(t1));
            }
        }
        (lo < hi).then_some(lo)
    }

    proptest! {
        /// Random grids, starts and angles: the traversal's answer equals the minimum over all
        /// occupied cells of the slab entry distance (capped at the max range).
        #[test]
        fn matches_brute_force_slab_reference(
            w in 1usize..12,
            h in 1usize..12,
            bits in proptest::collection::vec(0u8..4, 144),
            px in -3.0f64..15.0,
            py in -3.0f64..15.0,
            angle in -4.0f64..4.0,
            res in 0.05f64..1.0,
            max_cells in 0.5f64..25.0,
        ) {
            let cells: Vec<_> = (0..w * h)
                .map(|i| if bits[i] == 0 { super::super::grid::Cell::Occupied } else { super::super::grid::Cell::Free })
                .collect();
            let geometry = GridGeometry {
                width: w, height: h, resolution_m: res, origin_x_m: -0.7, origin_y_m: 1.3,
            };
            let grid = OccupancyGrid::new(geometry, cells).unwrap();
            let (x, y) = (-0.7 + px * res, 1.3 + py * res);
            let max_range = max_cells * res;
            let got = f64::from(ray_cast_grid(&grid, x, y, angle, max_range));
            let (uy, ux) = angle.sin_cos();
            let mut want = max_range;
            for r in 0..h {
                for c in 0..w {
                    if grid.is_occupied(c, r) {
                        if let Some(t) = slab_entry(px, py, ux, uy, c as f64, r as f64) {
                            want = want.min(t * res);
                        }
                    }
                }
            }
            prop_assert!((got - want).abs() <= 1e-5 * res.max(want), "got {got}, want {want}");
        }
    }
}
