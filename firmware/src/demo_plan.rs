//! What the demo computes, shared word for word by the firmware (`src/bin/demo.rs`) and the
//! host's reference run of it (`cargo xtask demo` recomputes every scan on the host with this
//! module and the same crate, and checks the device's report against it).
//!
//! Only `core` and `beamfield`: it compiles for the Cortex-M and the host alike.

use beamfield::{Pose, PreparedScan};

/// Tempering κ: `ln q = (1/κ)·Σ ln p` (docs/models.md#tempering) as calibrated on this log and map by
/// `beamfield calibrate` (coverage of the 95 % credible sets: 0.25 at κ = 1, 0.95 at κ = 8.25,
/// with σ_hit 5 cm; close to, not exactly, this demo's fitted σ_hit).
pub const KAPPA: f32 = 8.25;
/// σ_hit of the likelihood field, metres: the EM fit of the beam model on this log
/// (`beamfield fit --field intel.bin --log intel-corrected.log`: laser_sigma_hit 0.0588 m).
pub const SIGMA_HIT_M: f32 = 0.0588;
/// z_hit and z_rand: AMCL's defaults.
pub const Z_HIT: f32 = 0.95;
/// See [`Z_HIT`].
pub const Z_RAND: f32 = 0.05;
/// Acceptance of the demo: position error, metres.
pub const ACCEPT_M: f32 = 0.05;
/// Acceptance of the demo: heading error, degrees.
pub const ACCEPT_DEG: f32 = 1.0;

/// A grid of poses around a centre: `xy_steps` offsets per axis in x and y, `th_steps` in
/// heading, centred on 0.
#[derive(Clone, Copy)]
pub struct Grid {
    /// Poses per axis in x and y (odd).
    pub xy_steps: usize,
    /// Spacing in x and y, metres.
    pub xy_step_m: f32,
    /// Poses in heading (odd).
    pub th_steps: usize,
    /// Spacing in heading, degrees.
    pub th_step_deg: f32,
}

impl Grid {
    /// Poses in the grid.
    pub const fn len(&self) -> usize {
        self.xy_steps * self.xy_steps * self.th_steps
    }

    /// Pose `i` around `centre` (x fastest, then y, then heading).
    pub fn pose(&self, centre: &Pose, i: usize) -> Pose {
        let half_xy = (self.xy_steps / 2) as f32;
        let half_th = (self.th_steps / 2) as f32;
        let ix = (i % self.xy_steps) as f32 - half_xy;
        let iy = ((i / self.xy_steps) % self.xy_steps) as f32 - half_xy;
        let it = (i / (self.xy_steps * self.xy_steps)) as f32 - half_th;
        Pose::new(
            centre.x_m + ix * self.xy_step_m,
            centre.y_m + iy * self.xy_step_m,
            beamfield::wrap_angle(centre.theta_rad + (it * self.th_step_deg).to_radians()),
        )
    }
}

/// The hypotheses: offsets −20 … +20 cm in 2.5 cm steps in x and y, −5° … +5° in 0.5° steps.
pub const COARSE: Grid = Grid {
    xy_steps: 17,
    xy_step_m: 0.025,
    th_steps: 21,
    th_step_deg: 0.5,
};
/// The same window at 1 cm and 0.25°: only its best pose is kept.
pub const FINE: Grid = Grid {
    xy_steps: 41,
    xy_step_m: 0.01,
    th_steps: 41,
    th_step_deg: 0.25,
};
/// Pose hypotheses per scan.
pub const POSES: usize = COARSE.len();

/// Index of the best pose of the fine grid around `logged`: the first of the highest score
/// (scores are never NaN). Untempered (dividing by κ > 0 does not move the maximum), through
/// `score_with`: the demo's timed coarse loop stays the only caller of `TemperedScan::score`,
/// so the compiler inlines it there as it did without the fine search, and the instructions per
/// pose the demo reports are those of the same code.
#[inline(never)]
pub fn fine_search<const N: usize>(prepared: &PreparedScan<'_, N>, logged: &Pose) -> usize {
    let mut best = (0usize, f32::NEG_INFINITY);
    for i in 0..FINE.len() {
        let ll = prepared
            .score_with(&FINE.pose(logged, i), |_, _| {})
            .log_likelihood;
        if ll > best.1 {
            best = (i, ll);
        }
    }
    best.0
}

/// Distance (metres) and heading difference (degrees) of `p` from `logged`, and whether they
/// are within the acceptance.
pub fn offset(p: &Pose, logged: &Pose) -> (f32, f32, bool) {
    let dx = p.x_m - logged.x_m;
    let dy = p.y_m - logged.y_m;
    let d_m = beamfield::math::sqrt(dx * dx + dy * dy);
    let dth_deg = beamfield::wrap_angle(p.theta_rad - logged.theta_rad).to_degrees();
    let ok = d_m <= ACCEPT_M + 1e-4 && dth_deg.abs() <= ACCEPT_DEG + 1e-3;
    (d_m, dth_deg, ok)
}
