//! LDROBOT LD06 / LD19 / STL-19P frames: decoder (byte-at-a-time) and encoder.
//!
//! Protocol as published by LDROBOT (LD06 and LD19 development manuals, "communication
//! protocol" chapter; the same layout is used by their `ldlidar_stl_ros2` driver). A frame is
//! [`FRAME_LEN`] = 47 bytes, all multi-byte fields little-endian:
//!
//! | offset | size | field |
//! |---:|---:|---|
//! | 0 | 1 | header, [`HEADER`] = `0x54` |
//! | 1 | 1 | VerLen, [`VER_LEN`] = `0x2C`: packet type 1 (upper 3 bits), 12 points (lower 5 bits) |
//! | 2 | 2 | rotation speed, degrees per second |
//! | 4 | 2 | start angle, 0.01° |
//! | 6 | 36 | 12 × (distance mm `u16`, intensity `u8`) |
//! | 42 | 2 | end angle, 0.01° |
//! | 44 | 2 | timestamp, ms (the sensor wraps it at 30,000) |
//! | 46 | 1 | CRC-8 of bytes 0..46: polynomial `0x4D`, initial value 0, not reflected, no final XOR |
//!
//! The points of a frame are evenly spaced from the start to the end angle, clockwise: point `i`
//! lies at `start + i · (end − start) / 11`, where `end − start` is taken modulo 360° (a frame
//! may straddle 0°). A distance of 0 means "no measurement" and is emitted with
//! `valid == false`.
//!
//! The decoder only accepts VerLen `0x2C` (the fixed 12-point frame all three sensors send).
//! After a failed checksum it looks for the next header candidate inside the rejected bytes, so
//! a truncated frame costs only itself, not the frame that follows it.
//!
//! The CRC-8 lets through about one damaged window in 256, so a frame whose CRC passed must also
//! be plausible ([`Ld06Frame::is_plausible`]): a rotation speed within the manuals' 5–13 Hz
//! ([`MIN_SPEED_DEG_PER_S`] ..= [`MAX_SPEED_DEG_PER_S`]) and a span from the start to the end
//! angle no wider than twelve points can cover at that speed ([`Ld06Frame::max_span_cdeg`]). A
//! frame that fails is treated as a window the CRC should have caught: counted in
//! `implausible_frames`, none of its points emitted, its bytes searched for the next header.
//!
//! Files: this one holds the constants, the CRC, the field table (`field`, read by both
//! [`Ld06Frame::parse`] and [`Ld06Frame::emit`]) and the error type; `frame.rs` the frame's
//! fields, parse, checks, emit and points, and the revolution encoder; `decoder.rs` the stream
//! decoder, whose frame check returns a verdict that the shared header hunt
//! (`src/lidar/sync.rs`) settles.

use super::sync::{Header, Verdict};
use crate::wire::{self, Field};
use crc::Algorithm;

mod decoder;
mod frame;
#[cfg(test)]
mod tests;

pub use decoder::Ld06Decoder;
pub use frame::{encode_revolution, revolution_len, Ld06Frame, Ld06Sample};

/// Frame header byte.
pub const HEADER: u8 = 0x54;
/// The VerLen byte of a 12-point frame.
pub const VER_LEN: u8 = 0x2C;
/// Bytes per frame.
pub const FRAME_LEN: usize = 47;
/// Points per frame.
pub const POINTS_PER_FRAME: usize = 12;
/// Angles are in hundredths of a degree, below this value.
pub const FULL_TURN_CDEG: u16 = 36_000;
/// The sensor's timestamp wraps at this many milliseconds.
pub const TIMESTAMP_WRAP_MS: u16 = 30_000;
/// Slowest rotation the LD06 and LD19 manuals specify, degrees per second (5 Hz).
pub const MIN_SPEED_DEG_PER_S: u16 = 1_800;
/// Fastest rotation the LD06 and LD19 manuals specify, degrees per second (13 Hz).
pub const MAX_SPEED_DEG_PER_S: u16 = 4_680;
/// The sample rate [`Ld06Frame::max_span_cdeg`] assumes, samples per second: below every rate
/// the sensors are known to sample at (the LD06 manual's 4,500 Hz; the LD19 manual's example
/// frame, 10.43° over 11 steps at 2,152 °/s, was sampled at about 2,270 Hz).
pub const SAMPLE_RATE_FLOOR_HZ: u32 = 2_250;

/// The LD06 CRC-8 (polynomial `0x4D`, init 0, not reflected, no final XOR). Its check value
/// (the CRC of ASCII `123456789`) is `0xC3`.
pub const CRC_8_LD06: Algorithm<u8> = Algorithm {
    width: 8,
    poly: 0x4D,
    init: 0x00,
    refin: false,
    refout: false,
    xorout: 0x00,
    check: 0xC3,
    residue: 0x00,
};

/// The CRC of every byte value from a register of 0 (the table of LDROBOT's manuals and of
/// the `crc` crate's table-driven [`Algorithm`] implementation, built here so that the frame
/// check can run it unrolled).
// Evaluated at compile time: an index out of bounds would stop the build, it cannot panic.
#[allow(clippy::indexing_slicing)]
const CRC8_TABLE: [u8; 256] = {
    let mut table = [0u8; 256];
    let mut byte = 0;
    while byte < 256 {
        let mut c = byte as u8;
        let mut bit = 0;
        while bit < 8 {
            c = if c & 0x80 != 0 {
                (c << 1) ^ CRC_8_LD06.poly
            } else {
                c << 1
            };
            bit += 1;
        }
        table[byte] = c;
        byte += 1;
    }
    table
};

/// One byte into the CRC register `crc`.
#[inline(always)]
fn crc8_step(crc: u8, byte: u8) -> u8 {
    // A `u8` index into a 256-entry table: never out of bounds.
    CRC8_TABLE
        .get(usize::from(crc ^ byte))
        .copied()
        .unwrap_or(0)
}

/// The LD06 CRC-8 of `bytes`.
pub fn crc8(bytes: &[u8]) -> u8 {
    bytes.iter().fold(CRC_8_LD06.init, |c, &b| crc8_step(c, b))
}

/// The CRC-8 of the bytes of a frame it covers (`field::CHECKED`): [`crc8`] four bytes per
/// step, which the compiler lays out without a loop counter per byte (on a Cortex-M4 about three
/// instructions per byte instead of seven).
#[inline(always)]
fn crc8_frame(frame: &[u8; FRAME_LEN]) -> u8 {
    let checked = frame.get(field::CHECKED).unwrap_or(&[]);
    let words = checked.chunks_exact(4);
    let tail = words.remainder();
    let mut c = CRC_8_LD06.init;
    for w in words {
        if let [a, b, d, e] = *w {
            c = crc8_step(crc8_step(crc8_step(crc8_step(c, a), b), d), e);
        }
    }
    tail.iter().fold(c, |c, &b| crc8_step(c, b))
}

/// Where each field of a frame lies (offsets in bytes): the one table the parse and the emit
/// side read.
mod field {
    use crate::wire::Field;

    /// Header byte, [`HEADER`](super::HEADER).
    pub const HEADER: usize = 0;
    /// VerLen byte, [`VER_LEN`](super::VER_LEN).
    pub const VER_LEN: usize = 1;
    /// Rotation speed, degrees per second.
    pub const SPEED: Field = 2..4;
    /// Start angle, hundredths of a degree.
    pub const START_ANGLE: Field = 4..6;
    /// The twelve samples, [`sample::LEN`] bytes each.
    pub const SAMPLES: Field = 6..42;
    /// End angle, hundredths of a degree.
    pub const END_ANGLE: Field = 42..44;
    /// Timestamp, milliseconds.
    pub const TIMESTAMP: Field = 44..46;
    /// The bytes the CRC covers.
    pub const CHECKED: Field = 0..46;
    /// CRC-8 of [`CHECKED`].
    pub const CRC: usize = 46;

    /// One sample, within [`SAMPLES`].
    pub mod sample {
        use crate::wire::Field;

        /// Distance, millimetres.
        pub const DISTANCE: Field = 0..2;
        /// Intensity.
        pub const INTENSITY: usize = 2;
        /// Bytes per sample.
        pub const LEN: usize = 3;
    }
}

// The table covers the frame exactly, header to CRC.
const _: () = {
    assert!(field::HEADER == 0 && field::VER_LEN == 1 && field::SPEED.start == 2);
    assert!(field::SPEED.end == field::START_ANGLE.start);
    assert!(field::START_ANGLE.end == field::SAMPLES.start);
    assert!(wire::len(&field::SAMPLES) == POINTS_PER_FRAME * field::sample::LEN);
    assert!(field::SAMPLES.end == field::END_ANGLE.start);
    assert!(field::END_ANGLE.end == field::TIMESTAMP.start);
    assert!(field::TIMESTAMP.end == field::CRC && field::CHECKED.end == field::CRC);
    assert!(field::CRC + 1 == FRAME_LEN);
    assert!(wire::len(&field::sample::DISTANCE) == 2);
    assert!(field::sample::INTENSITY + 1 == field::sample::LEN);
};

/// The frame header, `0x54 0x2C`, for the shared header hunt.
#[derive(Clone, Copy, Debug)]
struct Ld06Header;

impl Header for Ld06Header {
    const FIRST: u8 = HEADER;
    #[inline(always)]
    fn second(byte: u8) -> bool {
        byte == VER_LEN
    }
}

/// Why a 47-byte frame was rejected by [`Ld06Frame::parse`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Ld06Error {
    /// Fewer than [`FRAME_LEN`] bytes.
    Truncated(usize),
    /// The first two bytes are not `0x54 0x2C`.
    BadHeader,
    /// The CRC-8 does not match.
    BadChecksum {
        /// CRC carried by the frame.
        carried: u8,
        /// CRC computed over bytes 0..46.
        computed: u8,
    },
    /// A start or end angle ≥ 360°.
    AngleOutOfRange,
    /// The CRC passed but the frame is not one the sensor can send: its rotation speed is outside
    /// 5–13 Hz or its span is wider than twelve points cover at that speed
    /// ([`Ld06Frame::is_plausible`]).
    Implausible {
        /// Rotation speed carried, degrees per second.
        speed_deg_per_s: u16,
        /// Span from the start to the end angle, hundredths of a degree.
        span_cdeg: u16,
    },
}

impl core::fmt::Display for Ld06Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Truncated(n) => write!(f, "frame truncated at {n} bytes"),
            Self::BadHeader => f.write_str("frame does not start with 0x54 0x2c"),
            Self::BadChecksum { carried, computed } => {
                write!(f, "crc {carried:#04x} carried, {computed:#04x} computed")
            }
            Self::AngleOutOfRange => f.write_str("angle of 360 degrees or more"),
            Self::Implausible {
                speed_deg_per_s,
                span_cdeg,
            } => write!(
                f,
                "implausible frame: span of {span_cdeg} hundredths of a degree at {speed_deg_per_s} degrees per second"
            ),
        }
    }
}

impl core::error::Error for Ld06Error {}

impl Ld06Error {
    /// What the rejection means for the stream (see [`Verdict`]).
    #[inline(always)]
    const fn verdict(self) -> Verdict {
        match self {
            // The decoder only judges whole frames that open with the header: these two
            // arise from `parse` alone, and mean the bytes are not a frame.
            Self::Truncated(_) | Self::BadHeader | Self::BadChecksum { .. } => Verdict::BadChecksum,
            Self::AngleOutOfRange => Verdict::Impossible,
            Self::Implausible { .. } => Verdict::Implausible,
        }
    }
}

/// The `u16` at `field` of a frame.
#[inline(always)]
fn u16_at(b: &[u8; FRAME_LEN], field: Field) -> u16 {
    wire::get_u16(b, field)
}
