//! Differential-drive odometry from wheel-encoder ticks, integrated exactly along the arc.
//!
//! Between two readings the left and right wheels travel `d_l` and `d_r` metres
//! (`2π·r·Δticks / ticks_per_rev`, each wheel with its own radius). With the wheels' speeds
//! constant over the step, the robot drives an arc (a straight line when `d_l = d_r`, a turn on
//! the spot when `d_l = −d_r`):
//!
//! ```text
//! Δs = (d_l + d_r) / 2            path length of the wheelbase's midpoint, m
//! Δθ = (d_r − d_l) / b            heading change, rad (b: wheelbase, m)
//! chord = Δs · sin(Δθ/2) / (Δθ/2)  straight distance from start to end, m (= Δs when Δθ = 0)
//! ```
//!
//! and the chord points at `Δθ/2` from the starting heading. That is exact for any `Δθ`; the
//! straight-line approximation (drive `Δs` along `θ`, then turn) is wrong by `Δs·Δθ/2` sideways.
//! The [`OdometryStep`] returned is `δrot1 = Δθ/2`, `δtrans = |chord|`, `δrot2 = Δθ − δrot1`
//! (reversing: `δrot1 = Δθ/2 + π`, wrapped), the step [`OdometryStep::between`] gives for the
//! arc's two end poses whenever the chord is at least [`IN_PLACE_TURN_M`], computed without the
//! round trip through two f32 poses.
//!
//! Shorter steps keep `δrot1 = Δθ/2` too, where `between` (like AMCL) makes them in-place turns
//! (`δrot1 = 0`, the translation along the old heading): at 100 Hz every step of a robot at
//! 1 m/s is under 1 cm, and that rule would bring back the straight-line approximation's error.
//! The one difference in noise: a turn on the spot split in two halves gets a heading variance of
//! `odom_alpha1·Δθ²/2` instead of AMCL's `odom_alpha1·Δθ²` (the position noise is the same).
//!
//! Counters wrap: the step takes the wrapping difference of two readings of a
//! [`counter_bits`](DiffDriveGeometry::counter_bits)-wide counter (32 for `i32` / `u32`
//! counters, 16 for a timer's), so a counter that overflowed between two readings still gives the
//! right step, as long as a wheel turns less than half the counter's range between readings. A
//! step in which a wheel travels more than [`max_travel_m`](DiffDriveGeometry::max_travel_m) is
//! refused ([`MotionError::StepTooLong`]): an encoder reset, a missed reading or a corrupted
//! count, not motion.

#[cfg(doc)]
use super::motion::IN_PLACE_TURN_M;
use super::motion::{MotionError, OdometryStep};
use crate::pose::{wrap_angle, Pose};
use core::f32::consts::{PI, TAU};

/// Which [`DiffDriveGeometry`] value was refused ([`MotionError::BadDiffDrive`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DiffDriveParam {
    /// `left_radius_m` is not finite and > 0.
    LeftRadius,
    /// `right_radius_m` is not finite and > 0.
    RightRadius,
    /// `wheelbase_m` is not finite and > 0.
    Wheelbase,
    /// `ticks_per_rev` is 0.
    TicksPerRev,
    /// `counter_bits` is not in 2 to 32.
    CounterBits,
    /// `max_travel_m` is not finite and > 0, or is half the counter's range or more (a wrap
    /// could not be told from a step).
    MaxTravel,
}

impl core::fmt::Display for DiffDriveParam {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::LeftRadius => "left wheel radius must be finite and > 0",
            Self::RightRadius => "right wheel radius must be finite and > 0",
            Self::Wheelbase => "wheelbase must be finite and > 0",
            Self::TicksPerRev => "ticks per revolution must be > 0",
            Self::CounterBits => "counter width must be 2 to 32 bits",
            Self::MaxTravel => {
                "max travel per step must be finite, > 0 and under half the counter's range"
            }
        })
    }
}

/// A differential drive's geometry and encoders, validated by [`DiffDrive::new`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DiffDriveGeometry {
    /// Radius of the left wheel, metres.
    pub left_radius_m: f32,
    /// Radius of the right wheel, metres.
    pub right_radius_m: f32,
    /// Distance between the two wheels' contact points, metres.
    pub wheelbase_m: f32,
    /// Encoder ticks per wheel revolution (after any quadrature multiplication), both wheels.
    pub ticks_per_rev: u32,
    /// Width of the encoder counters, bits (2 to 32): they wrap modulo `2^counter_bits`.
    pub counter_bits: u8,
    /// Largest travel of either wheel in one step, metres; a step beyond it is refused.
    pub max_travel_m: f32,
}

impl DiffDriveGeometry {
    /// A geometry with 32-bit counters.
    pub const fn new(
        left_radius_m: f32,
        right_radius_m: f32,
        wheelbase_m: f32,
        ticks_per_rev: u32,
        max_travel_m: f32,
    ) -> Self {
        Self {
            left_radius_m,
            right_radius_m,
            wheelbase_m,
            ticks_per_rev,
            counter_bits: 32,
            max_travel_m,
        }
    }

    /// The same geometry with `bits`-wide counters.
    pub const fn with_counter_bits(self, bits: u8) -> Self {
        Self {
            counter_bits: bits,
            ..self
        }
    }

    fn validate(&self) -> Result<[f32; 2], DiffDriveParam> {
        let positive = |v: f32| v.is_finite() && v > 0.0;
        let check = |ok: bool, p: DiffDriveParam| if ok { Ok(()) } else { Err(p) };
        check(positive(self.left_radius_m), DiffDriveParam::LeftRadius)?;
        check(positive(self.right_radius_m), DiffDriveParam::RightRadius)?;
        check(positive(self.wheelbase_m), DiffDriveParam::Wheelbase)?;
        check(self.ticks_per_rev > 0, DiffDriveParam::TicksPerRev)?;
        check(
            (2..=32).contains(&self.counter_bits),
            DiffDriveParam::CounterBits,
        )?;
        let per_tick = |r: f32| TAU * r / self.ticks_per_rev as f32;
        let m = [per_tick(self.left_radius_m), per_tick(self.right_radius_m)];
        // Half the counter's range, in metres of the wheel that covers it in fewer metres.
        let half_range = (1u64 << (self.counter_bits - 1)) as f32;
        let limit = half_range * m[0].min(m[1]);
        check(
            positive(self.max_travel_m) && self.max_travel_m < limit,
            DiffDriveParam::MaxTravel,
        )?;
        Ok(m)
    }
}

/// The wheel odometry of a differential drive: encoder readings in, [`OdometryStep`]s out, and
/// the integrated odometry pose.
#[derive(Clone, Debug)]
pub struct DiffDrive {
    geometry: DiffDriveGeometry,
    /// Metres per tick, left and right.
    per_tick_m: [f32; 2],
    /// The previous reading, left and right.
    last: Option<[i32; 2]>,
    pose: Pose,
}

impl DiffDrive {
    /// Odometry for `geometry`, starting at the origin, before its first reading.
    ///
    /// # Errors
    /// [`MotionError::BadDiffDrive`] naming the first refused value.
    pub fn new(geometry: DiffDriveGeometry) -> Result<Self, MotionError> {
        let per_tick_m = geometry.validate().map_err(MotionError::BadDiffDrive)?;
        Ok(Self {
            geometry,
            per_tick_m,
            last: None,
            pose: Pose::default(),
        })
    }

    /// The geometry.
    pub fn geometry(&self) -> &DiffDriveGeometry {
        &self.geometry
    }

    /// Takes the counters' readings and returns the step since the previous ones. The first
    /// reading (and the first after [`DiffDrive::reset`]) only sets the reference and returns
    /// [`OdometryStep::STILL`]. The odometry pose ([`DiffDrive::pose`]) moves by the step.
    ///
    /// # Errors
    /// [`MotionError::StepTooLong`] when a wheel travelled more than
    /// [`max_travel_m`](DiffDriveGeometry::max_travel_m): the step is dropped, the pose kept,
    /// and these readings become the reference for the next.
    pub fn step(&mut self, left_ticks: i32, right_ticks: i32) -> Result<OdometryStep, MotionError> {
        let now = [left_ticks, right_ticks];
        let Some([l0, r0]) = self.last.replace(now) else {
            return Ok(OdometryStep::STILL);
        };
        let [ml, mr] = self.per_tick_m;
        let dl = self.ticks_between(l0, left_ticks) as f32 * ml;
        let dr = self.ticks_between(r0, right_ticks) as f32 * mr;
        let max = self.geometry.max_travel_m;
        if dl.abs() > max || dr.abs() > max {
            return Err(MotionError::StepTooLong);
        }
        let step = arc_step(dl, dr, self.geometry.wheelbase_m)?;
        self.pose = step.apply(&self.pose);
        Ok(step)
    }

    /// The odometry pose: the sum of the steps so far from the origin (metres, metres, radians
    /// in `[−π, π)`).
    pub fn pose(&self) -> Pose {
        self.pose
    }

    /// Forgets the previous reading (after the counters were reset): the next reading is a new
    /// reference. The pose is kept.
    pub fn reset(&mut self) {
        self.last = None;
    }

    /// The signed tick count from `from` to `to` on a `counter_bits`-wide wrapping counter.
    fn ticks_between(&self, from: i32, to: i32) -> i32 {
        let shift = 32 - u32::from(self.geometry.counter_bits);
        (to.wrapping_sub(from) << shift) >> shift
    }
}

/// The step of a differential drive whose left and right wheels travelled `left_m` and
/// `right_m` metres (negative backwards) on a wheelbase of `wheelbase_m` metres, along the
/// exact arc (see the module's documentation).
///
/// # Errors
/// [`MotionError::NonFiniteOdometry`] when an input is NaN or infinite, or `wheelbase_m` is not
/// > 0.
pub fn arc_step(left_m: f32, right_m: f32, wheelbase_m: f32) -> Result<OdometryStep, MotionError> {
    if !(left_m.is_finite() && right_m.is_finite() && wheelbase_m.is_finite() && wheelbase_m > 0.0)
    {
        return Err(MotionError::NonFiniteOdometry);
    }
    let ds = 0.5 * (left_m + right_m);
    let dtheta = (right_m - left_m) / wheelbase_m;
    let half = 0.5 * dtheta;
    // sin(h)/h; below 1e-3 its Taylor polynomial 1 − h²/6 (error h⁴/120 < 1e-14).
    let sinc = if half.abs() < 1e-3 {
        1.0 - half * half / 6.0
    } else {
        libm::sinf(half) / half
    };
    let chord = ds * sinc;
    let trans = chord.abs();
    let rot1 = if chord >= 0.0 {
        wrap_angle(half)
    } else {
        wrap_angle(half + PI)
    };
    OdometryStep::new(rot1, trans, wrap_angle(dtheta - rot1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 0.05 m wheels, 0.3 m wheelbase, 4096 ticks/rev, 0.5 m max per step.
    fn robot() -> DiffDriveGeometry {
        DiffDriveGeometry::new(0.05, 0.05, 0.3, 4096, 0.5)
    }

    /// f64 reference, written from the instantaneous centre of rotation: the end pose of a
    /// differential drive from `pose` after wheel travels `dl`, `dr` on wheelbase `b`.
    fn reference(pose: [f64; 3], dl: f64, dr: f64, b: f64) -> [f64; 3] {
        let [x, y, t] = pose;
        let ds = (dl + dr) / 2.0;
        let dt = (dr - dl) / b;
        if dt.abs() < 1e-12 {
            return [x + ds * t.cos(), y + ds * t.sin(), t];
        }
        let r = ds / dt; // signed radius of the midpoint's circle
        [
            x + r * ((t + dt).sin() - t.sin()),
            y - r * ((t + dt).cos() - t.cos()),
            t + dt,
        ]
    }

    fn wrap64(a: f64) -> f64 {
        let w = (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU);
        w - std::f64::consts::PI
    }

    fn close(p: &Pose, r: [f64; 3], tol_m: f64, tol_rad: f64) -> bool {
        (f64::from(p.x_m) - r[0]).abs() < tol_m
            && (f64::from(p.y_m) - r[1]).abs() < tol_m
            && wrap64(f64::from(p.theta_rad) - r[2]).abs() < tol_rad
    }

    fn per_tick(r: f64) -> f64 {
        std::f64::consts::TAU * r / 4096.0
    }

    #[test]
    fn straight_line() {
        let mut d = DiffDrive::new(robot()).unwrap();
        assert_eq!(d.step(100, 100).unwrap(), OdometryStep::STILL);
        let s = d.step(100 + 4096, 100 + 4096).unwrap();
        let want = std::f64::consts::TAU * 0.05;
        assert!((f64::from(s.trans_m()) - want).abs() < 1e-6, "{s:?}");
        assert_eq!((s.rot1_rad(), s.rot2_rad()), (0.0, 0.0));
        let back = d.step(100, 100).unwrap();
        // Reversing: δrot1 = π (wrapped), δtrans > 0, as `between` gives.
        assert!((back.rot1_rad().abs() - PI).abs() < 1e-6, "{back:?}");
        assert!(
            close(&d.pose(), [0.0, 0.0, 0.0], 1e-6, 1e-6),
            "{:?}",
            d.pose()
        );
    }

    #[test]
    fn pure_rotation() {
        let mut d = DiffDrive::new(robot()).unwrap();
        d.step(0, 0).unwrap();
        // Quarter turn on the spot: each wheel travels b·(π/2)/2.
        let ticks = (0.3 * std::f64::consts::FRAC_PI_4 / per_tick(0.05)).round() as i32;
        let s = d.step(-ticks, ticks).unwrap();
        let want = 2.0 * f64::from(ticks) * per_tick(0.05) / 0.3;
        assert_eq!(s.trans_m(), 0.0);
        assert!(
            (f64::from(s.rot1_rad() + s.rot2_rad()) - want).abs() < 1e-6,
            "{s:?}"
        );
        assert!(close(&d.pose(), [0.0, 0.0, want], 1e-7, 1e-6));
    }

    #[test]
    fn arcs_match_the_reference() {
        let b = 0.3;
        for (dl, dr) in [
            (0.10, 0.12),
            (0.2, -0.05),
            (-0.3, -0.1),
            (0.4, 0.0),
            (0.0, -0.4),
            (0.25, 0.2501),
            (0.05, 0.45),
            (-0.45, 0.45),
        ] {
            let s = arc_step(dl as f32, dr as f32, b as f32).unwrap();
            let start = Pose::new(1.0, -2.0, 2.5);
            let got = s.apply(&start);
            let want = reference([1.0, -2.0, 2.5], dl, dr, b);
            assert!(
                close(&got, want, 2e-6, 2e-6),
                "{dl} {dr}: {got:?} vs {want:?}"
            );
            // The step `between` gives for the reference's end poses (a chord of 1 cm or more;
            // shorter ones it makes in-place turns).
            if s.trans_m() < crate::mcl::IN_PLACE_TURN_M {
                continue;
            }
            let end = Pose::new(want[0] as f32, want[1] as f32, wrap64(want[2]) as f32);
            let b_step = OdometryStep::between(&start, &end).unwrap();
            assert!((b_step.trans_m() - s.trans_m()).abs() < 2e-6);
            assert!(wrap_angle(b_step.rot1_rad() - s.rot1_rad()).abs() < 1e-4);
            assert!(wrap_angle(b_step.rot2_rad() - s.rot2_rad()).abs() < 1e-4);
        }
        // The straight-line approximation would be 1.2 cm off sideways on the first of these
        // arcs over 1 m; the exact arc is not.
        let s = arc_step(0.9, 1.1, 0.3).unwrap();
        let got = s.apply(&Pose::default());
        let want = reference([0.0; 3], 0.9, 1.1, 0.3);
        assert!(close(&got, want, 1e-6, 1e-6));
    }

    #[test]
    fn many_small_steps_integrate_a_circle() {
        // 1000 steps of (3, 7) ticks (0.2 and 0.5 mm) through the counters' wrap, against the
        // reference integrated in f64.
        let mut d = DiffDrive::new(robot()).unwrap();
        let (mut l, mut r) = (i32::MAX - 1500, i32::MAX - 3000);
        d.step(l, r).unwrap();
        let mut want = [0.0f64; 3];
        for _ in 0..1000 {
            l = l.wrapping_add(3);
            r = r.wrapping_add(7);
            d.step(l, r).unwrap();
            want = reference(want, 3.0 * per_tick(0.05), 7.0 * per_tick(0.05), 0.3);
        }
        assert!(
            close(&d.pose(), want, 1e-4, 1e-4),
            "{:?} vs {want:?}",
            d.pose()
        );
    }

    #[test]
    fn wrap_around_of_32_and_16_bit_counters() {
        let mut d = DiffDrive::new(robot()).unwrap();
        d.step(i32::MAX - 9, i32::MIN + 5).unwrap();
        // Left forward 20 ticks through the wrap, right backward 10 through it.
        let s = d.step(i32::MIN + 10, i32::MAX - 4).unwrap();
        let want = reference([0.0; 3], 20.0 * per_tick(0.05), -10.0 * per_tick(0.05), 0.3);
        assert!(close(&d.pose(), want, 1e-7, 1e-6), "{s:?}");

        let g = robot().with_counter_bits(16);
        let mut d = DiffDrive::new(g).unwrap();
        d.step(65_530, 3).unwrap();
        d.step(4, 65_533).unwrap(); // +10 and −6 ticks
        let want = reference([0.0; 3], 10.0 * per_tick(0.05), -6.0 * per_tick(0.05), 0.3);
        assert!(close(&d.pose(), want, 1e-7, 1e-6));
        // A u32 counter passed as its bits is the same.
        let mut d = DiffDrive::new(robot()).unwrap();
        d.step(u32::MAX as i32, 0).unwrap();
        let s = d.step(9u32 as i32, 10).unwrap();
        assert!((f64::from(s.trans_m()) - 10.0 * per_tick(0.05)).abs() < 1e-5);
    }

    #[test]
    fn unequal_radii() {
        // Right wheel 2 % larger: equal ticks drive a left-hand arc.
        let g = DiffDriveGeometry::new(0.05, 0.051, 0.3, 4096, 0.5);
        let mut d = DiffDrive::new(g).unwrap();
        d.step(0, 0).unwrap();
        d.step(4000, 4000).unwrap();
        let dl = 4000.0 * per_tick(0.05);
        let dr = 4000.0 * std::f64::consts::TAU * 0.051 / 4096.0;
        let want = reference([0.0; 3], dl, dr, 0.3);
        assert!(want[2] > 0.02);
        assert!(
            close(&d.pose(), want, 1e-6, 1e-6),
            "{:?} vs {want:?}",
            d.pose()
        );
    }

    #[test]
    fn absurd_steps_are_refused_and_re_anchor() {
        let mut d = DiffDrive::new(robot()).unwrap();
        d.step(0, 0).unwrap();
        // 0.5 m is 6519.9 ticks: 6520 is refused.
        assert_eq!(d.step(6520, 0), Err(MotionError::StepTooLong));
        assert_eq!(d.step(6520, -7000), Err(MotionError::StepTooLong));
        assert_eq!(d.pose(), Pose::default());
        // The refused reading is the new reference.
        let s = d.step(6520 + 100, -7000 + 100).unwrap();
        assert!((f64::from(s.trans_m()) - 100.0 * per_tick(0.05)).abs() < 1e-6);
        d.reset();
        assert_eq!(d.step(1_000_000, 0).unwrap(), OdometryStep::STILL);
    }

    #[test]
    fn bad_geometry_is_typed() {
        let bad = |g: DiffDriveGeometry| match DiffDrive::new(g) {
            Err(MotionError::BadDiffDrive(p)) => Some(p),
            _ => None,
        };
        let g = robot();
        use DiffDriveParam::*;
        assert_eq!(
            bad(DiffDriveGeometry {
                left_radius_m: 0.0,
                ..g
            }),
            Some(LeftRadius)
        );
        assert_eq!(
            bad(DiffDriveGeometry {
                right_radius_m: f32::NAN,
                ..g
            }),
            Some(RightRadius)
        );
        assert_eq!(
            bad(DiffDriveGeometry {
                wheelbase_m: -0.3,
                ..g
            }),
            Some(Wheelbase)
        );
        assert_eq!(
            bad(DiffDriveGeometry {
                ticks_per_rev: 0,
                ..g
            }),
            Some(TicksPerRev)
        );
        assert_eq!(bad(g.with_counter_bits(1)), Some(CounterBits));
        assert_eq!(bad(g.with_counter_bits(33)), Some(CounterBits));
        assert_eq!(
            bad(DiffDriveGeometry {
                max_travel_m: f32::INFINITY,
                ..g
            }),
            Some(MaxTravel)
        );
        // 8-bit counters: half the range is 128 ticks, 9.8 mm of wheel.
        assert_eq!(bad(g.with_counter_bits(8)), Some(MaxTravel));
        assert_eq!(
            bad(DiffDriveGeometry {
                max_travel_m: 0.009,
                ..g.with_counter_bits(8)
            }),
            None
        );
        assert_eq!(
            arc_step(0.1, f32::NAN, 0.3),
            Err(MotionError::NonFiniteOdometry)
        );
        assert!(MotionError::BadDiffDrive(Wheelbase)
            .to_string()
            .starts_with("diff"));
    }
}
