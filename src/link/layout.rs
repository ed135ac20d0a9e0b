//! Byte offsets of every field on the wire, one module per part of a frame, as ranges into the
//! decoded frame (`header`) or into the payload (every message). All multi-byte fields are
//! little-endian; `f32` is IEEE 754 binary32, `u64`/`u32`/`u16` unsigned, `i32` two's complement.
//! `docs/link-protocol.md` has the same tables with units and valid ranges.

/// A field: the byte range it occupies.
pub type Field = core::ops::Range<usize>;

/// The header that starts every decoded frame, and the checksum that ends it.
pub mod header {
    use super::Field;
    /// Protocol version, `u8` ([`VERSION`](crate::link::VERSION)).
    pub const VERSION: Field = 0..1;
    /// Message type, `u8` ([`MessageType`](crate::link::MessageType)).
    pub const TYPE: Field = 1..2;
    /// Sequence number, `u16`, per sender, wrapping.
    pub const SEQ: Field = 2..4;
    /// Header length: the payload starts here.
    pub const LEN: usize = 4;
    /// Length of the CRC-32 that follows the payload (`u32`).
    pub const CRC_LEN: usize = 4;
}

/// `WheelOdometry` (type `0x01`).
pub mod wheel_odometry {
    use super::Field;
    /// `u64`, µs, device clock.
    pub const TIMESTAMP_US: Field = 0..8;
    /// `f32`, m, odometry frame.
    pub const X_M: Field = 8..12;
    /// `f32`, m, odometry frame.
    pub const Y_M: Field = 12..16;
    /// `f32`, rad, counter-clockwise.
    pub const THETA_RAD: Field = 16..20;
    /// Payload length.
    pub const LEN: usize = 20;
}

/// `WheelTicks` (type `0x02`).
pub mod wheel_ticks {
    use super::Field;
    /// `u64`, µs, device clock.
    pub const TIMESTAMP_US: Field = 0..8;
    /// `i32`, ticks, wrapping counter of the left wheel's encoder.
    pub const LEFT_TICKS: Field = 8..12;
    /// `i32`, ticks, wrapping counter of the right wheel's encoder.
    pub const RIGHT_TICKS: Field = 12..16;
    /// Payload length.
    pub const LEN: usize = 16;
}

/// `SetInitialPose` (type `0x03`).
pub mod set_initial_pose {
    use super::Field;
    /// `u64`, µs, device clock (0: on arrival).
    pub const TIMESTAMP_US: Field = 0..8;
    /// `f32`, m, map frame.
    pub const X_M: Field = 8..12;
    /// `f32`, m, map frame.
    pub const Y_M: Field = 12..16;
    /// `f32`, rad, map frame.
    pub const THETA_RAD: Field = 16..20;
    /// 9 × `f32`, covariance of (x, y, θ) row-major: m², m·rad, rad².
    pub const COVARIANCE: Field = 20..56;
    /// Payload length.
    pub const LEN: usize = 56;
}

/// `SetParameters` (type `0x06`).
pub mod set_parameters {
    use super::Field;
    /// `u8`, which of the following fields are present (bit 0 particles, 1 κ, 2..5 α1..α4).
    pub const PRESENT: Field = 0..1;
    /// `u16`, particles in use.
    pub const PARTICLES: Field = 1..3;
    /// `f32`, κ, the tempering exponent (dimensionless).
    pub const KAPPA: Field = 3..7;
    /// `f32`, odometry noise α1 (rad²/rad²).
    pub const ODOM_ALPHA1: Field = 7..11;
    /// `f32`, odometry noise α2 (rad²/m²).
    pub const ODOM_ALPHA2: Field = 11..15;
    /// `f32`, odometry noise α3 (m²/m²).
    pub const ODOM_ALPHA3: Field = 15..19;
    /// `f32`, odometry noise α4 (m²/rad²).
    pub const ODOM_ALPHA4: Field = 19..23;
    /// Payload length.
    pub const LEN: usize = 23;
}

/// `Estimate` (type `0x81`).
pub mod estimate {
    use super::Field;
    /// `u64`, µs, device clock: when the scan the estimate used ended.
    pub const TIMESTAMP_US: Field = 0..8;
    /// `f32`, m, map frame.
    pub const X_M: Field = 8..12;
    /// `f32`, m, map frame.
    pub const Y_M: Field = 12..16;
    /// `f32`, rad, map frame.
    pub const THETA_RAD: Field = 16..20;
    /// 9 × `f32`, covariance of (x, y, θ) row-major: m², m·rad, rad².
    pub const COVARIANCE: Field = 20..56;
    /// `f32`, effective sample size (particles).
    pub const ESS: Field = 56..60;
    /// `u16`, flags bitfield ([`EstimateFlags`](crate::link::EstimateFlags)).
    pub const FLAGS: Field = 60..62;
    /// `u8`, [`QualityState`](crate::link::QualityState).
    pub const QUALITY_STATE: Field = 62..63;
    /// `f32`, quality score in `[0, 1]`.
    pub const QUALITY_SCORE: Field = 63..67;
    /// `f32`, m, odometry frame: the odometry pose the update predicted to (x).
    pub const ODOM_X_M: Field = 67..71;
    /// `f32`, m, odometry frame (y).
    pub const ODOM_Y_M: Field = 71..75;
    /// `f32`, rad, odometry frame (θ).
    pub const ODOM_THETA_RAD: Field = 75..79;
    /// Payload length.
    pub const LEN: usize = 79;
}

/// `Heartbeat` (type `0x82`): every counter a wrapping `u32` since the device started.
pub mod heartbeat {
    use super::Field;
    /// `u64`, µs, device clock: when the heartbeat was sent.
    pub const TIMESTAMP_US: Field = 0..8;
    /// Bytes received from the computer.
    pub const BYTES: Field = 8..12;
    /// Frames received and accepted.
    pub const FRAMES: Field = 12..16;
    /// Frames whose CRC failed.
    pub const CHECKSUM_FAILURES: Field = 16..20;
    /// LiDAR scans completed.
    pub const SCANS: Field = 20..24;
    /// Filter updates (estimates) computed.
    pub const UPDATES: Field = 24..28;
    /// Odometry messages (`WheelOdometry`, `WheelTicks`) accepted.
    pub const ODOMETRY: Field = 28..32;
    /// Scans or messages the device dropped (no time or buffer for them).
    pub const DROPS: Field = 32..36;
    /// Frames received and refused, all causes (CRC failures included).
    pub const LINK_ERRORS: Field = 36..40;
    /// LiDAR bytes the decoder skipped while searching for a frame header (noise, a wrong baud
    /// rate, the rest of a frame whose checksum failed).
    pub const LIDAR_SKIPPED: Field = 40..44;
    /// Frames the device could not encode (never sent).
    pub const ENCODE_FAILURES: Field = 44..48;
    /// Frames refused after their CRC passed (an `Error` went out for each).
    pub const REFUSED: Field = 48..52;
    /// `u32`, ms since the device started, on its own monotonic clock (not the LiDAR's).
    pub const UPTIME_MS: Field = 52..56;
    /// Payload length.
    pub const LEN: usize = 56;
}

/// `Error` (type `0x83`).
pub mod error {
    use super::Field;
    /// `u8`, [`ErrorCode`](crate::link::ErrorCode).
    pub const CODE: Field = 0..1;
    /// `u8`, the type byte of the offending frame.
    pub const MSG_TYPE: Field = 1..2;
    /// `u16`, the sequence number of the offending frame.
    pub const SEQ: Field = 2..4;
    /// `u8`, detail (per code).
    pub const DETAIL: Field = 4..5;
    /// Payload length.
    pub const LEN: usize = 5;
}
