//! Wheel odometry that is not the filter's motion model: a differential-drive base driven along
//! a logged trajectory, whose real wheels differ from the geometry its odometry believes
//! (unequal radii, a wrong wheelbase) and slip at every step. The odometry integrates the
//! wheels' believed travel into poses (exact arcs, f64), one per logged pose.
//!
//! The believed geometry is a Pioneer-like base ([`NOMINAL_WHEELBASE_M`]); only the ratios of
//! the real to the believed values and the slip matter. Each step of the trajectory is driven
//! as an arc: its forward component and its heading change; a sideways component (which a
//! differential drive cannot drive) is lost, as on a real base.

use crate::splitmix::{Draws, SplitMix64};
use beamfield::Pose;
use std::f64::consts::{PI, TAU};

/// The wheelbase the odometry believes, metres.
pub const NOMINAL_WHEELBASE_M: f64 = 0.33;

/// The real wheels relative to the believed ones.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WheelErrors {
    /// Left wheel radius / believed.
    pub left_radius_scale: f64,
    /// Right wheel radius / believed.
    pub right_radius_scale: f64,
    /// Wheelbase / believed.
    pub wheelbase_scale: f64,
    /// Standard deviation of each wheel's slip per step, as a fraction of its travel.
    pub slip_sigma: f64,
}

impl WheelErrors {
    /// Radii +0.6 % / −0.4 %, wheelbase +1.5 %, slip σ 1.5 % of each wheel's travel.
    pub const MILD: Self = Self {
        left_radius_scale: 1.006,
        right_radius_scale: 0.996,
        wheelbase_scale: 1.015,
        slip_sigma: 0.015,
    };

    /// Every error of [`WheelErrors::MILD`] twice as large.
    pub const STRONG: Self = Self {
        left_radius_scale: 1.012,
        right_radius_scale: 0.992,
        wheelbase_scale: 1.03,
        slip_sigma: 0.03,
    };
}

fn wrap(a: f64) -> f64 {
    let mut a = a % TAU;
    if a >= PI {
        a -= TAU;
    } else if a < -PI {
        a += TAU;
    }
    a
}

/// The odometry of a run along `logged` (seeded): the first pose is the first logged one,
/// then each step's believed wheel travel integrated.
pub fn wheel_odometry(logged: &[Pose], errors: &WheelErrors, seed: u64) -> Vec<Pose> {
    let mut rng = SplitMix64::new(seed);
    let mut out = Vec::with_capacity(logged.len());
    let Some(first) = logged.first() else {
        return out;
    };
    let (mut x, mut y, mut th) = (
        f64::from(first.x_m),
        f64::from(first.y_m),
        f64::from(first.theta_rad),
    );
    out.push(*first);
    for w in logged.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        let (th0, th1) = (f64::from(a.theta_rad), f64::from(b.theta_rad));
        let dth = wrap(th1 - th0);
        let (dx, dy) = (f64::from(b.x_m - a.x_m), f64::from(b.y_m - a.y_m));
        let mid = th0 + dth / 2.0;
        let chord = dx * mid.cos() + dy * mid.sin();
        let arc = if dth.abs() < 1e-9 {
            chord
        } else {
            chord * (dth / 2.0) / (dth / 2.0).sin()
        };
        // What the real wheels travel for this motion …
        let real_base = NOMINAL_WHEELBASE_M * errors.wheelbase_scale;
        let travel = [arc - dth * real_base / 2.0, arc + dth * real_base / 2.0];
        let scales = [errors.left_radius_scale, errors.right_radius_scale];
        // … and what the odometry believes they travelled: turns of the real wheel times the
        // believed radius, with slip.
        let mut seen = [0.0f64; 2];
        for k in 0..2 {
            let slip = errors.slip_sigma * rng.normal();
            seen[k] = travel[k] / scales[k] * (1.0 + slip);
        }
        let s = 0.5 * (seen[0] + seen[1]);
        let turn = (seen[1] - seen[0]) / NOMINAL_WHEELBASE_M;
        let h = th + turn / 2.0;
        let chord = if turn.abs() < 1e-9 {
            s
        } else {
            s * (turn / 2.0).sin() / (turn / 2.0)
        };
        x += chord * h.cos();
        y += chord * h.sin();
        th = wrap(th + turn);
        out.push(Pose::new(x as f32, y as f32, th as f32));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perfect_wheels_reproduce_the_trajectory() {
        let perfect = WheelErrors {
            left_radius_scale: 1.0,
            right_radius_scale: 1.0,
            wheelbase_scale: 1.0,
            slip_sigma: 0.0,
        };
        let path: Vec<Pose> = (0..50)
            .map(|k| {
                let t = k as f32 * 0.1;
                Pose::new(
                    2.0 * t.cos(),
                    2.0 * t.sin(),
                    t + std::f32::consts::FRAC_PI_2,
                )
            })
            .collect();
        let odom = wheel_odometry(&path, &perfect, 1);
        let last = (path.last().unwrap(), odom.last().unwrap());
        assert!((last.0.x_m - last.1.x_m).abs() < 1e-3, "{last:?}");
        assert!((last.0.y_m - last.1.y_m).abs() < 1e-3, "{last:?}");
        // Unequal radii bend a straight line.
        let line: Vec<Pose> = (0..20)
            .map(|k| Pose::new(k as f32 * 0.1, 0.0, 0.0))
            .collect();
        let bent = wheel_odometry(
            &line,
            &WheelErrors {
                slip_sigma: 0.0,
                ..WheelErrors::MILD
            },
            1,
        );
        assert!(bent.last().unwrap().theta_rad.abs() > 1e-3);
    }
}
