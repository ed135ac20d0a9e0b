//! Wheel odometry that is not the filter's motion model: a differential-drive base driven along
//! a logged trajectory, whose real wheels differ from the geometry its odometry believes
//! (unequal radii, a wrong wheelbase) and slip at every step, sometimes hard. There is no
//! Gaussian noise on the odometry pose, so the errors are systematic (a drift in heading on
//! straight lines, a scale error in every turn) plus the slip.
//!
//! It lives in the tools so that `beamfield track --wheel-odometry` can feed it to the filter;
//! the host tests and `cargo xtask robot` use it as `host_tests::wheel_odometry`.
//!
//! Two views of the same wheels:
//! - [`Encoders`]: the counters of the wheels' encoders, what a base controller reads (`cargo
//!   xtask robot` sends them to the device, which turns ticks back into travel with the
//!   believed radii);
//! - [`wheel_odometry`]: the believed travel integrated into poses (exact arcs, f64), one per
//!   logged pose (the host's tracking runs).
//!
//! Each step of the trajectory is driven as an arc ([`arc_travel`]): its forward component and
//! its heading change. A sideways component, which a differential drive cannot drive, is lost,
//! as on a real base.

use super::draws::Draws;
use beamfield::mcl::SplitMix64;
use beamfield::Pose;
use std::f64::consts::{PI, TAU};

/// The wheelbase a Pioneer-like base's odometry believes, metres ([`wheel_odometry`]; only the
/// ratios of the real to the believed values and the slip matter there).
pub const NOMINAL_WHEELBASE_M: f64 = 0.33;

/// A wheel losing part of its travel at once (a bump, a wet patch).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HardSlip {
    /// Probability per step that one of the wheels (either, equally likely) slips hard.
    pub p: f64,
    /// The fraction of its travel that wheel loses.
    pub loss: f64,
}

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
    /// Hard slips, if any.
    pub hard_slip: Option<HardSlip>,
}

impl WheelErrors {
    /// Radii +0.6 % / −0.4 %, wheelbase +1.5 %, slip σ 1.5 % of each wheel's travel.
    pub const MILD: Self = Self {
        left_radius_scale: 1.006,
        right_radius_scale: 0.996,
        wheelbase_scale: 1.015,
        slip_sigma: 0.015,
        hard_slip: None,
    };

    /// Every error of [`WheelErrors::MILD`] twice as large.
    pub const STRONG: Self = Self {
        left_radius_scale: 1.012,
        right_radius_scale: 0.992,
        wheelbase_scale: 1.03,
        slip_sigma: 0.03,
        hard_slip: None,
    };

    /// The errors of `cargo xtask robot`: the left wheel 0.3 % larger and the right 0.2 %
    /// smaller than believed (wear, tyre pressure), the wheelbase 1 % longer (the contact
    /// points are not where the drawing says), 1 % slip per step per wheel, and one step in 500
    /// in which a wheel loses 20 % of its travel.
    pub const TYPICAL: Self = Self {
        left_radius_scale: 1.003,
        right_radius_scale: 0.998,
        wheelbase_scale: 1.01,
        slip_sigma: 0.01,
        hard_slip: Some(HardSlip {
            p: 0.002,
            loss: 0.2,
        }),
    };

    /// Each wheel's slip for one step, as a fraction of its travel (left, right).
    fn slips(&self, rng: &mut SplitMix64) -> [f64; 2] {
        let hard = self
            .hard_slip
            .and_then(|h| (rng.uniform() < h.p).then(|| (rng.uniform() < 0.5, h.loss)));
        let mut out = [0.0; 2];
        for (w, s) in out.iter_mut().enumerate() {
            *s = self.slip_sigma * rng.normal();
            if let Some((left, loss)) = hard {
                if left == (w == 0) {
                    *s -= loss;
                }
            }
        }
        out
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

/// What the wheels of a base with this `wheelbase_m` travel (left, right; metres) to drive the
/// step from `a` to `b` as an arc: the chord's component along the heading halfway through the
/// step, lengthened to the arc, and the heading change.
pub fn arc_travel(a: &Pose, b: &Pose, wheelbase_m: f64) -> [f64; 2] {
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
    [arc - dth * wheelbase_m / 2.0, arc + dth * wheelbase_m / 2.0]
}

/// The geometry the base controller believes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    /// Left wheel radius, metres.
    pub left_radius_m: f64,
    /// Right wheel radius, metres.
    pub right_radius_m: f64,
    /// Distance between the wheels' contact points, metres.
    pub wheelbase_m: f64,
    /// Encoder ticks per wheel revolution.
    pub ticks_per_rev: u32,
}

/// The encoders of a simulated base: cumulative tick counts per wheel.
pub struct Encoders {
    geometry: Geometry,
    errors: WheelErrors,
    rng: SplitMix64,
    /// Wheel turns so far, radians, left and right.
    turned: [f64; 2],
}

impl Encoders {
    /// Encoders at zero on a base the controller believes has `geometry`, whose real wheels
    /// differ by `errors`; the slip drawn from `seed`.
    pub fn new(geometry: Geometry, errors: WheelErrors, seed: u64) -> Self {
        Self {
            geometry,
            errors,
            rng: SplitMix64::new(seed),
            turned: [0.0; 2],
        }
    }

    /// Drives from `a` to `b` (poses of the trajectory) and returns the counts after the step:
    /// `ticks = travel / (2π r_real) · ticks_per_rev · (1 + slip)`.
    pub fn drive(&mut self, a: &Pose, b: &Pose) -> [i32; 2] {
        let g = &self.geometry;
        let travel = arc_travel(a, b, g.wheelbase_m * self.errors.wheelbase_scale);
        let radii = [
            g.left_radius_m * self.errors.left_radius_scale,
            g.right_radius_m * self.errors.right_radius_scale,
        ];
        let slips = self.errors.slips(&mut self.rng);
        for w in 0..2 {
            self.turned[w] += travel[w] / radii[w] * (1.0 + slips[w]);
        }
        self.ticks()
    }

    /// The counts now.
    pub fn ticks(&self) -> [i32; 2] {
        let per_turn = f64::from(self.geometry.ticks_per_rev);
        self.turned
            .map(|t| (t / TAU * per_turn).floor() as i64 as i32)
    }
}

/// The odometry of a run along `logged` (seeded): the first pose is the first logged one,
/// then each step's believed wheel travel integrated, with the believed wheelbase
/// [`NOMINAL_WHEELBASE_M`].
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
        // What the real wheels travel for this motion, and what the odometry believes they
        // travelled: turns of the real wheel times the believed radius, with slip.
        let travel = arc_travel(&w[0], &w[1], NOMINAL_WHEELBASE_M * errors.wheelbase_scale);
        let scales = [errors.left_radius_scale, errors.right_radius_scale];
        let slips = errors.slips(&mut rng);
        let seen = [0, 1].map(|k| travel[k] / scales[k] * (1.0 + slips[k]));
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

    const PERFECT: WheelErrors = WheelErrors {
        left_radius_scale: 1.0,
        right_radius_scale: 1.0,
        wheelbase_scale: 1.0,
        slip_sigma: 0.0,
        hard_slip: None,
    };

    const BASE: Geometry = Geometry {
        left_radius_m: 0.033,
        right_radius_m: 0.033,
        wheelbase_m: 0.16,
        ticks_per_rev: 4096,
    };

    #[test]
    fn perfect_wheels_reproduce_the_trajectory() {
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
        let odom = wheel_odometry(&path, &PERFECT, 1);
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

    #[test]
    fn a_perfect_robot_counts_what_the_controller_expects() {
        let mut e = Encoders::new(BASE, PERFECT, 1);
        // One metre straight: 1 / (2π · 0.033) turns of 4,096 ticks.
        let t = e.drive(&Pose::new(0.0, 0.0, 0.0), &Pose::new(1.0, 0.0, 0.0));
        let want = (1.0 / (TAU * 0.033) * 4096.0).floor() as i32;
        assert!(
            (t[0] - want).abs() <= 1 && (t[1] - want).abs() <= 1,
            "{t:?} vs {want}"
        );
        // A quarter turn on the spot: the wheels go opposite ways by b·π/4.
        let mut e = Encoders::new(BASE, PERFECT, 1);
        let t = e.drive(&Pose::new(0.0, 0.0, 0.0), &Pose::new(0.0, 0.0, 1.5707964));
        let want = (0.16 * PI / 4.0 / (TAU * 0.033) * 4096.0) as i32;
        assert!(
            (t[1] - want).abs() <= 2 && (t[0] + want).abs() <= 2,
            "{t:?} vs ±{want}"
        );
    }

    #[test]
    fn unequal_radii_bend_a_straight_line_of_ticks() {
        let errors = WheelErrors {
            slip_sigma: 0.0,
            hard_slip: None,
            ..WheelErrors::TYPICAL
        };
        let mut e = Encoders::new(BASE, errors, 1);
        let t = e.drive(&Pose::new(0.0, 0.0, 0.0), &Pose::new(1.0, 0.0, 0.0));
        // The right wheel is smaller: it turns more for the same travel.
        assert!(t[1] > t[0]);
    }
}
