//! YDLIDAR X4 / X2 / G4 point-cloud packets (the "PH" `0x55AA` packets of the scan response):
//! decoder (byte-at-a-time) and encoder.
//!
//! Protocol as published by EAI / YDLIDAR in the *YDLIDAR X4 Development Manual* ("scan command"
//! response content, distance and angle analysis, check code parsing; the X2 and G4 manuals and
//! the *YDLidar-SDK Communication Protocol* document give the same layout). After the scan
//! command `A5 60` and its 7-byte answer `A5 5A 05 00 00 40 81`, the sensor streams packets of
//! [`HEADER_LEN`] + 2·LSN bytes, every 16-bit field little-endian:
//!
//! | offset | bytes | field |
//! |---:|---:|---|
//! | 0 | 2 | PH, packet header `0x55AA` (sent `AA 55`) |
//! | 2 | 1 | CT, packet type: bit 0 set on the zero packet that starts a revolution; on some models bits 7..1 of the zero packet carry the scan frequency of the previous revolution in 0.1 Hz |
//! | 3 | 1 | LSN, number of samples in the packet (1 in a zero packet) |
//! | 4 | 2 | FSA, angle of the first sample: bit 0 is a check bit (always 1), bits 15..1 the angle in 1/64° |
//! | 6 | 2 | LSA, angle of the last sample, same layout |
//! | 8 | 2 | CS, the XOR of every other 16-bit word of the packet (PH, CT·LSN, FSA, LSA, the samples) |
//! | 10 | 2·LSN | samples: distance in quarter millimetres (`Si / 4` mm); 0 means no measurement |
//!
//! **Angles** (clockwise). First level: sample `i` of `n` lies at `FSA + i·diff/(n − 1)`, where
//! `diff` is the clockwise difference from FSA to LSA, taken modulo 360°. Second level, for the
//! triangulation models (X4, X2, G4): a sample with distance `d` mm ≠ 0 is moved by
//! `atan(21.8·(155.3 − d)/(155.3·d))` degrees ([`angle_correction_deg`]); the result is wrapped
//! into `[0, 360)`. [`AngleCorrection::None`] reports the first-level angles instead.
//!
//! Implemented: the 2-byte samples of the X4 / X2 / G4 family, distance = `Si / 4` mm (the
//! sample's two low bits are the quarter millimetres, as the X4 manual reads them). Left out: the
//! 3-byte samples with an intensity byte (the models that send intensities), the TOF models'
//! distance in whole millimetres, the commands and the device-information and health answers
//! (a receiver that starts after the scan answer only sees packets; the decoder skips the 7-byte
//! answer as garbage).
//!
//! The decoder waits for `AA 55`, reads LSN from the fourth byte, buffers the whole packet and
//! the two bytes after it, and emits the packet's points only when CS passes **and** those two
//! bytes are the next packet's `AA 55` ([`YdlidarDecoder::flush`] takes the last packet of a
//! recording without them). The second rule is needed because a 16-bit XOR is weak against lost
//! bytes: a packet cut short and filled up by the start of the next one passes whenever the
//! filling bytes XOR to the missing ones, and an intact packet whose samples are all "no
//! measurement" XORs to 0 with its own check code (on the Intel log, 179 of 810 truncations of
//! one revolution's packets passed CS alone). A packet whose check code passes but whose check
//! bits are 0, whose angle is ≥ 360° or which has no sample is counted in `bad_frames`. A failed
//! check code or a missing next header counts in `bad_checksum`, and the decoder looks for the
//! next `AA 55` inside the rejected bytes (a header found in noise can announce up to 255 samples
//! and swallow the packets behind it; they are read again from the buffer).
//!
//! Files: this one holds the constants, the field table (`field`, read by both
//! [`YdlidarPacket::parse`] and [`emit_packet`]), the check code and the error type;
//! `packet.rs` the checked packet, its points and the encoders; `decoder.rs` the stream decoder,
//! whose packet check returns a verdict that the shared header hunt (`src/lidar/sync.rs`)
//! settles.

use super::sync::{Header, Verdict};
use crate::wire;

mod decoder;
mod packet;
#[cfg(test)]
mod tests;

pub use decoder::YdlidarDecoder;
pub use packet::{
    distance_q2_from_range_m, emit_packet, encode_revolution, revolution_len, YdlidarPacket,
};

/// First byte of a packet (the low byte of `0x55AA`).
pub const PH0: u8 = 0xAA;
/// Second byte of a packet.
pub const PH1: u8 = 0x55;
/// Bytes of a packet before its samples.
pub const HEADER_LEN: usize = field::SAMPLES.start;
/// Bytes per sample.
pub const SAMPLE_LEN: usize = field::sample::LEN;
/// Most samples a packet can carry (LSN is one byte).
pub const MAX_SAMPLES: usize = 255;
/// Bytes of the longest packet.
pub const MAX_PACKET_LEN: usize = HEADER_LEN + SAMPLE_LEN * MAX_SAMPLES;
/// A full turn in the angle fields' unit (360 · 64).
pub const FULL_TURN_Q6: u16 = 23_040;
/// The scan answer that precedes the packets: start sign `A5 5A`, continuous response, type
/// `0x81`.
pub const SCAN_ANSWER: [u8; 7] = [0xA5, 0x5A, 0x05, 0x00, 0x00, 0x40, 0x81];
/// Largest distance a sample carries, metres (65,535 quarter millimetres).
pub const MAX_RANGE_M: f32 = 16.383_75;

/// Bytes of a packet of `samples` samples.
pub const fn packet_len(samples: u8) -> usize {
    HEADER_LEN + SAMPLE_LEN * samples as usize
}

/// Where each field of a packet lies (offsets in bytes): the one table the parse and the emit
/// side read.
mod field {
    use crate::wire::{Field, Rest};

    /// PH, `AA 55`.
    pub const PH: Field = 0..2;
    /// CT, the packet type.
    pub const CT: usize = 2;
    /// LSN, the number of samples.
    pub const LSN: usize = 3;
    /// FSA: check bit and first angle.
    pub const FSA: Field = 4..6;
    /// LSA: check bit and last angle.
    pub const LSA: Field = 6..8;
    /// CS, the check code.
    pub const CS: Field = 8..10;
    /// The samples, [`sample::LEN`] bytes each, LSN of them.
    pub const SAMPLES: Rest = 10..;

    /// One sample, within [`SAMPLES`].
    pub mod sample {
        use crate::wire::Field;

        /// Distance, quarter millimetres.
        pub const DISTANCE: Field = 0..2;
        /// Bytes per sample.
        pub const LEN: usize = 2;
    }
}

// The table covers the header exactly, in 16-bit words (the check code is a XOR of words).
const _: () = {
    assert!(field::PH.start == 0 && field::PH.end == field::CT && field::CT + 1 == field::LSN);
    assert!(field::LSN + 1 == field::FSA.start && field::FSA.end == field::LSA.start);
    assert!(field::LSA.end == field::CS.start && field::CS.end == field::SAMPLES.start);
    assert!(field::CS.start % 2 == 0 && field::SAMPLES.start % 2 == 0);
    assert!(wire::len(&field::sample::DISTANCE) == field::sample::LEN);
};

/// The packet header, `AA 55`, for the shared header hunt.
#[derive(Clone, Copy, Debug)]
struct YdlidarHeader;

impl Header for YdlidarHeader {
    const FIRST: u8 = PH0;
    #[inline(always)]
    fn second(byte: u8) -> bool {
        byte == PH1
    }
}

/// Which second-level angle analysis the decoder applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AngleCorrection {
    /// The triangulation models' correction (X4, X2, G4): each measured sample is moved by
    /// [`angle_correction_deg`] of its distance.
    #[default]
    Triangulation,
    /// First-level angles only (interpolated between FSA and LSA).
    None,
}

/// The triangulation correction of the manual's second-level analysis, degrees, for a distance
/// in millimetres: 0 for 0 mm, else `atan(21.8·(155.3 − d)/(155.3·d))` (about −6.76° at 1 m,
/// tending to −7.99° far away, positive below 155.3 mm).
#[inline]
pub fn angle_correction_deg(distance_mm: f32) -> f32 {
    if distance_mm == 0.0 {
        0.0
    } else {
        libm::atanf(21.8 * (155.3 - distance_mm) / (155.3 * distance_mm))
            * (180.0 / core::f32::consts::PI)
    }
}

/// The check code of a packet: the XOR of its little-endian 16-bit words, the CS word (bytes
/// 8..10) left out. `packet` is the whole packet (an odd last byte is ignored).
pub fn checksum(packet: &[u8]) -> u16 {
    let mut cs = 0u16;
    for (k, w) in packet.chunks_exact(2).enumerate() {
        if let [lo, hi] = *w {
            if k != field::CS.start / 2 {
                cs ^= u16::from_le_bytes([lo, hi]);
            }
        }
    }
    cs
}

/// Why a packet was rejected by [`YdlidarPacket::parse`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum YdlidarError {
    /// Fewer bytes than the header or than LSN announces.
    Truncated(usize),
    /// The packet does not start with `AA 55`.
    BadHeader,
    /// The check code does not match.
    BadChecksum {
        /// Check code carried by the packet.
        carried: u16,
        /// Check code computed over the packet.
        computed: u16,
    },
    /// A check bit (bit 0 of FSA or LSA) is 0.
    BadCheckBit,
    /// A start or end angle ≥ 360°.
    AngleOutOfRange,
    /// A packet with LSN = 0.
    NoSamples,
}

impl core::fmt::Display for YdlidarError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Truncated(n) => write!(f, "packet truncated at {n} bytes"),
            Self::BadHeader => f.write_str("packet does not start with 0xaa 0x55"),
            Self::BadChecksum { carried, computed } => {
                write!(
                    f,
                    "check code {carried:#06x} carried, {computed:#06x} computed"
                )
            }
            Self::BadCheckBit => f.write_str("angle check bit is 0"),
            Self::AngleOutOfRange => f.write_str("angle of 360 degrees or more"),
            Self::NoSamples => f.write_str("packet without samples"),
        }
    }
}

impl core::error::Error for YdlidarError {}

impl YdlidarError {
    /// What the rejection means for the stream (see [`Verdict`]).
    #[inline(always)]
    const fn verdict(self) -> Verdict {
        match self {
            Self::Truncated(_) | Self::BadHeader | Self::BadChecksum { .. } => Verdict::BadChecksum,
            // The check code vouches for the bytes: a whole packet with impossible content.
            Self::BadCheckBit | Self::AngleOutOfRange | Self::NoSamples => Verdict::Impossible,
        }
    }
}
