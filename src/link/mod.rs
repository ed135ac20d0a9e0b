//! The serial link between the device and the computer: framed, checksummed, versioned
//! messages, encoder and decoder side by side. `no_std`, no allocation (the caller's buffers, a
//! fixed 89-byte buffer in the [`Decoder`]), no panic on any input.
//!
//! `docs/link-protocol.md` describes the protocol byte by byte for an implementation in another
//! language; in short, every frame on the wire is
//!
//! ```text
//! COBS( version u8 | type u8 | seq u16 | payload | CRC-32 u32 )  0x00
//! ```
//!
//! little-endian, with a fixed payload layout per message type ([`layout`]). COBS removes every
//! `0x00` from the frame, so `0x00` only ever ends one and a receiver that lost track (garbage,
//! a cut cable, a reset mid-frame) is back in step at the next `0x00`. The CRC is CRC-32/ISO-HDLC
//! (zlib's `crc32`). The decoder checks every value it hands out (finite poses within range, a
//! symmetric covariance with a non-negative diagonal, known flag bits, …): a [`Frame`] never
//! holds a NaN or an out-of-range value, and the encoder refuses to write one.
//!
//! ```
//! use beamfield::link::{Decoder, Encoder, Message, WheelTicks, MAX_WIRE_LEN};
//!
//! // Computer side: encode.
//! let mut encoder = Encoder::new();
//! let mut wire = [0u8; MAX_WIRE_LEN];
//! let ticks = WheelTicks { timestamp_us: 1_000_000, left_ticks: 1200, right_ticks: -35 };
//! let n = encoder.encode(&Message::WheelTicks(ticks), &mut wire)?;
//!
//! // Device side: feed the UART's bytes as they come.
//! let mut decoder = Decoder::new();
//! let mut got = None;
//! decoder.feed(&wire[..n], |frame| got = Some(frame));
//! let frame = got.expect("one frame")?;
//! assert_eq!((frame.seq, frame.message), (0, Message::WheelTicks(ticks)));
//! assert_eq!(decoder.stats().frames, 1);
//! # Ok::<(), beamfield::link::LinkError>(())
//! ```
//!
//! Why an explicit layout and not postcard: postcard writes integers as variable-length
//! varints, so a message's size and every field's offset depend on the values, and a host must
//! reimplement postcard's varint and serde data model to read them. Here every message has one
//! length and every field one offset, so a host reads a frame with Python's `struct.unpack`,
//! a C `memcpy` per field, or a table of offsets ([`layout`]), and a wrong length is an error
//! on its own.

mod decoder;
mod error;
mod frame;
mod from_device;
pub mod layout;
mod to_device;
mod wire;

#[cfg(test)]
mod tests;

pub use decoder::{Decoder, LinkStats};
pub use error::LinkError;
pub use frame::{crc32, decode, encode, Encoder};
pub use from_device::{
    ErrorCode, ErrorReport, Estimate, EstimateFlags, Heartbeat, Quality, QualityState,
};
pub use to_device::{SetInitialPose, SetParameters, WheelOdometry, WheelTicks};

/// The protocol version this module speaks (byte 0 of every frame).
pub const VERSION: u8 = 2;
/// The frame delimiter on the wire.
pub const DELIMITER: u8 = 0x00;
/// Longest payload (an [`Estimate`]), bytes.
pub const MAX_PAYLOAD_LEN: usize = layout::estimate::LEN;
/// Longest decoded frame: header, payload and CRC, bytes.
pub const MAX_FRAME_LEN: usize = layout::header::LEN + MAX_PAYLOAD_LEN + layout::header::CRC_LEN;
/// Longest COBS-encoded frame, without its delimiter, bytes.
pub const MAX_ENCODED_LEN: usize = cobs::max_encoding_length(MAX_FRAME_LEN);
/// Longest frame on the wire, delimiter included: an output buffer of this size takes any frame.
pub const MAX_WIRE_LEN: usize = MAX_ENCODED_LEN + 1;
/// Largest `|x|` and `|y|` of a pose on the link, metres (100 km: f32 still resolves 8 mm there).
pub const MAX_POSITION_M: f32 = 1.0e5;
/// Largest `|θ|` of a pose on the link, radians: π rounded to f32 (3.14159274), so that every
/// heading wrapped into `[−π, π)` in f32 or f64 passes.
pub const MAX_THETA_RAD: f32 = core::f32::consts::PI;
/// Largest particle count ([`SetParameters::particles`], [`Estimate::ess`]).
pub const MAX_PARTICLES: usize = crate::mcl::MAX_PARTICLES;

/// The type byte of a frame. Types `0x01..=0x7F` go to the device, `0x80..=0xFF` come from it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
#[non_exhaustive]
pub enum MessageType {
    /// [`WheelOdometry`].
    WheelOdometry = 0x01,
    /// [`WheelTicks`].
    WheelTicks = 0x02,
    /// [`SetInitialPose`].
    SetInitialPose = 0x03,
    /// [`Message::StartGlobalLocalization`].
    StartGlobalLocalization = 0x04,
    /// [`Message::RequestNoMotionUpdate`].
    RequestNoMotionUpdate = 0x05,
    /// [`SetParameters`].
    SetParameters = 0x06,
    /// [`Estimate`].
    Estimate = 0x81,
    /// [`Heartbeat`].
    Heartbeat = 0x82,
    /// [`ErrorReport`].
    Error = 0x83,
}

impl MessageType {
    /// The type of a type byte, `None` for a byte that names no message.
    pub const fn from_u8(b: u8) -> Option<Self> {
        Some(match b {
            0x01 => Self::WheelOdometry,
            0x02 => Self::WheelTicks,
            0x03 => Self::SetInitialPose,
            0x04 => Self::StartGlobalLocalization,
            0x05 => Self::RequestNoMotionUpdate,
            0x06 => Self::SetParameters,
            0x81 => Self::Estimate,
            0x82 => Self::Heartbeat,
            0x83 => Self::Error,
            _ => return None,
        })
    }

    /// The payload length of this type, bytes.
    pub const fn payload_len(self) -> usize {
        match self {
            Self::WheelOdometry => layout::wheel_odometry::LEN,
            Self::WheelTicks => layout::wheel_ticks::LEN,
            Self::SetInitialPose => layout::set_initial_pose::LEN,
            Self::StartGlobalLocalization | Self::RequestNoMotionUpdate => 0,
            Self::SetParameters => layout::set_parameters::LEN,
            Self::Estimate => layout::estimate::LEN,
            Self::Heartbeat => layout::heartbeat::LEN,
            Self::Error => layout::error::LEN,
        }
    }

    /// True for the messages that go to the device.
    pub const fn is_to_device(self) -> bool {
        (self as u8) < 0x80
    }
}

/// A message of either direction.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Message {
    /// To the device: the wheel-odometry pose.
    WheelOdometry(WheelOdometry),
    /// To the device: the wheel encoders' counters.
    WheelTicks(WheelTicks),
    /// To the device: re-initialize around a pose.
    SetInitialPose(SetInitialPose),
    /// To the device: re-initialize with particles spread over the map's free space (nav2's
    /// `reinitialize_global_localization` service). No payload.
    StartGlobalLocalization,
    /// To the device: update the filter with the next scan although the robot has not moved
    /// (nav2's `request_nomotion_update` service). No payload.
    RequestNoMotionUpdate,
    /// To the device: change some parameters.
    SetParameters(SetParameters),
    /// From the device: the estimate after a scan.
    Estimate(Estimate),
    /// From the device: its counters.
    Heartbeat(Heartbeat),
    /// From the device: a frame it refused.
    Error(ErrorReport),
}

impl Message {
    /// The message's type.
    pub const fn message_type(&self) -> MessageType {
        match self {
            Self::WheelOdometry(_) => MessageType::WheelOdometry,
            Self::WheelTicks(_) => MessageType::WheelTicks,
            Self::SetInitialPose(_) => MessageType::SetInitialPose,
            Self::StartGlobalLocalization => MessageType::StartGlobalLocalization,
            Self::RequestNoMotionUpdate => MessageType::RequestNoMotionUpdate,
            Self::SetParameters(_) => MessageType::SetParameters,
            Self::Estimate(_) => MessageType::Estimate,
            Self::Heartbeat(_) => MessageType::Heartbeat,
            Self::Error(_) => MessageType::Error,
        }
    }
}

/// A decoded frame: its sequence number and its message (every value checked).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame {
    /// The sender's sequence number: one more (wrapping) than that of its previous frame.
    pub seq: u16,
    /// The message.
    pub message: Message,
}
