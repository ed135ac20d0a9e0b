//! Local pose grids around a known pose, scored with any [`SensorModel`]: the common ground of
//! `beamfield score --grid`, `beamfield calibrate` and the Intel localization test.
//!
//! A grid is `nx × ny × nθ` poses centred on a given pose (the centre is always a grid point,
//! so the truth is one cell, as [`crate::calibrate`] needs). Cells are ordered θ-major, then y,
//! then x: index `(it·ny + iy)·nx + ix`.

use crate::calibrate::GridScores;
use beamfield::{BeamLayout, Pose, Scan, SensorModel};

/// Half-widths and steps of a local pose grid.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct GridSpec {
    /// Half-width in x and in y, metres.
    pub half_xy_m: f64,
    /// Step in x and y, metres (> 0).
    pub step_xy_m: f64,
    /// Half-width in θ, radians.
    pub half_theta_rad: f64,
    /// Step in θ, radians (> 0).
    pub step_theta_rad: f64,
}

impl GridSpec {
    /// Cells on each side of the centre along x/y (rounded to the nearest whole step).
    pub fn half_cells_xy(&self) -> usize {
        half_cells(self.half_xy_m, self.step_xy_m)
    }

    /// Cells on each side of the centre along θ.
    pub fn half_cells_theta(&self) -> usize {
        half_cells(self.half_theta_rad, self.step_theta_rad)
    }

    /// `(nx, ny, nθ)`.
    pub fn dims(&self) -> (usize, usize, usize) {
        let n = 2 * self.half_cells_xy() + 1;
        (n, n, 2 * self.half_cells_theta() + 1)
    }

    /// Total number of poses.
    pub fn len(&self) -> usize {
        let (a, b, c) = self.dims();
        a * b * c
    }

    /// Never empty (the centre is always a cell).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Index of the centre cell.
    pub fn center_index(&self) -> usize {
        let (nx, ny, _) = self.dims();
        (self.half_cells_theta() * ny + self.half_cells_xy()) * nx + self.half_cells_xy()
    }

    /// Offsets `(dx_m, dy_m, dθ_rad)` of cell `index` from the centre.
    pub fn offset(&self, index: usize) -> (f64, f64, f64) {
        let (nx, ny, _) = self.dims();
        let (ix, iy, it) = (index % nx, (index / nx) % ny, index / (nx * ny));
        let (hx, ht) = (self.half_cells_xy() as f64, self.half_cells_theta() as f64);
        (
            (ix as f64 - hx) * self.step_xy_m,
            (iy as f64 - hx) * self.step_xy_m,
            (it as f64 - ht) * self.step_theta_rad,
        )
    }

    /// The pose of cell `index` around `center`.
    pub fn pose(&self, center: &Pose, index: usize) -> Pose {
        let (dx, dy, dt) = self.offset(index);
        Pose::new(
            (f64::from(center.x_m) + dx) as f32,
            (f64::from(center.y_m) + dy) as f32,
            (f64::from(center.theta_rad) + dt) as f32,
        )
    }
}

fn half_cells(half: f64, step: f64) -> usize {
    if step > 0.0 && half.is_finite() && half > 0.0 {
        (half / step).round() as usize
    } else {
        0
    }
}

/// Scores `scan` at every pose of `spec` around `center` with `model`; the truth is the centre.
pub fn score_grid<M: SensorModel<N>, const N: usize>(
    model: &M,
    layout: &BeamLayout<N>,
    scan: &Scan<N>,
    center: &Pose,
    spec: &GridSpec,
) -> GridScores {
    let log_likelihood = (0..spec.len())
        .map(|i| {
            let p = spec.pose(center, i);
            f64::from(model.score(layout, scan, &p).log_likelihood)
        })
        .collect();
    GridScores {
        log_likelihood,
        truth: spec.center_index(),
    }
}

/// Index of the largest score (the first one on ties), or `None` for an empty slice.
pub fn argmax(scores: &[f64]) -> Option<usize> {
    scores
        .iter()
        .enumerate()
        .fold(None, |best: Option<(usize, f64)>, (i, &l)| match best {
            Some((_, b)) if b >= l => best,
            _ => Some((i, l)),
        })
        .map(|b| b.0)
}

/// Posterior standard deviations `(sd_x_m, sd_y_m, sd_θ_rad)` of the grid's marginals at
/// tempering `kappa`, flat prior over the grid.
pub fn posterior_sd(g: &GridScores, spec: &GridSpec, kappa: f64) -> (f64, f64, f64) {
    let max = g
        .log_likelihood
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let mut total = 0.0;
    let mut m = [0.0f64; 3];
    let mut m2 = [0.0f64; 3];
    for (i, &l) in g.log_likelihood.iter().enumerate() {
        let w = ((l - max) / kappa).exp();
        let (dx, dy, dt) = spec.offset(i);
        total += w;
        for (k, v) in [dx, dy, dt].into_iter().enumerate() {
            m[k] += w * v;
            m2[k] += w * v * v;
        }
    }
    let sd = |k: usize| (m2[k] / total - (m[k] / total).powi(2)).max(0.0).sqrt();
    (sd(0), sd(1), sd(2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_indexing_round_trips() {
        let s = GridSpec {
            half_xy_m: 0.1,
            step_xy_m: 0.05,
            half_theta_rad: 0.02,
            step_theta_rad: 0.01,
        };
        assert_eq!(s.dims(), (5, 5, 5));
        assert_eq!(s.offset(s.center_index()), (0.0, 0.0, 0.0));
        let (dx, dy, dt) = s.offset(0);
        assert!((dx + 0.1).abs() < 1e-12 && (dy + 0.1).abs() < 1e-12 && (dt + 0.02).abs() < 1e-12);
        let (dx, dy, dt) = s.offset(s.len() - 1);
        assert!((dx - 0.1).abs() < 1e-12 && (dy - 0.1).abs() < 1e-12 && (dt - 0.02).abs() < 1e-12);
        // x varies fastest.
        assert!((s.offset(1).0 + 0.05).abs() < 1e-12);
        assert_eq!(argmax(&[1.0, 3.0, 3.0, -1.0]), Some(1));
        assert_eq!(argmax(&[]), None);
    }
}
