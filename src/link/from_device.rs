//! The messages the device sends to the computer, their payloads and range checks (see
//! [`super::to_device`] for the `read` / `check` / `write` convention).

use super::layout::{error as er, estimate as es, heartbeat as hb};
use super::wire::{self, require, Check};
use super::LinkError;
use crate::pose::Pose;

/// Bits of [`Estimate::flags`]. Bits 6 to 15 are reserved and zero in this protocol version.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EstimateFlags(u16);

impl EstimateFlags {
    /// No flag set.
    pub const EMPTY: Self = Self(0);
    /// Bit 0: the filter holds particles (without it the pose means nothing).
    pub const INITIALIZED: Self = Self(1 << 0);
    /// Bit 1: the update resampled the particles.
    pub const RESAMPLED: Self = Self(1 << 1);
    /// Bit 2: the update injected random particles (augmented-MCL recovery).
    pub const RECOVERY: Self = Self(1 << 2);
    /// Bit 3: the filter's last initialization was global (`StartGlobalLocalization`), not a
    /// `SetInitialPose`.
    pub const GLOBAL_LOCALIZATION: Self = Self(1 << 3);
    /// Bit 4: the update was asked for by `RequestNoMotionUpdate` (no motion since the last).
    pub const NO_MOTION_UPDATE: Self = Self(1 << 4);
    /// Bit 5: no odometry reached the device within its timeout before the scan.
    pub const ODOMETRY_STALE: Self = Self(1 << 5);
    /// Every defined bit.
    pub const ALL: Self = Self(0b11_1111);

    /// The flags of `bits`, `None` when a reserved bit is set.
    pub const fn from_bits(bits: u16) -> Option<Self> {
        if bits & !Self::ALL.0 == 0 {
            Some(Self(bits))
        } else {
            None
        }
    }

    /// The bits on the wire.
    pub const fn bits(self) -> u16 {
        self.0
    }

    /// True when every flag of `other` is set in `self`.
    pub const fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }
}

impl core::ops::BitOr for EstimateFlags {
    type Output = Self;
    fn bitor(self, rhs: Self) -> Self {
        Self(self.0 | rhs.0)
    }
}

/// What the device thinks of its own estimate: byte `QUALITY_STATE` of [`Estimate`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum QualityState {
    /// 0: not assessed (the device computes no quality signal).
    #[default]
    Unknown = 0,
    /// 1: the estimate follows the robot.
    Tracking = 1,
    /// 2: the particles are spread or the scans fit poorly.
    Uncertain = 2,
    /// 3: the filter has lost the robot (recovery or re-initialization needed).
    Lost = 3,
}

impl QualityState {
    /// The state of a byte, `None` for 4 to 255.
    pub const fn from_u8(b: u8) -> Option<Self> {
        match b {
            0 => Some(Self::Unknown),
            1 => Some(Self::Tracking),
            2 => Some(Self::Uncertain),
            3 => Some(Self::Lost),
            _ => None,
        }
    }
}

/// The quality signal of an [`Estimate`]: the localizer's own assessment
/// ([`crate::mcl::QualityReport`], converted by `From`); a device that computes none sends
/// [`QualityState::Unknown`] and a score of 0.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Quality {
    /// The state.
    pub state: QualityState,
    /// A score in `[0, 1]` (dimensionless; 1 best), finite.
    pub score: f32,
}

impl From<crate::mcl::Quality> for QualityState {
    fn from(q: crate::mcl::Quality) -> Self {
        match q {
            crate::mcl::Quality::Tracking => Self::Tracking,
            crate::mcl::Quality::Uncertain => Self::Uncertain,
            crate::mcl::Quality::Lost => Self::Lost,
        }
    }
}

impl From<&crate::mcl::QualityReport> for Quality {
    /// The state, and the report's score (a NaN score, which a report never has, sends 0).
    fn from(r: &crate::mcl::QualityReport) -> Self {
        let score = if r.score.is_nan() {
            0.0
        } else {
            r.score.clamp(0.0, 1.0)
        };
        Self {
            state: r.state.into(),
            score,
        }
    }
}

/// The filter's estimate after a scan (what nav2_amcl publishes on `/amcl_pose`).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Estimate {
    /// When the scan the update used ended: µs on the device's clock.
    pub timestamp_us: u64,
    /// Map-frame pose (metres, metres, radians), ranges as in [`super::WheelOdometry::pose`].
    pub pose: Pose,
    /// Covariance of `(x, y, θ)`, row-major (m², m², rad² on the diagonal): finite, exactly
    /// symmetric, non-negative diagonal.
    pub covariance: [[f32; 3]; 3],
    /// Effective sample size, particles: finite, in `[0, MAX_PARTICLES]`.
    pub ess: f32,
    /// Flags; reserved bits zero.
    pub flags: EstimateFlags,
    /// Quality signal.
    pub quality: Quality,
    /// The odometry-frame pose (metres, metres, radians) at the scan's time: the odometry the
    /// update predicted to. With [`Self::pose`] it gives the map → odom transform
    /// (`pose ⊖ odometry`), the one nav2_amcl broadcasts, without the computer needing the
    /// odometry at the scan's time itself. Ranges as in [`super::WheelOdometry::pose`].
    pub odometry: Pose,
}

impl Estimate {
    /// The message for the filter's [`crate::mcl::Estimate`] of a scan that ended at
    /// `timestamp_us`, predicted to the odometry pose `odometry`. The covariance is made exactly symmetric (the mean of each mirrored
    /// pair), so that it passes the receiver's check.
    pub fn from_mcl(
        estimate: &crate::mcl::Estimate,
        timestamp_us: u64,
        flags: EstimateFlags,
        quality: Quality,
        odometry: Pose,
    ) -> Self {
        let mut covariance = estimate.covariance;
        let c = estimate.covariance;
        for (i, row) in covariance.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                let mirror = c.get(j).and_then(|r| r.get(i)).copied().unwrap_or(*v);
                *v = if i == j { *v } else { 0.5 * (*v + mirror) };
            }
        }
        Self {
            timestamp_us,
            pose: estimate.pose,
            covariance,
            ess: estimate.ess,
            flags,
            quality,
            odometry,
        }
    }

    /// Reads the payload; `Err` (the offset) for reserved flag bits or an unknown state.
    pub(super) fn read(p: &[u8]) -> Result<Self, usize> {
        let flags = EstimateFlags::from_bits(wire::u16_at(p, es::FLAGS)).ok_or(es::FLAGS.start)?;
        let state = QualityState::from_u8(wire::u8_at(p, es::QUALITY_STATE))
            .ok_or(es::QUALITY_STATE.start)?;
        Ok(Self {
            timestamp_us: wire::u64_at(p, es::TIMESTAMP_US),
            pose: wire::pose_at(p, es::X_M, es::Y_M, es::THETA_RAD),
            covariance: wire::matrix_at(p, es::COVARIANCE),
            ess: wire::f32_at(p, es::ESS),
            flags,
            quality: Quality {
                state,
                score: wire::f32_at(p, es::QUALITY_SCORE),
            },
            odometry: wire::pose_at(p, es::ODOM_X_M, es::ODOM_Y_M, es::ODOM_THETA_RAD),
        })
    }

    pub(super) fn check(&self) -> Check {
        wire::check_pose(&self.pose, &es::X_M, &es::Y_M, &es::THETA_RAD)?;
        wire::check_covariance(&self.covariance, &es::COVARIANCE)?;
        // `MAX_PARTICLES` (65,535) is exact in f32.
        let max = super::MAX_PARTICLES as f32;
        require(
            self.ess.is_finite() && (0.0..=max).contains(&self.ess),
            &es::ESS,
        )?;
        let s = self.quality.score;
        require(
            s.is_finite() && (0.0..=1.0).contains(&s),
            &es::QUALITY_SCORE,
        )?;
        wire::check_pose(
            &self.odometry,
            &es::ODOM_X_M,
            &es::ODOM_Y_M,
            &es::ODOM_THETA_RAD,
        )
    }

    pub(super) fn write(&self, p: &mut [u8]) {
        wire::put_u64(p, es::TIMESTAMP_US, self.timestamp_us);
        wire::put_pose(p, es::X_M, es::Y_M, es::THETA_RAD, &self.pose);
        wire::put_matrix(p, es::COVARIANCE, &self.covariance);
        wire::put_f32(p, es::ESS, self.ess);
        wire::put_u16(p, es::FLAGS, self.flags.bits());
        wire::put_u8(p, es::QUALITY_STATE, self.quality.state as u8);
        wire::put_f32(p, es::QUALITY_SCORE, self.quality.score);
        wire::put_pose(
            p,
            es::ODOM_X_M,
            es::ODOM_Y_M,
            es::ODOM_THETA_RAD,
            &self.odometry,
        );
    }
}

/// The device's counters, sent periodically (e.g. once a second). Every counter is a wrapping
/// `u32` since the device started; the computer takes differences between heartbeats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Heartbeat {
    /// When the heartbeat was sent: µs on the device's clock.
    pub timestamp_us: u64,
    /// Bytes received from the computer.
    pub bytes: u32,
    /// Frames received and accepted.
    pub frames: u32,
    /// Frames whose CRC failed.
    pub checksum_failures: u32,
    /// LiDAR scans completed.
    pub scans: u32,
    /// Filter updates (estimates) computed.
    pub updates: u32,
    /// Odometry messages (`WheelOdometry`, `WheelTicks`) accepted.
    pub odometry: u32,
    /// Scans or messages the device dropped (no time or buffer for them).
    pub drops: u32,
    /// Frames received and refused, all causes (the CRC failures included).
    pub link_errors: u32,
    /// LiDAR bytes the decoder skipped while searching for a frame header (noise, a wrong baud
    /// rate, the rest of a frame whose checksum failed).
    pub lidar_skipped: u32,
    /// Frames (estimates, heartbeats, error reports) the device could not encode: never sent.
    pub encode_failures: u32,
    /// Frames refused after their CRC passed (commands and odometry): an error report went
    /// out for each. Also counted in [`Heartbeat::link_errors`].
    pub refused: u32,
    /// Milliseconds since the device started on its own monotonic clock (not the LiDAR's:
    /// it advances whatever the LiDAR sends), wrapping at 2³²; 0 from a device that keeps none.
    pub uptime_ms: u32,
}

impl Heartbeat {
    pub(super) fn read(p: &[u8]) -> Self {
        Self {
            timestamp_us: wire::u64_at(p, hb::TIMESTAMP_US),
            bytes: wire::u32_at(p, hb::BYTES),
            frames: wire::u32_at(p, hb::FRAMES),
            checksum_failures: wire::u32_at(p, hb::CHECKSUM_FAILURES),
            scans: wire::u32_at(p, hb::SCANS),
            updates: wire::u32_at(p, hb::UPDATES),
            odometry: wire::u32_at(p, hb::ODOMETRY),
            drops: wire::u32_at(p, hb::DROPS),
            link_errors: wire::u32_at(p, hb::LINK_ERRORS),
            lidar_skipped: wire::u32_at(p, hb::LIDAR_SKIPPED),
            encode_failures: wire::u32_at(p, hb::ENCODE_FAILURES),
            refused: wire::u32_at(p, hb::REFUSED),
            uptime_ms: wire::u32_at(p, hb::UPTIME_MS),
        }
    }

    pub(super) fn write(&self, p: &mut [u8]) {
        wire::put_u64(p, hb::TIMESTAMP_US, self.timestamp_us);
        wire::put_u32(p, hb::BYTES, self.bytes);
        wire::put_u32(p, hb::FRAMES, self.frames);
        wire::put_u32(p, hb::CHECKSUM_FAILURES, self.checksum_failures);
        wire::put_u32(p, hb::SCANS, self.scans);
        wire::put_u32(p, hb::UPDATES, self.updates);
        wire::put_u32(p, hb::ODOMETRY, self.odometry);
        wire::put_u32(p, hb::DROPS, self.drops);
        wire::put_u32(p, hb::LINK_ERRORS, self.link_errors);
        wire::put_u32(p, hb::LIDAR_SKIPPED, self.lidar_skipped);
        wire::put_u32(p, hb::ENCODE_FAILURES, self.encode_failures);
        wire::put_u32(p, hb::REFUSED, self.refused);
        wire::put_u32(p, hb::UPTIME_MS, self.uptime_ms);
    }
}

/// Why the device refused a frame whose CRC passed (byte `CODE` of [`ErrorReport`]). Frames
/// that fail earlier (COBS, length, CRC) are only counted ([`Heartbeat`]): nothing in them, not
/// even the sequence number, can be trusted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
#[non_exhaustive]
pub enum ErrorCode {
    /// 1: another protocol version; detail: the version byte received.
    WrongVersion = 1,
    /// 2: unknown message type; detail: 0.
    UnknownType = 2,
    /// 3: wrong payload length; detail: the length received (bytes).
    WrongLength = 3,
    /// 4: a value out of range; detail: the payload offset of the first bad field.
    ValueOutOfRange = 4,
    /// 5: a valid message the device cannot carry out (e.g. more particles than its capacity);
    /// detail: 0.
    Refused = 5,
    /// 6: the message needs an initialized filter (e.g. `RequestNoMotionUpdate` before any
    /// `SetInitialPose` or `StartGlobalLocalization`); detail: 0.
    NotInitialized = 6,
    /// 7: a timestamped message (odometry) not later than the last one accepted: time went
    /// backwards or the message was replayed; detail: 0.
    OutOfOrder = 7,
}

impl ErrorCode {
    /// The code of a byte, `None` for 0 and 8 to 255.
    pub const fn from_u8(b: u8) -> Option<Self> {
        match b {
            1 => Some(Self::WrongVersion),
            2 => Some(Self::UnknownType),
            3 => Some(Self::WrongLength),
            4 => Some(Self::ValueOutOfRange),
            5 => Some(Self::Refused),
            6 => Some(Self::NotInitialized),
            7 => Some(Self::OutOfOrder),
            _ => None,
        }
    }
}

/// The device's answer to a frame it refused: which frame, and why.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ErrorReport {
    /// Why.
    pub code: ErrorCode,
    /// The offending frame's type byte.
    pub msg_type: u8,
    /// The offending frame's sequence number.
    pub seq: u16,
    /// Per code (see [`ErrorCode`]).
    pub detail: u8,
}

impl ErrorReport {
    /// The report of a decoding error, when the frame's CRC passed (else `None`: such frames
    /// are only counted).
    pub fn for_link_error(e: &LinkError) -> Option<Self> {
        let (code, msg_type, seq, detail) = match *e {
            LinkError::WrongVersion {
                version,
                msg_type,
                seq,
            } => (ErrorCode::WrongVersion, msg_type, seq, version),
            LinkError::UnknownType { msg_type, seq } => (ErrorCode::UnknownType, msg_type, seq, 0),
            LinkError::WrongLength { msg_type, seq, len } => {
                (ErrorCode::WrongLength, msg_type, seq, len)
            }
            LinkError::ValueOutOfRange {
                msg_type,
                seq,
                offset,
            } => (ErrorCode::ValueOutOfRange, msg_type, seq, offset),
            _ => return None,
        };
        Some(Self {
            code,
            msg_type,
            seq,
            detail,
        })
    }

    /// Reads the payload; `Err` (the offset) for an unknown code.
    pub(super) fn read(p: &[u8]) -> Result<Self, usize> {
        Ok(Self {
            code: ErrorCode::from_u8(wire::u8_at(p, er::CODE)).ok_or(er::CODE.start)?,
            msg_type: wire::u8_at(p, er::MSG_TYPE),
            seq: wire::u16_at(p, er::SEQ),
            detail: wire::u8_at(p, er::DETAIL),
        })
    }

    pub(super) fn write(&self, p: &mut [u8]) {
        wire::put_u8(p, er::CODE, self.code as u8);
        wire::put_u8(p, er::MSG_TYPE, self.msg_type);
        wire::put_u16(p, er::SEQ, self.seq);
        wire::put_u8(p, er::DETAIL, self.detail);
    }
}
