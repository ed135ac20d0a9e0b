//! SLAMTEC RPLIDAR (A1, A2, C1, …) standard scan mode: stream decoder, node encoder, and the
//! few commands a controller sends with their responses.
//!
//! Protocol as published by SLAMTEC in *RPLIDAR Interface Protocol and Application Notes*
//! (document LR001, "standard scan" request `0x20` and its response). All multi-byte fields are
//! little-endian.
//!
//! - A **request** is `0xA5`, a command byte, and for the few commands that carry a payload a
//!   size, the payload and an XOR checksum; the commands here carry none ([`Command`]).
//! - A **response descriptor** is 7 bytes: `0xA5 0x5A`, a 32-bit word whose low 30 bits are the
//!   response length and whose top 2 bits are the send mode (0 single, 1 multiple), and a data
//!   type byte. The scan's descriptor is [`SCAN_DESCRIPTOR`] = `A5 5A 05 00 00 40 81`; GET_INFO
//!   answers `A5 5A 14 00 00 00 04` then 20 bytes ([`DeviceInfo`]); GET_HEALTH answers
//!   `A5 5A 03 00 00 00 06` then 3 bytes ([`Health`]).
//! - After the scan descriptor come 5-byte **nodes** until the controller stops the scan:
//!
//! | byte | bits |
//! |---:|---|
//! | 0 | quality (6 bits) · `!S` · `S` (S = first node of a new revolution) |
//! | 1 | angle_q6 bits 6..0 · check bit `C` (always 1) |
//! | 2 | angle_q6 bits 14..7 |
//! | 3–4 | distance_q2 (`u16`) |
//!
//! angle = angle_q6 / 64 degrees (clockwise), distance = distance_q2 / 4 millimetres; a distance
//! of 0 means no measurement. A node has no checksum: the decoder checks that `S` and `!S`
//! differ and that `C` is 1 before it emits the point, and rejects an angle ≥ 360°. Those checks
//! are weaker than a CRC (a random 5-byte window passes them one time in four), so after a failed
//! node the decoder slides by one byte, and the assembler's rotor tracking keeps stray points from
//! merging revolutions.
//!
//! Every parse and emit of this module places its fields through the one table `field` below.

mod decoder;
mod messages;
mod node;
#[cfg(test)]
mod tests;

pub use decoder::RplidarDecoder;
pub use messages::{Command, Descriptor, DeviceInfo, Health};
pub use node::{encode_revolution, revolution_len, RplidarNode};

/// First byte of every request and of every response descriptor.
pub const SYNC: u8 = 0xA5;
/// Second byte of a response descriptor.
pub const SYNC2: u8 = 0x5A;
/// Bytes per scan node.
pub const NODE_LEN: usize = 5;
/// Bytes per response descriptor.
pub const DESCRIPTOR_LEN: usize = 7;
/// The response descriptor of a standard scan: 5-byte nodes, multiple responses, type `0x81`.
pub const SCAN_DESCRIPTOR: [u8; DESCRIPTOR_LEN] = [0xA5, 0x5A, 0x05, 0x00, 0x00, 0x40, 0x81];
/// Bytes of a GET_INFO response payload.
pub const INFO_LEN: usize = 20;
/// Bytes of a GET_HEALTH response payload.
pub const HEALTH_LEN: usize = 3;
/// A full turn in angle_q6 units (360 · 64).
pub const FULL_TURN_Q6: u16 = 23_040;
/// Bytes per request (the commands here carry no payload).
const REQUEST_LEN: usize = 2;

/// Where each field lies (offsets in bytes) in a request, a descriptor, the single responses and
/// a scan node: the one table the parse and the emit side read.
mod field {
    /// A request.
    pub mod request {
        /// [`SYNC`](super::super::SYNC).
        pub const SYNC: usize = 0;
        /// The command byte.
        pub const COMMAND: usize = 1;
    }

    /// A response descriptor.
    pub mod descriptor {
        use crate::wire::Field;

        /// `A5 5A`.
        pub const SYNC: Field = 0..2;
        /// Response length (low 30 bits) and send mode (top 2 bits), one `u32`.
        pub const LEN_MODE: Field = 2..6;
        /// Data type.
        pub const DATA_TYPE: usize = 6;
    }

    /// The GET_INFO payload.
    pub mod info {
        use crate::wire::Rest;

        /// Model id.
        pub const MODEL: usize = 0;
        /// Firmware version, minor part.
        pub const FIRMWARE_MINOR: usize = 1;
        /// Firmware version, major part.
        pub const FIRMWARE_MAJOR: usize = 2;
        /// Hardware version.
        pub const HARDWARE: usize = 3;
        /// The 16-byte serial number.
        pub const SERIAL: Rest = 4..;
    }

    /// The GET_HEALTH payload.
    pub mod health {
        use crate::wire::Field;

        /// Status.
        pub const STATUS: usize = 0;
        /// Error code.
        pub const ERROR_CODE: Field = 1..3;
    }

    /// A scan node.
    pub mod node {
        use crate::wire::Field;

        /// Quality (bits 7..2), `!S` (bit 1), `S` (bit 0).
        pub const FLAGS: usize = 0;
        /// angle_q6 bits 6..0 (bits 7..1), the check bit `C` (bit 0).
        pub const ANGLE_LOW: usize = 1;
        /// angle_q6 bits 14..7.
        pub const ANGLE_HIGH: usize = 2;
        /// distance_q2.
        pub const DISTANCE: Field = 3..5;
    }
}

// The tables cover each structure exactly.
const _: () = {
    use field::{descriptor, health, info, node, request};
    assert!(request::SYNC == 0 && request::COMMAND + 1 == REQUEST_LEN);
    assert!(descriptor::SYNC.start == 0 && descriptor::SYNC.end == descriptor::LEN_MODE.start);
    assert!(descriptor::LEN_MODE.end == descriptor::DATA_TYPE);
    assert!(descriptor::DATA_TYPE + 1 == DESCRIPTOR_LEN);
    assert!(info::MODEL == 0 && info::HARDWARE + 1 == info::SERIAL.start);
    assert!(INFO_LEN - info::SERIAL.start == 16);
    assert!(health::STATUS == 0 && health::ERROR_CODE.start == 1);
    assert!(health::ERROR_CODE.end == HEALTH_LEN);
    assert!(node::FLAGS == 0 && node::ANGLE_LOW == 1 && node::ANGLE_HIGH == 2);
    assert!(node::DISTANCE.start == 3 && node::DISTANCE.end == NODE_LEN);
};

/// Why bytes were rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum RplidarError {
    /// Fewer bytes than the structure needs.
    Truncated(usize),
    /// A node whose start flag and inverted start flag are equal.
    BadStartFlag,
    /// A node whose check bit is 0.
    BadCheckBit,
    /// A node angle ≥ 360°.
    AngleOutOfRange,
    /// A descriptor that does not start with `0xA5 0x5A`.
    BadSync,
    /// A well-formed descriptor of a response this module does not decode.
    UnknownResponse(Descriptor),
    /// Not a request this module knows.
    UnknownCommand(u8),
}

impl core::fmt::Display for RplidarError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Truncated(n) => write!(f, "truncated at {n} bytes"),
            Self::BadStartFlag => f.write_str("start flag and inverted start flag agree"),
            Self::BadCheckBit => f.write_str("check bit is 0"),
            Self::AngleOutOfRange => f.write_str("angle of 360 degrees or more"),
            Self::BadSync => f.write_str("descriptor does not start with 0xa5 0x5a"),
            Self::UnknownResponse(d) => write!(
                f,
                "unknown response: length {}, mode {}, type {:#04x}",
                d.len, d.mode, d.data_type
            ),
            Self::UnknownCommand(c) => write!(f, "unknown command {c:#04x}"),
        }
    }
}

impl core::error::Error for RplidarError {}
