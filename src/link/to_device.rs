//! The messages the computer sends to the device, their payloads and range checks.
//!
//! Each payload type has `read` (bytes to value, no check), `check` (the ranges of
//! `docs/link-protocol.md`; the offset of the first bad field) and `write` (value to bytes, on a
//! value that passed `check`). The frame codec ([`super::frame`]) runs them in that order.

use super::layout::{set_initial_pose as sip, set_parameters as sp, wheel_odometry as wo};
use super::layout::{wheel_ticks as wt, Field};
use super::wire::{self, require, Check};
use crate::pose::Pose;

/// The robot's pose in the odometry frame from the wheel encoders (nav_msgs/Odometry reduced to
/// 2-D), at a time on the device's clock.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WheelOdometry {
    /// When the pose was measured: µs on the device's clock (0: on arrival).
    pub timestamp_us: u64,
    /// Odometry-frame pose: metres, metres, radians; `|x|, |y| ≤`
    /// [`MAX_POSITION_M`](super::MAX_POSITION_M), `|θ| ≤` [`MAX_THETA_RAD`](super::MAX_THETA_RAD).
    pub pose: Pose,
}

impl WheelOdometry {
    pub(super) fn read(p: &[u8]) -> Self {
        Self {
            timestamp_us: wire::u64_at(p, wo::TIMESTAMP_US),
            pose: wire::pose_at(p, wo::X_M, wo::Y_M, wo::THETA_RAD),
        }
    }

    pub(super) fn check(&self) -> Check {
        wire::check_pose(&self.pose, &wo::X_M, &wo::Y_M, &wo::THETA_RAD)
    }

    pub(super) fn write(&self, p: &mut [u8]) {
        wire::put_u64(p, wo::TIMESTAMP_US, self.timestamp_us);
        wire::put_pose(p, wo::X_M, wo::Y_M, wo::THETA_RAD, &self.pose);
    }
}

/// The two wheels' encoder counters, read at the same time. Counters wrap (any `i32` is valid;
/// a `u32` counter is sent as its bits); the device takes the wrapping difference from the
/// previous message ([`crate::mcl::odometry::DiffDrive`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WheelTicks {
    /// When the counters were read: µs on the device's clock (0: on arrival).
    pub timestamp_us: u64,
    /// The left wheel's counter, ticks (increasing when the wheel drives the robot forward).
    pub left_ticks: i32,
    /// The right wheel's counter, ticks (increasing when the wheel drives the robot forward).
    pub right_ticks: i32,
}

impl WheelTicks {
    pub(super) fn read(p: &[u8]) -> Self {
        Self {
            timestamp_us: wire::u64_at(p, wt::TIMESTAMP_US),
            left_ticks: wire::i32_at(p, wt::LEFT_TICKS),
            right_ticks: wire::i32_at(p, wt::RIGHT_TICKS),
        }
    }

    pub(super) fn write(&self, p: &mut [u8]) {
        wire::put_u64(p, wt::TIMESTAMP_US, self.timestamp_us);
        wire::put_i32(p, wt::LEFT_TICKS, self.left_ticks);
        wire::put_i32(p, wt::RIGHT_TICKS, self.right_ticks);
    }
}

/// Re-initializes the filter around a pose (nav2's `/initialpose`,
/// geometry_msgs/PoseWithCovarianceStamped, reduced to x, y, yaw).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SetInitialPose {
    /// When the robot was at `pose`: µs on the device's clock (0: on arrival).
    pub timestamp_us: u64,
    /// Map-frame pose: metres, metres, radians, ranges as [`WheelOdometry::pose`].
    pub pose: Pose,
    /// Covariance of `(x, y, θ)`, row-major (m², m², rad² on the diagonal; m² and m·rad off
    /// it): finite, exactly symmetric, non-negative diagonal.
    pub covariance: [[f32; 3]; 3],
}

impl SetInitialPose {
    pub(super) fn read(p: &[u8]) -> Self {
        Self {
            timestamp_us: wire::u64_at(p, sip::TIMESTAMP_US),
            pose: wire::pose_at(p, sip::X_M, sip::Y_M, sip::THETA_RAD),
            covariance: wire::matrix_at(p, sip::COVARIANCE),
        }
    }

    pub(super) fn check(&self) -> Check {
        wire::check_pose(&self.pose, &sip::X_M, &sip::Y_M, &sip::THETA_RAD)?;
        wire::check_covariance(&self.covariance, &sip::COVARIANCE)
    }

    pub(super) fn write(&self, p: &mut [u8]) {
        wire::put_u64(p, sip::TIMESTAMP_US, self.timestamp_us);
        wire::put_pose(p, sip::X_M, sip::Y_M, sip::THETA_RAD, &self.pose);
        wire::put_matrix(p, sip::COVARIANCE, &self.covariance);
    }
}

/// Changes some of the filter's parameters; `None` leaves one as it is. The device answers a
/// value it cannot take (e.g. more particles than its capacity) with an
/// [`ErrorReport`](super::ErrorReport) of code [`Refused`](super::ErrorCode::Refused).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SetParameters {
    /// Particles in use, 1 to [`MAX_PARTICLES`](super::MAX_PARTICLES).
    pub particles: Option<u16>,
    /// κ, the tempering exponent (dimensionless; [`crate::Tempered`]): finite, > 0.
    pub kappa: Option<f32>,
    /// The odometry noise `odom_alpha1..4` ([`crate::mcl::OdometryNoise`]; dimensionless):
    /// each finite and ≥ 0.
    pub odom_alpha: [Option<f32>; 4],
}

/// The four α fields, in order.
const ALPHA: [Field; 4] = [
    sp::ODOM_ALPHA1,
    sp::ODOM_ALPHA2,
    sp::ODOM_ALPHA3,
    sp::ODOM_ALPHA4,
];
/// Presence bits: particles, κ, α1..α4.
const HAS_PARTICLES: u8 = 1 << 0;
const HAS_KAPPA: u8 = 1 << 1;
const fn has_alpha(i: usize) -> u8 {
    1 << (2 + i)
}
/// Bits 6 and 7 of the presence byte: reserved, zero.
const RESERVED_PRESENT: u8 = 0b1100_0000;

impl SetParameters {
    fn present(&self) -> u8 {
        let mut bits = 0;
        if self.particles.is_some() {
            bits |= HAS_PARTICLES;
        }
        if self.kappa.is_some() {
            bits |= HAS_KAPPA;
        }
        for (i, a) in self.odom_alpha.iter().enumerate() {
            if a.is_some() {
                bits |= has_alpha(i);
            }
        }
        bits
    }

    /// Reads the payload; `Err` (the offset) when a reserved presence bit is set or an absent
    /// field is not zero (so that every value has exactly one encoding).
    pub(super) fn read(p: &[u8]) -> Result<Self, usize> {
        let present = wire::u8_at(p, sp::PRESENT);
        require(present & RESERVED_PRESENT == 0, &sp::PRESENT)?;
        let particles = wire::u16_at(p, sp::PARTICLES);
        require(
            present & HAS_PARTICLES != 0 || particles == 0,
            &sp::PARTICLES,
        )?;
        let kappa = wire::f32_at(p, sp::KAPPA);
        require(present & HAS_KAPPA != 0 || kappa.to_bits() == 0, &sp::KAPPA)?;
        let mut odom_alpha = [None; 4];
        for (i, (slot, field)) in odom_alpha.iter_mut().zip(ALPHA).enumerate() {
            let a = wire::f32_at(p, field.clone());
            if present & has_alpha(i) != 0 {
                *slot = Some(a);
            } else {
                require(a.to_bits() == 0, &field)?;
            }
        }
        Ok(Self {
            particles: (present & HAS_PARTICLES != 0).then_some(particles),
            kappa: (present & HAS_KAPPA != 0).then_some(kappa),
            odom_alpha,
        })
    }

    pub(super) fn check(&self) -> Check {
        if let Some(n) = self.particles {
            require(
                n >= 1 && usize::from(n) <= super::MAX_PARTICLES,
                &sp::PARTICLES,
            )?;
        }
        if let Some(k) = self.kappa {
            require(k.is_finite() && k > 0.0, &sp::KAPPA)?;
        }
        for (a, field) in self.odom_alpha.iter().zip(&ALPHA) {
            if let Some(a) = *a {
                require(a.is_finite() && a >= 0.0, field)?;
            }
        }
        Ok(())
    }

    pub(super) fn write(&self, p: &mut [u8]) {
        wire::put_u8(p, sp::PRESENT, self.present());
        wire::put_u16(p, sp::PARTICLES, self.particles.unwrap_or(0));
        wire::put_f32(p, sp::KAPPA, self.kappa.unwrap_or(0.0));
        for (a, field) in self.odom_alpha.iter().zip(ALPHA) {
            wire::put_f32(p, field, a.unwrap_or(0.0));
        }
    }
}
