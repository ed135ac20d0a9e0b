//! The odometry motion model, sampled: Thrun Table 5.6 (`sample_motion_model_odometry`), in
//! AMCL's convention for the noise parameters.
//!
//! Two odometry poses `x̄ = (x̄, ȳ, θ̄)` and `x̄' = (x̄', ȳ', θ̄')`, read from the wheel encoders in
//! the odometry frame, are turned into a rotation, a translation and a second rotation
//! (Thrun eq. 5.34–5.36):
//!
//! ```text
//! δtrans = √((x̄' − x̄)² + (ȳ' − ȳ)²)
//! δrot1  = atan2(ȳ' − ȳ, x̄' − x̄) − θ̄        (0 when δtrans < 1 cm: an in-place turn)
//! δrot2  = θ̄' − θ̄ − δrot1
//! ```
//!
//! and each is perturbed by a zero-mean normal whose **variance** is (AMCL's `odom_alpha1..4`;
//! the book writes the same terms with α as standard-deviation coefficients in Table 5.6 and as
//! variances in Table 5.5):
//!
//! ```text
//! var δrot1  = odom_alpha1·δrot1² + odom_alpha2·δtrans²
//! var δtrans = odom_alpha3·δtrans² + odom_alpha4·(δrot1² + δrot2²)
//! var δrot2  = odom_alpha1·δrot2² + odom_alpha2·δtrans²
//! ```
//!
//! Backward motion: the rotation terms of the variances use the smaller of `|δrot|` and
//! `|δrot − π|` (both wrapped), so a robot reversing 1 m does not get the noise of a half turn
//! (AMCL does the same). Units: metres and radians throughout.

use super::normal::standard_normal_from;
use crate::math;
use crate::math::fast::{sin_cos_near, wrap_once};
use crate::pose::{wrap_angle, Pose};
use core::f32::consts::PI;
use rand_core::Rng;

/// Translations below this (metres) are in-place turns: `δrot1 = 0`, the whole turn is `δrot2`.
pub const IN_PLACE_TURN_M: f32 = 0.01;

/// The longest odometry step the motion model takes, metres (`|δtrans|`, forward or reversing):
/// 1 km. The f32 spacing there is 61 µm, so a step this long still carries its own noise, and
/// with every `odom_alpha` at most [`MAX_ALPHA`] each sampled variance stays below 10¹³ and the
/// moved particles finite. A longer step (an encoder reset, a corrupted message, a unit error)
/// is [`MotionError::StepTooLarge`].
pub const MAX_STEP_M: f32 = 1_000.0;

/// The largest rotation of an odometry step the motion model takes, radians (`|δrot1|`,
/// `|δrot2|`): 1,000 rad (about 159 turns; f32 spacing 61 µrad). [`OdometryStep::between`]
/// wraps both rotations into `[−π, π)`; only [`OdometryStep::new`] can be given more.
pub const MAX_STEP_ROTATION_RAD: f32 = 1_000.0;

/// The largest `odom_alpha` coefficient [`OdometryNoise::new`] accepts: 10⁶ (a standard
/// deviation a thousand times the motion; AMCL's defaults are 0.2). Larger ones overflow the
/// variances of long steps.
pub const MAX_ALPHA: f32 = 1.0e6;

/// Errors building an odometry noise model or step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum MotionError {
    /// A noise coefficient is NaN, infinite, negative or above [`MAX_ALPHA`] (its index, 1 to
    /// 4).
    BadAlpha(u8),
    /// An odometry pose or step has a NaN or infinite coordinate.
    NonFiniteOdometry,
    /// A differential drive's geometry was refused ([`super::odometry::DiffDrive::new`]).
    BadDiffDrive(super::odometry::DiffDriveParam),
    /// A wheel travelled more than the differential drive's maximum in one step
    /// ([`super::odometry::DiffDrive::step`]).
    StepTooLong,
    /// An odometry step's translation is beyond [`MAX_STEP_M`] or a rotation beyond
    /// [`MAX_STEP_ROTATION_RAD`]: more than the motion model can represent.
    StepTooLarge,
}

impl core::fmt::Display for MotionError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BadAlpha(i) => write!(f, "odom_alpha{i} must be finite and >= 0"),
            Self::NonFiniteOdometry => f.write_str("odometry is not finite"),
            Self::BadDiffDrive(p) => write!(f, "differential drive: {p}"),
            Self::StepTooLong => f.write_str("wheel travel over the maximum per step"),
            Self::StepTooLarge => f.write_str("odometry step beyond the motion model's range"),
        }
    }
}

impl core::error::Error for MotionError {}

/// The four variance coefficients of the odometry model (AMCL's `odom_alpha1..4`),
/// dimensionless (rad²/rad², rad²/m², m²/m², m²/rad²).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OdometryNoise {
    alpha: [f32; 4],
}

impl OdometryNoise {
    /// `odom_alpha1` (rotation from rotation), `odom_alpha2` (rotation from translation),
    /// `odom_alpha3` (translation from translation), `odom_alpha4` (translation from rotation).
    ///
    /// # Errors
    /// [`MotionError::BadAlpha`] for a NaN, negative or infinite coefficient, or one above
    /// [`MAX_ALPHA`].
    pub fn new(alpha1: f32, alpha2: f32, alpha3: f32, alpha4: f32) -> Result<Self, MotionError> {
        let alpha = [alpha1, alpha2, alpha3, alpha4];
        for (i, a) in (1u8..).zip(alpha) {
            if !(0.0..=MAX_ALPHA).contains(&a) {
                return Err(MotionError::BadAlpha(i));
            }
        }
        Ok(Self { alpha })
    }

    /// The same coefficient for all four terms.
    ///
    /// # Errors
    /// As [`OdometryNoise::new`].
    pub fn uniform(alpha: f32) -> Result<Self, MotionError> {
        Self::new(alpha, alpha, alpha, alpha)
    }

    /// `[odom_alpha1, odom_alpha2, odom_alpha3, odom_alpha4]`.
    pub fn alphas(&self) -> [f32; 4] {
        self.alpha
    }

    /// The standard deviations `(σ δrot1, σ δtrans, σ δrot2)` (radians, metres, radians) of the
    /// noise added to `step`.
    pub fn sigmas(&self, step: &OdometryStep) -> (f32, f32, f32) {
        let [a1, a2, a3, a4] = self.alpha;
        let r1 = backward_aware(step.rot1_rad);
        let r2 = backward_aware(step.rot2_rad);
        let t2 = step.trans_m * step.trans_m;
        (
            math::sqrt(a1 * r1 * r1 + a2 * t2),
            math::sqrt(a3 * t2 + a4 * (r1 * r1 + r2 * r2)),
            math::sqrt(a1 * r2 * r2 + a2 * t2),
        )
    }

    /// Draws the robot's new pose from `p(x' | step, x)` (Thrun Table 5.6).
    ///
    /// # Random numbers
    /// Three standard normals by the ziggurat ([`super::normal`]): the noise of δrot1 and
    /// δtrans start from the low and high halves of one `next_u64`, that of δrot2 from one
    /// `next_u32`, all three drawn first; about one normal in 80 then needs further words
    /// (the ziggurat's slow path), in that order. The
    /// returned heading is wrapped into `[−π, π)`.
    pub fn sample<R: Rng + ?Sized>(&self, pose: &Pose, step: &OdometryStep, rng: &mut R) -> Pose {
        sample_with(pose, step, self.sigmas(step), rng)
    }
}

/// [`OdometryNoise::sample`] with the standard deviations already computed
/// ([`OdometryNoise::sigmas`]): they depend on the step only, so a filter computes them once
/// per step, not once per particle. Same draws, same result.
pub fn sample_with<R: Rng + ?Sized>(
    pose: &Pose,
    step: &OdometryStep,
    sigmas: (f32, f32, f32),
    rng: &mut R,
) -> Pose {
    let pair = rng.next_u64();
    let third = rng.next_u32();
    sample_words(
        pose,
        step,
        sigmas,
        [pair as u32, (pair >> 32) as u32, third],
        rng,
    )
}

/// The motion sample whose three normals (the noise of δrot1, δtrans, δrot2) start from
/// `words` ([`standard_normal_from`]); their rare slow paths draw more from `rng`.
#[inline]
pub(super) fn sample_words<R: Rng + ?Sized>(
    pose: &Pose,
    step: &OdometryStep,
    (s_rot1, s_trans, s_rot2): (f32, f32, f32),
    [w1, w2, w3]: [u32; 3],
    rng: &mut R,
) -> Pose {
    let n1 = standard_normal_from(w1, rng);
    let n2 = standard_normal_from(w2, rng);
    let n3 = standard_normal_from(w3, rng);
    let rot1 = step.rot1_rad - s_rot1 * n1;
    let trans = step.trans_m - s_trans * n2;
    let rot2 = step.rot2_rad - s_rot2 * n3;
    let (s, c) = sin_cos_near(pose.theta_rad + rot1);
    Pose {
        x_m: pose.x_m + trans * c,
        y_m: pose.y_m + trans * s,
        theta_rad: wrap_once(pose.theta_rad + rot1 + rot2),
    }
}

/// `min(|δ|, |wrap(δ − π)|)`... the smaller of the angle and its complement to a half turn, both
/// wrapped: the rotation a reversing robot really made.
fn backward_aware(rot_rad: f32) -> f32 {
    let a = wrap_angle(rot_rad).abs();
    let b = wrap_angle(rot_rad - PI).abs();
    a.min(b)
}

/// One odometry increment as Thrun's `(δrot1, δtrans, δrot2)`: radians, metres, radians.
/// Always finite.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OdometryStep {
    rot1_rad: f32,
    trans_m: f32,
    rot2_rad: f32,
}

impl OdometryStep {
    /// No motion.
    pub const STILL: Self = Self {
        rot1_rad: 0.0,
        trans_m: 0.0,
        rot2_rad: 0.0,
    };

    /// The step between two odometry readings (Thrun eq. 5.34–5.36; steps under
    /// [`IN_PLACE_TURN_M`] are in-place turns). Both rotations are wrapped into `[−π, π)`.
    ///
    /// # Errors
    /// [`MotionError::NonFiniteOdometry`] when a coordinate of either pose is NaN or infinite,
    /// or the step itself overflows; [`MotionError::StepTooLarge`] when the poses are more than
    /// [`MAX_STEP_M`] apart.
    pub fn between(previous: &Pose, current: &Pose) -> Result<Self, MotionError> {
        if !(previous.is_finite() && current.is_finite()) {
            return Err(MotionError::NonFiniteOdometry);
        }
        let dx = current.x_m - previous.x_m;
        let dy = current.y_m - previous.y_m;
        let trans_m = math::sqrt(dx * dx + dy * dy);
        let turn = current.theta_rad - previous.theta_rad;
        let rot1_rad = if trans_m < IN_PLACE_TURN_M {
            0.0
        } else {
            wrap_angle(math::atan2(dy, dx) - previous.theta_rad)
        };
        let rot2_rad = wrap_angle(turn - rot1_rad);
        Self::new(rot1_rad, trans_m, rot2_rad)
    }

    /// A step from its three parts. A negative `trans_m` is a reversing step.
    ///
    /// # Errors
    /// [`MotionError::NonFiniteOdometry`] for a NaN or infinite part;
    /// [`MotionError::StepTooLarge`] for `|trans_m|` above [`MAX_STEP_M`] or a rotation above
    /// [`MAX_STEP_ROTATION_RAD`] in magnitude.
    pub fn new(rot1_rad: f32, trans_m: f32, rot2_rad: f32) -> Result<Self, MotionError> {
        if !(rot1_rad.is_finite() && trans_m.is_finite() && rot2_rad.is_finite()) {
            return Err(MotionError::NonFiniteOdometry);
        }
        if trans_m.abs() > MAX_STEP_M
            || rot1_rad.abs() > MAX_STEP_ROTATION_RAD
            || rot2_rad.abs() > MAX_STEP_ROTATION_RAD
        {
            return Err(MotionError::StepTooLarge);
        }
        Ok(Self {
            rot1_rad,
            trans_m,
            rot2_rad,
        })
    }

    /// δrot1, radians.
    pub fn rot1_rad(&self) -> f32 {
        self.rot1_rad
    }

    /// δtrans, metres.
    pub fn trans_m(&self) -> f32 {
        self.trans_m
    }

    /// δrot2, radians.
    pub fn rot2_rad(&self) -> f32 {
        self.rot2_rad
    }

    /// The pose reached from `pose` by this step without noise.
    pub fn apply(&self, pose: &Pose) -> Pose {
        let (s, c) = math::sin_cos(pose.theta_rad + self.rot1_rad);
        Pose {
            x_m: pose.x_m + self.trans_m * c,
            y_m: pose.y_m + self.trans_m * s,
            theta_rad: wrap_angle(pose.theta_rad + self.rot1_rad + self.rot2_rad),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mcl::SplitMix64 as SplitMix;

    #[test]
    fn step_round_trips_through_apply() {
        // Hand-derived: from (1, 2, 0) to (2, 3, π/2): δtrans = √2, δrot1 = π/4, δrot2 = π/4.
        let a = Pose::new(1.0, 2.0, 0.0);
        let b = Pose::new(2.0, 3.0, PI / 2.0);
        let s = OdometryStep::between(&a, &b).unwrap();
        assert!((s.trans_m() - 2f32.sqrt()).abs() < 1e-6);
        assert!((s.rot1_rad() - PI / 4.0).abs() < 1e-6);
        assert!((s.rot2_rad() - PI / 4.0).abs() < 1e-6);
        let c = s.apply(&a);
        assert!((c.x_m - 2.0).abs() < 1e-5 && (c.y_m - 3.0).abs() < 1e-5);
        assert!((c.theta_rad - PI / 2.0).abs() < 1e-5);
    }

    #[test]
    fn short_steps_are_in_place_turns() {
        let a = Pose::new(0.0, 0.0, 0.3);
        let b = Pose::new(0.005, -0.005, 1.3);
        let s = OdometryStep::between(&a, &b).unwrap();
        assert_eq!(s.rot1_rad(), 0.0);
        assert!((s.rot2_rad() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn backward_motion_gets_forward_noise() {
        // Reversing 1 m: δrot1 = π (wrapped to −π). Its rotation noise must be that of a
        // 0-rad turn, i.e. σ δrot1 = √(α2·1) only.
        let n = OdometryNoise::new(0.1, 0.01, 0.0, 0.0).unwrap();
        let a = Pose::new(0.0, 0.0, 0.0);
        let b = Pose::new(-1.0, 0.0, 0.0);
        let s = OdometryStep::between(&a, &b).unwrap();
        let (r1, t, r2) = n.sigmas(&s);
        assert!((r1 - 0.1).abs() < 1e-5, "{r1}");
        assert!((r2 - 0.1).abs() < 1e-5, "{r2}");
        assert_eq!(t, 0.0);
    }

    #[test]
    fn bad_input_is_typed() {
        assert_eq!(
            OdometryNoise::new(0.1, f32::NAN, 0.0, 0.0),
            Err(MotionError::BadAlpha(2))
        );
        assert_eq!(
            OdometryNoise::new(0.1, 0.0, 0.0, -1.0),
            Err(MotionError::BadAlpha(4))
        );
        let a = Pose::new(0.0, 0.0, 0.0);
        let b = Pose::new(f32::INFINITY, 0.0, 0.0);
        assert_eq!(
            OdometryStep::between(&a, &b),
            Err(MotionError::NonFiniteOdometry)
        );
        assert_eq!(
            OdometryStep::between(&Pose::new(-3e38, 0.0, 0.0), &Pose::new(3e38, 0.0, 0.0)),
            Err(MotionError::NonFiniteOdometry)
        );
    }

    #[test]
    fn steps_beyond_the_model_are_typed_errors() {
        // 1e20 m: its variance overflows f32 and one prediction made every particle NaN.
        assert_eq!(
            OdometryStep::new(0.0, 1e20, 0.0),
            Err(MotionError::StepTooLarge)
        );
        assert_eq!(
            OdometryStep::new(0.0, -1_000.5, 0.0),
            Err(MotionError::StepTooLarge)
        );
        assert_eq!(
            OdometryStep::new(1e4, 0.0, 0.0),
            Err(MotionError::StepTooLarge)
        );
        assert_eq!(
            OdometryStep::new(0.0, 0.0, -1e4),
            Err(MotionError::StepTooLarge)
        );
        assert!(OdometryStep::new(-MAX_STEP_ROTATION_RAD, MAX_STEP_M, 3.0).is_ok());
        assert_eq!(
            OdometryStep::between(&Pose::new(0.0, 0.0, 0.0), &Pose::new(800.0, 800.0, 0.0)),
            Err(MotionError::StepTooLarge)
        );
        assert_eq!(
            OdometryNoise::new(0.0, 0.0, 1e30, 0.0),
            Err(MotionError::BadAlpha(3))
        );
        // The largest step with the largest noise still moves every sample to a finite pose.
        let noise = OdometryNoise::uniform(MAX_ALPHA).unwrap();
        let step = OdometryStep::new(MAX_STEP_ROTATION_RAD, -MAX_STEP_M, 2.0).unwrap();
        let (a, b, c) = noise.sigmas(&step);
        assert!(a.is_finite() && b.is_finite() && c.is_finite());
        let mut rng = SplitMix::new(5);
        let mut p = Pose::new(1e5, -1e5, 0.0);
        for _ in 0..1000 {
            p = noise.sample(&p, &step, &mut rng);
            assert!(p.is_finite(), "{p:?}");
        }
    }

    #[test]
    fn sample_moments_match_the_variances() {
        // f64 reference: the sampled δtrans has mean δtrans and variance α3·δtrans² + α4·(r1²+r2²).
        let noise = OdometryNoise::new(0.02, 0.01, 0.03, 0.04).unwrap();
        let step = OdometryStep::new(0.0, 1.0, 0.5).unwrap();
        let start = Pose::new(0.0, 0.0, 0.0);
        let mut rng = SplitMix::new(7);
        let n = 20_000;
        let (mut sx, mut sxx, mut sth, mut sthth) = (0f64, 0f64, 0f64, 0f64);
        for _ in 0..n {
            let p = noise.sample(&start, &step, &mut rng);
            let d = f64::from(p.x_m.hypot(p.y_m));
            sx += d;
            sxx += d * d;
            let t = f64::from(p.theta_rad);
            sth += t;
            sthth += t * t;
        }
        let nf = f64::from(n);
        let var_t = sxx / nf - (sx / nf).powi(2);
        let want_t = 0.03 + 0.04 * 0.25;
        assert!((sx / nf - 1.0).abs() < 0.01, "{}", sx / nf);
        assert!((var_t / want_t - 1.0).abs() < 0.05, "{var_t} vs {want_t}");
        // heading = rot1 + rot2 noise: var = (α2) + (α1·0.25 + α2) = 0.025.
        let var_th = sthth / nf - (sth / nf).powi(2);
        assert!((var_th / 0.025 - 1.0).abs() < 0.05, "{var_th}");
    }
}
