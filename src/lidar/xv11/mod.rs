//! Neato XV-11 / Xiaomi LDS02RR packets (firmware 2.4 and later): decoder and encoder.
//!
//! Protocol as reverse-engineered and published by the XV-11 hacking community (the "LIDAR
//! Sensor" page of the xv11hacking wiki, "data format for firmware v2.4"; the same layout is
//! read by the ROS `xv_11_laser_driver`). A packet is [`PACKET_LEN`] = 22 bytes, multi-byte
//! fields little-endian:
//!
//! | offset | bytes | field |
//! |---:|---:|---|
//! | 0 | 1 | start byte [`START`] = `0xFA` |
//! | 1 | 1 | index `0xA0..=0xF9`: packet `index − 0xA0` of the 90 of a turn |
//! | 2 | 2 | rotation speed, rpm × 64 |
//! | 4 | 16 | 4 readings: byte 0–1 = distance mm (14 bits), bit 15 "invalid data", bit 14 "strength warning"; bytes 2–3 = signal strength |
//! | 20 | 2 | checksum |
//!
//! Reading `j` of packet `i` is at `4·i + j` degrees, clockwise (ROS drivers store it at
//! `359 − angle` in their counter-clockwise scans). When the invalid flag is set the distance
//! bits carry an error code: such readings are emitted with `valid == false`.
//!
//! Checksum ([`checksum`]): read the first 20 bytes as ten little-endian 16-bit words `w`;
//! `c = 0; for each w: c = 2·c + w` (in 32 bits); then `((c & 0x7FFF) + (c >> 15)) & 0x7FFF`.
//!
//! The decoder waits for `0xFA` followed by a valid index byte. After a failed checksum it looks
//! for the next such pair inside the rejected bytes. Parse and emit place every field through
//! the one table `field`; the decoder's packet check returns a verdict that the shared header
//! hunt (`src/lidar/sync.rs`) settles (it counts, skips and resynchronises); the decoder is in
//! `decoder.rs`.

use super::sync::{Header, Verdict};
use super::{range_units, room, EncodeError, LidarPoint};
use crate::wire;

mod decoder;
#[cfg(test)]
mod tests;

pub use decoder::Xv11Decoder;

/// Start byte of a packet.
pub const START: u8 = 0xFA;
/// Index byte of the first packet of a turn.
pub const FIRST_INDEX: u8 = 0xA0;
/// Packets per turn.
pub const PACKETS_PER_TURN: usize = 90;
/// Bytes per packet.
pub const PACKET_LEN: usize = 22;
/// Readings per packet.
pub const READINGS_PER_PACKET: usize = 4;
/// Largest distance the 14-bit field carries, millimetres.
pub const MAX_DISTANCE_MM: u16 = 0x3FFF;

/// Where each field of a packet lies (offsets in bytes): the one table the parse and the emit
/// side read.
mod field {
    use crate::wire::Field;

    /// Start byte, [`START`](super::START).
    pub const START: usize = 0;
    /// Index byte, `0xA0 + packet`.
    pub const INDEX: usize = 1;
    /// Rotation speed, rpm × 64.
    pub const SPEED: Field = 2..4;
    /// The four readings, [`reading::LEN`] bytes each.
    pub const READINGS: Field = 4..20;
    /// The bytes the checksum covers (as ten 16-bit words).
    pub const CHECKED: Field = 0..20;
    /// Checksum of [`CHECKED`].
    pub const CHECKSUM: Field = 20..22;

    /// One reading, within [`READINGS`].
    pub mod reading {
        use crate::wire::Field;

        /// Distance (the low 14 bits) and the flags (the top 2 bits), one `u16`.
        pub const DISTANCE: Field = 0..2;
        /// Signal strength.
        pub const STRENGTH: Field = 2..4;
        /// Bytes per reading.
        pub const LEN: usize = 4;
        /// The distance bits of [`DISTANCE`].
        pub const DISTANCE_MASK: u16 = 0x3FFF;
        /// "Invalid data": the distance bits are an error code.
        pub const INVALID: u16 = 0x8000;
        /// "Strength warning".
        pub const STRENGTH_WARNING: u16 = 0x4000;
    }
}

// The table covers the packet exactly.
const _: () = {
    assert!(field::START == 0 && field::INDEX == 1 && field::SPEED.start == 2);
    assert!(field::SPEED.end == field::READINGS.start);
    assert!(wire::len(&field::READINGS) == READINGS_PER_PACKET * field::reading::LEN);
    assert!(
        field::READINGS.end == field::CHECKSUM.start && field::CHECKED.end == field::CHECKSUM.start
    );
    assert!(field::CHECKSUM.end == PACKET_LEN);
    assert!(field::reading::STRENGTH.end == field::reading::LEN);
};

/// The packet checksum of the first 20 bytes of `packet` (see the module docs).
pub fn checksum(packet: &[u8]) -> u16 {
    let mut c: u32 = 0;
    for w in packet.get(field::CHECKED).unwrap_or(&[]).chunks_exact(2) {
        if let [lo, hi] = *w {
            c = (c << 1).wrapping_add(u32::from(u16::from_le_bytes([lo, hi])));
        }
    }
    (((c & 0x7FFF) + (c >> 15)) & 0x7FFF) as u16
}

fn is_index(b: u8) -> bool {
    (FIRST_INDEX..FIRST_INDEX + PACKETS_PER_TURN as u8).contains(&b)
}

/// The packet header, `0xFA` and an index byte, for the shared header hunt.
#[derive(Clone, Copy, Debug)]
struct Xv11Header;

impl Header for Xv11Header {
    const FIRST: u8 = START;
    #[inline(always)]
    fn second(byte: u8) -> bool {
        is_index(byte)
    }
}

/// Why a packet was rejected by [`Xv11Packet::parse`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Xv11Error {
    /// Fewer than [`PACKET_LEN`] bytes.
    Truncated(usize),
    /// No `0xFA` start byte.
    BadStart,
    /// The checksum does not match.
    BadChecksum {
        /// Checksum carried by the packet.
        carried: u16,
        /// Checksum computed over bytes 0..20.
        computed: u16,
    },
    /// An index byte outside `0xA0..=0xF9` (with a good checksum).
    BadIndex(u8),
}

impl core::fmt::Display for Xv11Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Truncated(n) => write!(f, "packet truncated at {n} bytes"),
            Self::BadStart => f.write_str("packet does not start with 0xfa"),
            Self::BadChecksum { carried, computed } => {
                write!(
                    f,
                    "checksum {carried:#06x} carried, {computed:#06x} computed"
                )
            }
            Self::BadIndex(i) => write!(f, "index byte {i:#04x} outside 0xa0..=0xf9"),
        }
    }
}

impl core::error::Error for Xv11Error {}

impl Xv11Error {
    /// What the rejection means for the stream (see [`Verdict`]).
    #[inline(always)]
    const fn verdict(self) -> Verdict {
        match self {
            Self::Truncated(_) | Self::BadStart | Self::BadChecksum { .. } => Verdict::BadChecksum,
            // The hunt only buffers a packet after a valid index, so the decoder never meets
            // this one.
            Self::BadIndex(_) => Verdict::Impossible,
        }
    }
}

/// One reading, as transmitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Xv11Reading {
    /// Distance, millimetres (14 bits); an error code when `invalid`.
    pub distance_mm: u16,
    /// The sensor could not measure this angle.
    pub invalid: bool,
    /// The signal was weaker than expected (the distance is still reported).
    pub strength_warning: bool,
    /// Signal strength.
    pub strength: u16,
}

impl Xv11Reading {
    /// The reading an XV-11 would send for a range (metres): the distance rounded to the
    /// millimetre; NaN, negative, 0 mm and anything past 16,383 mm become an invalid reading
    /// (error code 0, strength 0).
    pub fn from_range_m(range_m: f32, strength: u16) -> Self {
        let distance_mm = range_units(range_m, 1000.0, MAX_DISTANCE_MM);
        if distance_mm != 0 {
            Self {
                distance_mm,
                invalid: false,
                strength_warning: false,
                strength,
            }
        } else {
            Self {
                distance_mm: 0,
                invalid: true,
                strength_warning: false,
                strength: 0,
            }
        }
    }
}

/// One packet's fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Xv11Packet {
    /// Packet number within the turn, `0..90` (sent as `0xA0 + packet`).
    pub packet: u8,
    /// Rotation speed, rpm × 64.
    pub speed_rpm_q6: u16,
    /// The four readings, at `4·packet + j` degrees.
    pub readings: [Xv11Reading; READINGS_PER_PACKET],
}

impl Xv11Packet {
    /// Parses and checks one packet: start byte, checksum, index.
    ///
    /// # Errors
    /// [`Xv11Error::Truncated`], [`Xv11Error::BadStart`], [`Xv11Error::BadChecksum`],
    /// [`Xv11Error::BadIndex`].
    pub fn parse(bytes: &[u8]) -> Result<Self, Xv11Error> {
        use field::reading;
        let b: &[u8; PACKET_LEN] = bytes
            .get(..PACKET_LEN)
            .and_then(|s| s.try_into().ok())
            .ok_or(Xv11Error::Truncated(bytes.len()))?;
        if b[field::START] != START {
            return Err(Xv11Error::BadStart);
        }
        let carried = wire::get_u16(b, field::CHECKSUM);
        let computed = checksum(b);
        if carried != computed {
            return Err(Xv11Error::BadChecksum { carried, computed });
        }
        let index = b[field::INDEX];
        if !is_index(index) {
            return Err(Xv11Error::BadIndex(index));
        }
        let mut readings = [Xv11Reading::default(); READINGS_PER_PACKET];
        let body = b.get(field::READINGS).unwrap_or(&[]);
        for (r, c) in readings.iter_mut().zip(body.chunks_exact(reading::LEN)) {
            let d = wire::get_u16(c, reading::DISTANCE);
            *r = Xv11Reading {
                distance_mm: d & reading::DISTANCE_MASK,
                invalid: d & reading::INVALID != 0,
                strength_warning: d & reading::STRENGTH_WARNING != 0,
                strength: wire::get_u16(c, reading::STRENGTH),
            };
        }
        Ok(Self {
            packet: index - FIRST_INDEX,
            speed_rpm_q6: wire::get_u16(b, field::SPEED),
            readings,
        })
    }

    /// Writes the packet, checksum included; returns [`PACKET_LEN`]. Distances are cut to 14
    /// bits; the packet number is written as `0xA0 + packet` (wrapping, so tests can build bad
    /// indices).
    ///
    /// # Errors
    /// [`EncodeError::BufferTooSmall`].
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        use field::reading;
        let o = room(out, PACKET_LEN)?;
        if let Some(start) = o.get_mut(field::START) {
            *start = START;
        }
        if let Some(index) = o.get_mut(field::INDEX) {
            *index = FIRST_INDEX.wrapping_add(self.packet);
        }
        wire::put_u16(o, field::SPEED, self.speed_rpm_q6);
        if let Some(body) = o.get_mut(field::READINGS) {
            for (c, r) in body
                .chunks_exact_mut(reading::LEN)
                .zip(self.readings.iter())
            {
                let mut d = r.distance_mm & reading::DISTANCE_MASK;
                if r.invalid {
                    d |= reading::INVALID;
                }
                if r.strength_warning {
                    d |= reading::STRENGTH_WARNING;
                }
                wire::put_u16(c, reading::DISTANCE, d);
                wire::put_u16(c, reading::STRENGTH, r.strength);
            }
        }
        wire::put_u16(o, field::CHECKSUM, checksum(o));
        Ok(PACKET_LEN)
    }

    /// Reading `j` (`< 4`) as a point at `4·packet + j` degrees clockwise.
    pub fn point(&self, j: usize) -> LidarPoint {
        let r = self.readings.get(j).copied().unwrap_or_default();
        let valid = !r.invalid && r.distance_mm != 0;
        LidarPoint {
            angle_cw_deg: f32::from(u16::from(self.packet) * 4 + j as u16),
            range_m: if valid {
                f32::from(r.distance_mm) * 0.001
            } else {
                0.0
            },
            quality: r.strength,
            valid,
            timestamp_ms: None,
        }
    }
}

/// Bytes of one turn (90 packets).
pub const REVOLUTION_LEN: usize = PACKETS_PER_TURN * PACKET_LEN;

/// Writes one turn: `readings[a]` at `a` degrees clockwise, 90 packets; returns
/// [`REVOLUTION_LEN`].
///
/// # Errors
/// [`EncodeError::BufferTooSmall`].
pub fn encode_revolution(
    readings: &[Xv11Reading; 360],
    speed_rpm_q6: u16,
    out: &mut [u8],
) -> Result<usize, EncodeError> {
    let out = room(out, REVOLUTION_LEN)?;
    for (p, (chunk, dst)) in readings
        .chunks_exact(READINGS_PER_PACKET)
        .zip(out.chunks_exact_mut(PACKET_LEN))
        .enumerate()
    {
        let mut pkt = Xv11Packet {
            packet: p as u8,
            speed_rpm_q6,
            readings: [Xv11Reading::default(); READINGS_PER_PACKET],
        };
        pkt.readings.copy_from_slice(chunk);
        pkt.emit(dst)?;
    }
    Ok(REVOLUTION_LEN)
}
