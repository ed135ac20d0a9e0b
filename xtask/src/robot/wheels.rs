//! A differential-drive robot driven along a logged trajectory, seen through its wheel
//! encoders: what `cargo xtask robot` sends as odometry.
//!
//! This is deliberately *not* the filter's motion model (no Gaussian noise on the odometry
//! pose): the robot's real wheels differ from the geometry the device believes
//! ([`beamfield_fixtures::robot_plan::WHEELS`]) — unequal radii, a wrong wheelbase — and every
//! wheel slips a little at every step and sometimes a lot. The encoder counts the wheel's
//! turns: `ticks = travel / (2π r_true) · ticks_per_rev · (1 + slip)`; the device turns ticks
//! back into travel with its nominal radius, so the errors are systematic (a drift in heading
//! on straight lines, a scale error in every turn) plus random.
//!
//! The trajectory's steps are driven as arcs: the forward component of each step and its
//! heading change. A sideways component (which a differential drive cannot drive) is lost, as
//! it would be on a real base.

use beamfield::Pose;
use beamfield_fixtures::robot_plan::WHEELS;
use host_tests::splitmix::{Draws, SplitMix64};
use std::f64::consts::{PI, TAU};

/// The real robot's wheels, relative to what the device believes.
#[derive(Clone, Copy, Debug)]
pub struct WheelErrors {
    /// Left wheel radius / nominal.
    pub left_radius_scale: f64,
    /// Right wheel radius / nominal.
    pub right_radius_scale: f64,
    /// Wheelbase / nominal.
    pub wheelbase_scale: f64,
    /// Standard deviation of each wheel's slip per step (fraction of its travel).
    pub slip_sigma: f64,
    /// Probability per step that one wheel slips hard.
    pub slip_event_p: f64,
    /// Fraction of its travel a wheel loses in a hard slip.
    pub slip_event_loss: f64,
}

impl WheelErrors {
    /// The errors of the README's run: the left wheel 0.3 % larger and the right 0.2 % smaller
    /// than nominal (wear, tyre pressure), the wheelbase 1 % longer (the contact points are not
    /// where the drawing says), 1 % slip per step per wheel, and one step in 500 in which a
    /// wheel loses 20 % of its travel.
    pub const TYPICAL: Self = Self {
        left_radius_scale: 1.003,
        right_radius_scale: 0.998,
        wheelbase_scale: 1.01,
        slip_sigma: 0.01,
        slip_event_p: 0.002,
        slip_event_loss: 0.2,
    };
}

/// The encoders of the simulated robot: cumulative tick counts per wheel.
pub struct Encoders {
    errors: WheelErrors,
    rng: SplitMix64,
    /// Wheel turns so far, radians, left and right.
    turned: [f64; 2],
}

impl Encoders {
    pub fn new(errors: WheelErrors, seed: u64) -> Self {
        Self {
            errors,
            rng: SplitMix64::new(seed),
            turned: [0.0; 2],
        }
    }

    /// Drives from `a` to `b` (poses of the trajectory, map frame) and returns the encoders'
    /// counts after the step.
    pub fn drive(&mut self, a: &Pose, b: &Pose) -> [i32; 2] {
        let (th0, th1) = (f64::from(a.theta_rad), f64::from(b.theta_rad));
        let dth = wrap(th1 - th0);
        let (dx, dy) = (f64::from(b.x_m - a.x_m), f64::from(b.y_m - a.y_m));
        // The chord's component along the heading halfway through the step.
        let mid = th0 + dth / 2.0;
        let chord = dx * mid.cos() + dy * mid.sin();
        let arc = if dth.abs() < 1e-9 {
            chord
        } else {
            chord * (dth / 2.0) / (dth / 2.0).sin()
        };
        let base = f64::from(WHEELS.wheelbase_m) * self.errors.wheelbase_scale;
        let travel = [arc - dth * base / 2.0, arc + dth * base / 2.0];
        let radii = [
            f64::from(WHEELS.left_radius_m) * self.errors.left_radius_scale,
            f64::from(WHEELS.right_radius_m) * self.errors.right_radius_scale,
        ];
        let hard =
            (self.rng.uniform() < self.errors.slip_event_p).then(|| self.rng.uniform() < 0.5);
        for w in 0..2 {
            let mut slip = self.errors.slip_sigma * self.rng.normal();
            if hard == Some(w == 0) {
                slip -= self.errors.slip_event_loss;
            }
            self.turned[w] += travel[w] / radii[w] * (1.0 + slip);
        }
        self.ticks()
    }

    /// The counts now.
    pub fn ticks(&self) -> [i32; 2] {
        let per_turn = f64::from(WHEELS.ticks_per_rev);
        self.turned
            .map(|t| (t / TAU * per_turn).floor() as i64 as i32)
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_perfect_robot_counts_what_the_device_expects() {
        let perfect = WheelErrors {
            left_radius_scale: 1.0,
            right_radius_scale: 1.0,
            wheelbase_scale: 1.0,
            slip_sigma: 0.0,
            slip_event_p: 0.0,
            slip_event_loss: 0.0,
        };
        let mut e = Encoders::new(perfect, 1);
        // One metre straight: 1 / (2π · 0.033) turns of 4,096 ticks.
        let t = e.drive(&Pose::new(0.0, 0.0, 0.0), &Pose::new(1.0, 0.0, 0.0));
        let want = (1.0 / (TAU * 0.033) * 4096.0).floor() as i32;
        assert!(
            (t[0] - want).abs() <= 1 && (t[1] - want).abs() <= 1,
            "{t:?} vs {want}"
        );
        // A quarter turn on the spot: the wheels go opposite ways by b·π/4.
        let mut e = Encoders::new(perfect, 1);
        let t = e.drive(&Pose::new(0.0, 0.0, 0.0), &Pose::new(0.0, 0.0, 1.5707964));
        let want = (0.16 * PI / 4.0 / (TAU * 0.033) * 4096.0) as i32;
        assert!(
            (t[1] - want).abs() <= 2 && (t[0] + want).abs() <= 2,
            "{t:?} vs ±{want}"
        );
    }

    #[test]
    fn unequal_radii_bend_a_straight_line() {
        let mut e = Encoders::new(
            WheelErrors {
                slip_sigma: 0.0,
                slip_event_p: 0.0,
                ..WheelErrors::TYPICAL
            },
            1,
        );
        let t = e.drive(&Pose::new(0.0, 0.0, 0.0), &Pose::new(1.0, 0.0, 0.0));
        // The right wheel is smaller: it turns more for the same travel.
        assert!(t[1] > t[0]);
    }
}
