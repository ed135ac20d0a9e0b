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

use super::sync::HeaderHunt;
use super::{bump, range_units, room, DecoderStats, EncodeError, LidarPoint};
use crc::{Algorithm, Crc};

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

const CRC8: Crc<u8> = Crc::<u8>::new(&CRC_8_LD06);

/// The LD06 CRC-8 of `bytes`.
pub fn crc8(bytes: &[u8]) -> u8 {
    CRC8.checksum(bytes)
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

/// One measurement of a frame, as transmitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ld06Sample {
    /// Distance, millimetres; 0 means no measurement.
    pub distance_mm: u16,
    /// Intensity (signal strength), 0..=255.
    pub intensity: u8,
}

impl Ld06Sample {
    /// The sample an LD06 would send for a range (metres): the distance rounded to the
    /// millimetre; 0 ("no measurement") for NaN, negative, or anything that rounds to 0 mm or
    /// past 65,535 mm.
    pub fn from_range_m(range_m: f32, intensity: u8) -> Self {
        let distance_mm = range_units(range_m, 1000.0, u16::MAX);
        Self {
            distance_mm,
            intensity: if distance_mm == 0 { 0 } else { intensity },
        }
    }
}

/// One frame's fields, in the protocol's units.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ld06Frame {
    /// Rotation speed, degrees per second (3,600 is 10 revolutions per second).
    pub speed_deg_per_s: u16,
    /// Angle of the first point, hundredths of a degree clockwise, `< 36,000`.
    pub start_angle_cdeg: u16,
    /// The twelve measurements, in clockwise order.
    pub samples: [Ld06Sample; POINTS_PER_FRAME],
    /// Angle of the last point, hundredths of a degree clockwise, `< 36,000`.
    pub end_angle_cdeg: u16,
    /// Timestamp, milliseconds (wraps at [`TIMESTAMP_WRAP_MS`]).
    pub timestamp_ms: u16,
}

fn le16(lo: u8, hi: u8) -> u16 {
    u16::from_le_bytes([lo, hi])
}

impl Ld06Frame {
    /// Parses and checks one frame: header, CRC, angle ranges, then plausibility.
    ///
    /// # Errors
    /// [`Ld06Error::Truncated`], [`Ld06Error::BadHeader`], [`Ld06Error::BadChecksum`],
    /// [`Ld06Error::AngleOutOfRange`], [`Ld06Error::Implausible`].
    pub fn parse(bytes: &[u8]) -> Result<Self, Ld06Error> {
        let b: &[u8; FRAME_LEN] = bytes
            .get(..FRAME_LEN)
            .and_then(|s| s.try_into().ok())
            .ok_or(Ld06Error::Truncated(bytes.len()))?;
        Self::parse_array(b)
    }

    fn parse_array(b: &[u8; FRAME_LEN]) -> Result<Self, Ld06Error> {
        if b[0] != HEADER || b[1] != VER_LEN {
            return Err(Ld06Error::BadHeader);
        }
        let computed = crc8(b.get(..FRAME_LEN - 1).unwrap_or(&[]));
        let carried = b[FRAME_LEN - 1];
        if computed != carried {
            return Err(Ld06Error::BadChecksum { carried, computed });
        }
        let frame = Self::fields(b);
        if frame.start_angle_cdeg >= FULL_TURN_CDEG || frame.end_angle_cdeg >= FULL_TURN_CDEG {
            return Err(Ld06Error::AngleOutOfRange);
        }
        if !frame.is_plausible() {
            return Err(Ld06Error::Implausible {
                speed_deg_per_s: frame.speed_deg_per_s,
                span_cdeg: frame.span_cdeg(),
            });
        }
        Ok(frame)
    }

    /// The widest span from the start to the end angle a frame can have at `speed_deg_per_s`,
    /// hundredths of a degree: twelve sample periods at [`SAMPLE_RATE_FLOOR_HZ`], and half as
    /// much again for the speed's variation within a frame (the slack LDROBOT's own drivers
    /// allow), i.e. `1.5 · 12 · speed / 2,250` degrees, `0.8 · speed` hundredths of a degree
    /// (37.44° at [`MAX_SPEED_DEG_PER_S`]). The true span is 11 sample periods.
    pub const fn max_span_cdeg(speed_deg_per_s: u16) -> u32 {
        // 100 · 1.5 · 12 · speed / rate, in integers.
        speed_deg_per_s as u32 * (100 * 3 * POINTS_PER_FRAME as u32) / (2 * SAMPLE_RATE_FLOOR_HZ)
    }

    /// True when the frame is one the sensor can send: speed within [`MIN_SPEED_DEG_PER_S`]
    /// ..= [`MAX_SPEED_DEG_PER_S`] and [`Ld06Frame::span_cdeg`] at most
    /// [`Ld06Frame::max_span_cdeg`] of that speed. Angles are assumed `< 36,000` (checked
    /// before).
    #[inline]
    pub fn is_plausible(&self) -> bool {
        let v = self.speed_deg_per_s;
        // span ≤ max_span_cdeg(v) without the division: 2 · rate · span ≤ 3,600 · v.
        (MIN_SPEED_DEG_PER_S..=MAX_SPEED_DEG_PER_S).contains(&v)
            && 2 * SAMPLE_RATE_FLOOR_HZ * u32::from(self.span_cdeg())
                <= 100 * 3 * POINTS_PER_FRAME as u32 * u32::from(v)
    }

    /// Reads the fields without any check.
    fn fields(b: &[u8; FRAME_LEN]) -> Self {
        let mut samples = [Ld06Sample::default(); POINTS_PER_FRAME];
        let raw = b.get(6..42).unwrap_or(&[]);
        for (s, c) in samples.iter_mut().zip(raw.chunks_exact(3)) {
            if let [lo, hi, intensity] = *c {
                *s = Ld06Sample {
                    distance_mm: le16(lo, hi),
                    intensity,
                };
            }
        }
        Self {
            speed_deg_per_s: le16(b[2], b[3]),
            start_angle_cdeg: le16(b[4], b[5]),
            samples,
            end_angle_cdeg: le16(b[42], b[43]),
            timestamp_ms: le16(b[44], b[45]),
        }
    }

    /// Writes the frame, CRC included, into `out[..FRAME_LEN]`; returns [`FRAME_LEN`].
    ///
    /// Fields are written as given (an angle ≥ 360° is written too, so tests can build frames
    /// the decoder must reject).
    ///
    /// # Errors
    /// [`EncodeError::BufferTooSmall`] when `out` is shorter than [`FRAME_LEN`].
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        let given = out.len();
        let o: &mut [u8; FRAME_LEN] = out
            .get_mut(..FRAME_LEN)
            .and_then(|s| s.try_into().ok())
            .ok_or(EncodeError::BufferTooSmall {
                needed: FRAME_LEN,
                given,
            })?;
        o[0] = HEADER;
        o[1] = VER_LEN;
        [o[2], o[3]] = self.speed_deg_per_s.to_le_bytes();
        [o[4], o[5]] = self.start_angle_cdeg.to_le_bytes();
        if let Some(raw) = o.get_mut(6..42) {
            for (c, s) in raw.chunks_exact_mut(3).zip(self.samples.iter()) {
                let [lo, hi] = s.distance_mm.to_le_bytes();
                c.copy_from_slice(&[lo, hi, s.intensity]);
            }
        }
        [o[42], o[43]] = self.end_angle_cdeg.to_le_bytes();
        [o[44], o[45]] = self.timestamp_ms.to_le_bytes();
        o[FRAME_LEN - 1] = crc8(o.get(..FRAME_LEN - 1).unwrap_or(&[]));
        Ok(FRAME_LEN)
    }

    /// The span from the start to the end angle, hundredths of a degree, in `[0, 36,000)`
    /// (clockwise, across 0° when the end angle is smaller than the start angle).
    pub fn span_cdeg(&self) -> u16 {
        let (s, e) = (self.start_angle_cdeg, self.end_angle_cdeg);
        if e >= s {
            e - s
        } else {
            // e < s < 36,000 in a checked frame, so this neither overflows nor wraps.
            (FULL_TURN_CDEG - s).wrapping_add(e)
        }
    }

    /// Hands the 12 points to `on_point`, in order: the same values as [`Ld06Frame::point`],
    /// with the angle stepped instead of recomputed.
    #[inline]
    pub fn points(&self, on_point: &mut impl FnMut(LidarPoint)) {
        let step = POINTS_PER_FRAME as u32 - 1;
        let full = u32::from(FULL_TURN_CDEG) * step;
        let span = u32::from(self.span_cdeg());
        let mut a = u32::from(self.start_angle_cdeg) * step;
        let scale = 1.0 / (100.0 * step as f32);
        for s in &self.samples {
            on_point(LidarPoint {
                angle_cw_deg: a as f32 * scale,
                range_m: f32::from(s.distance_mm) * 0.001,
                quality: u16::from(s.intensity),
                valid: s.distance_mm != 0,
                timestamp_ms: Some(self.timestamp_ms),
            });
            a += span;
            if a >= full {
                a -= full;
            }
        }
    }

    /// Point `i` (`< 12`) of the frame: its angle interpolated between the start and end angles.
    ///
    /// The angle is computed in integers of 1/1,100 degree (`start · 11 + span · i`, reduced
    /// modulo 360°), then converted once, so a frame with whole-degree angles gives exact
    /// whole-degree points.
    pub fn point(&self, i: usize) -> LidarPoint {
        let s = self.samples.get(i).copied().unwrap_or_default();
        let step = POINTS_PER_FRAME as u32 - 1;
        let full = u32::from(FULL_TURN_CDEG) * step;
        let mut a =
            u32::from(self.start_angle_cdeg) * step + u32::from(self.span_cdeg()) * i as u32;
        if a >= full {
            a -= full;
        }
        LidarPoint {
            angle_cw_deg: a as f32 * (1.0 / (100.0 * step as f32)),
            range_m: f32::from(s.distance_mm) * 0.001,
            quality: u16::from(s.intensity),
            valid: s.distance_mm != 0,
            timestamp_ms: Some(self.timestamp_ms),
        }
    }
}

/// Byte-at-a-time LD06 stream decoder. See the module docs for the frame and the resync rule.
#[derive(Clone, Debug)]
pub struct Ld06Decoder {
    hunt: HeaderHunt<FRAME_LEN>,
    last: Option<Ld06Frame>,
}

impl Default for Ld06Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Ld06Decoder {
    /// A decoder waiting for a frame header.
    pub const fn new() -> Self {
        Self {
            hunt: HeaderHunt::new(),
            last: None,
        }
    }

    /// Feeds received bytes; `on_point` is called for each of the 12 points of every frame
    /// whose CRC passed and whose content is valid and plausible, in order, as soon as the
    /// frame's last byte arrives.
    ///
    /// Inside a frame the bytes are copied in one block, not pushed one by one: the per-byte work
    /// is the copy, the CRC and the share of the frame's 12 points.
    pub fn feed(&mut self, bytes: &[u8], mut on_point: impl FnMut(LidarPoint)) {
        let mut rest = bytes;
        while !rest.is_empty() {
            let h = &mut self.hunt;
            if h.len >= 2 {
                let take = (FRAME_LEN - h.len).min(rest.len());
                let (head, tail) = rest.split_at(take);
                if let Some(dst) = h.buf.get_mut(h.len..h.len + take) {
                    dst.copy_from_slice(head);
                }
                h.counter.stats.bytes = h.counter.stats.bytes.saturating_add(take as u32);
                h.len += take;
                rest = tail;
                if h.len == FRAME_LEN {
                    self.complete(&mut on_point);
                }
            } else if let Some((&b, tail)) = rest.split_first() {
                self.push_byte(b, &mut on_point);
                rest = tail;
            }
        }
    }

    /// Feeds one byte (see [`Ld06Decoder::feed`]).
    #[inline]
    pub fn push_byte(&mut self, byte: u8, on_point: &mut impl FnMut(LidarPoint)) {
        if self.hunt.push(byte, HEADER, |b| b == VER_LEN) {
            self.complete(on_point);
        }
    }

    fn complete(&mut self, on_point: &mut impl FnMut(LidarPoint)) {
        // The header is known good (the decoder only buffers after `0x54 0x2C`): check the CRC
        // in place, then build the frame once, where it is kept.
        let buf = &self.hunt.buf;
        let crc_ok = crc8(buf.get(..FRAME_LEN - 1).unwrap_or(&[])) == buf[FRAME_LEN - 1];
        // 0: accepted; 1: whole but impossible (an angle ≥ 360°); 2: implausible; 3: bad CRC.
        let verdict = if crc_ok {
            let prev = self.last.take();
            let f = self.last.insert(Ld06Frame::fields(buf));
            let v = if f.start_angle_cdeg >= FULL_TURN_CDEG || f.end_angle_cdeg >= FULL_TURN_CDEG {
                1
            } else if f.is_plausible() {
                0
            } else {
                2
            };
            if v != 0 {
                // `last_frame` keeps the last frame that was accepted.
                self.last = prev;
            }
            v
        } else {
            3
        };
        let stats = &mut self.hunt.counter.stats;
        match verdict {
            0 => {
                bump(&mut stats.frames_ok);
                stats.points = stats.points.saturating_add(POINTS_PER_FRAME as u32);
                self.hunt.accept();
                if let Some(frame) = &self.last {
                    frame.points(on_point);
                }
            }
            1 => {
                // The CRC vouches for the bytes: the frame is whole, only its content is bad.
                bump(&mut stats.bad_frames);
                self.hunt.drop_frame();
            }
            v => {
                // A failed CRC, or a frame no sensor sends (most likely damage the CRC let
                // through, or a header met inside another frame): re-examine the rejected
                // bytes after the header and keep the first `0x54` that is followed by `0x2C`
                // (or that ends the buffer) as the start of the next frame.
                bump(if v == 2 {
                    &mut stats.implausible_frames
                } else {
                    &mut stats.bad_checksum
                });
                self.hunt.rehunt(HEADER, |b| b == VER_LEN);
            }
        }
    }

    /// The counters so far. `bytes == 47 · (frames_ok + bad_frames) + skipped_bytes +`
    /// [`Ld06Decoder::buffered`] always holds.
    pub fn stats(&self) -> DecoderStats {
        self.hunt.counter.stats
    }

    /// Bytes of a partial frame held, waiting for the rest.
    pub fn buffered(&self) -> usize {
        self.hunt.len
    }

    /// The last frame whose CRC passed (speed and timestamp included), if any.
    pub fn last_frame(&self) -> Option<&Ld06Frame> {
        self.last.as_ref()
    }

    /// Forgets any partial frame and zeroes the counters.
    pub fn reset(&mut self) {
        *self = Self::new();
    }
}

/// Bytes needed by [`encode_revolution`] for `samples` points.
pub const fn revolution_len(samples: usize) -> usize {
    samples / POINTS_PER_FRAME * FRAME_LEN
}

/// Writes one revolution as LD06 frames: `samples[k]` is the point at `k · 360° / len`
/// clockwise from 0°, twelve points per frame, in order.
///
/// The rotation speed field carries `speed_deg_per_s`; each frame's timestamp is
/// `start_timestamp_ms` plus the time the rotor takes to reach the frame's start angle at that
/// speed (rounded to the millisecond, wrapped at [`TIMESTAMP_WRAP_MS`]). Returns the bytes
/// written, [`revolution_len`]`(samples.len())`.
///
/// # Errors
/// [`EncodeError::BadSampleCount`] unless `samples.len()` is a positive multiple of 12 that
/// divides 36,000 (so every point lies on a whole hundredth of a degree: 360 points give 1°
/// steps, 480 give 0.75°); [`EncodeError::BufferTooSmall`].
pub fn encode_revolution(
    samples: &[Ld06Sample],
    speed_deg_per_s: u16,
    start_timestamp_ms: u16,
    out: &mut [u8],
) -> Result<usize, EncodeError> {
    let n = samples.len();
    if n == 0 || n % POINTS_PER_FRAME != 0 || usize::from(FULL_TURN_CDEG) % n != 0 {
        return Err(EncodeError::BadSampleCount(n));
    }
    let needed = revolution_len(n);
    let out = room(out, needed)?;
    let step_cdeg = u32::from(FULL_TURN_CDEG) / n as u32;
    for (f, (chunk, dst)) in samples
        .chunks_exact(POINTS_PER_FRAME)
        .zip(out.chunks_exact_mut(FRAME_LEN))
        .enumerate()
    {
        let start = f as u32 * POINTS_PER_FRAME as u32 * step_cdeg;
        let end = (start + (POINTS_PER_FRAME as u32 - 1) * step_cdeg) % u32::from(FULL_TURN_CDEG);
        let elapsed_ms = if speed_deg_per_s == 0 {
            0
        } else {
            // start [0.01°] / speed [°/s] · 1000 = start · 10 / speed, rounded.
            (start * 10 + u32::from(speed_deg_per_s) / 2) / u32::from(speed_deg_per_s)
        };
        let ts = (u32::from(start_timestamp_ms) + elapsed_ms) % u32::from(TIMESTAMP_WRAP_MS);
        let mut frame = Ld06Frame {
            speed_deg_per_s,
            start_angle_cdeg: start as u16,
            samples: [Ld06Sample::default(); POINTS_PER_FRAME],
            end_angle_cdeg: end as u16,
            timestamp_ms: ts as u16,
        };
        frame.samples.copy_from_slice(chunk);
        frame.emit(dst)?;
    }
    Ok(needed)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bit-by-bit CRC-8 (polynomial 0x4D, MSB first), independent of the `crc` crate's table.
    fn crc8_bitwise(bytes: &[u8]) -> u8 {
        let mut c = 0u8;
        for &b in bytes {
            c ^= b;
            for _ in 0..8 {
                c = if c & 0x80 != 0 {
                    (c << 1) ^ 0x4D
                } else {
                    c << 1
                };
            }
        }
        c
    }

    #[test]
    fn crc_matches_bitwise_definition_and_published_table_entries() {
        assert_eq!(crc8(b"123456789"), crc8_bitwise(b"123456789"));
        assert_eq!(crc8(b"123456789"), 0xC3);
        // LDROBOT's published table starts 0x00, 0x4d, 0x9a, 0xd7: the CRC of one byte 0..=3.
        for (b, want) in [(0u8, 0x00u8), (1, 0x4D), (2, 0x9A), (3, 0xD7)] {
            assert_eq!(crc8(&[b]), want);
        }
        for len in 0..64u8 {
            let v: Vec<u8> = (0..len).map(|i| i.wrapping_mul(37) ^ 0xA5).collect();
            assert_eq!(crc8(&v), crc8_bitwise(&v));
        }
    }

    fn sample_frame() -> Ld06Frame {
        let mut samples = [Ld06Sample::default(); 12];
        for (i, s) in samples.iter_mut().enumerate() {
            s.distance_mm = 1000 + i as u16 * 7;
            s.intensity = 200 - i as u8;
        }
        Ld06Frame {
            speed_deg_per_s: 3600,
            start_angle_cdeg: 35_500,
            samples,
            end_angle_cdeg: 600,
            timestamp_ms: 29_999,
        }
    }

    #[test]
    fn emit_then_parse_round_trips_and_layout_is_little_endian() {
        let f = sample_frame();
        let mut out = [0u8; 50];
        assert_eq!(f.emit(&mut out), Ok(FRAME_LEN));
        assert_eq!(&out[..6], &[0x54, 0x2C, 0x10, 0x0E, 0xAC, 0x8A]);
        assert_eq!(&out[6..9], &[0xE8, 0x03, 200]);
        assert_eq!(out[46], crc8_bitwise(&out[..46]));
        assert_eq!(Ld06Frame::parse(&out), Ok(f));
        assert_eq!(
            f.emit(&mut [0u8; 46]),
            Err(EncodeError::BufferTooSmall {
                needed: 47,
                given: 46
            })
        );
    }

    #[test]
    fn interpolation_wraps_across_zero() {
        // 355.00° .. 6.00°: span 11°, 1° per point; point 5 is at 360 → 0°.
        let f = sample_frame();
        assert_eq!(f.span_cdeg(), 1100);
        let want = [
            355.0, 356.0, 357.0, 358.0, 359.0, 0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0,
        ];
        for (i, w) in want.iter().enumerate() {
            let p = f.point(i);
            assert!((p.angle_cw_deg - w).abs() < 1e-4, "{i}: {}", p.angle_cw_deg);
            assert!((0.0..360.0).contains(&p.angle_cw_deg));
        }
        assert_eq!(f.point(3).timestamp_ms, Some(29_999));
        assert!((f.point(1).range_m - 1.007).abs() < 1e-6);
    }

    #[test]
    fn decoder_skips_garbage_and_rejects_bad_crc() {
        let f = sample_frame();
        let mut frame = [0u8; FRAME_LEN];
        f.emit(&mut frame).unwrap();
        let mut stream = vec![0x00, 0x54, 0x54, 0x11];
        stream.extend_from_slice(&frame);
        let mut bad = frame;
        bad[20] ^= 0x04;
        stream.extend_from_slice(&bad);
        stream.extend_from_slice(&frame[..30]); // truncated
        stream.extend_from_slice(&frame);
        let mut d = Ld06Decoder::new();
        let mut pts = Vec::new();
        d.feed(&stream, |p| pts.push(p));
        let s = d.stats();
        assert_eq!(s.frames_ok, 2);
        assert_eq!(pts.len(), 24);
        assert_eq!(s.bad_checksum, 2);
        assert_eq!(s.bytes as usize, stream.len());
        assert_eq!(
            s.bytes as usize,
            FRAME_LEN * (s.frames_ok + s.bad_frames) as usize
                + s.skipped_bytes as usize
                + d.buffered()
        );
        for p in &pts {
            assert_eq!(p.timestamp_ms, Some(29_999));
        }
    }

    #[test]
    fn block_feed_equals_byte_feed_and_points_equal_point() {
        let f = sample_frame();
        let mut pts = Vec::new();
        f.points(&mut |p| pts.push(p));
        assert_eq!(pts, (0..12).map(|i| f.point(i)).collect::<Vec<_>>());
        let mut frame = [0u8; FRAME_LEN];
        f.emit(&mut frame).unwrap();
        let mut stream = vec![0x54, 0x01, 0x54];
        for _ in 0..5 {
            stream.extend_from_slice(&frame);
            stream.extend_from_slice(&frame[..13]);
        }
        for piece in [1usize, 2, 5, 46, 47, 48, 1000] {
            let mut a = Ld06Decoder::new();
            let mut got = Vec::new();
            for c in stream.chunks(piece) {
                a.feed(c, |p| got.push(p));
            }
            let mut b = Ld06Decoder::new();
            let mut want = Vec::new();
            for &x in &stream {
                b.push_byte(x, &mut |p| want.push(p));
            }
            assert_eq!(got, want, "pieces of {piece}");
            assert_eq!(a.stats(), b.stats());
            assert_eq!(a.buffered(), b.buffered());
        }
    }

    #[test]
    fn angle_out_of_range_with_good_crc_is_counted_not_emitted() {
        let mut f = sample_frame();
        f.end_angle_cdeg = 36_000;
        let mut frame = [0u8; FRAME_LEN];
        f.emit(&mut frame).unwrap();
        let mut d = Ld06Decoder::new();
        let mut n = 0;
        d.feed(&frame, |_| n += 1);
        assert_eq!((n, d.stats().bad_frames, d.stats().frames_ok), (0, 1, 0));
        // `last_frame` keeps only accepted frames.
        assert!(d.last_frame().is_none());
        let good = sample_frame();
        let mut g = [0u8; FRAME_LEN];
        good.emit(&mut g).unwrap();
        d.feed(&g, |_| n += 1);
        d.feed(&frame, |_| n += 1);
        assert_eq!(d.last_frame(), Some(&good));
        assert_eq!(n, 12);
    }

    fn frame_bytes(f: &Ld06Frame) -> [u8; FRAME_LEN] {
        let mut b = [0u8; FRAME_LEN];
        f.emit(&mut b).unwrap();
        b
    }

    fn with(speed_deg_per_s: u16, start_angle_cdeg: u16, end_angle_cdeg: u16) -> Ld06Frame {
        Ld06Frame {
            speed_deg_per_s,
            start_angle_cdeg,
            end_angle_cdeg,
            ..sample_frame()
        }
    }

    /// Decodes `bytes` in one call: (points, stats, the byte accounting holds).
    fn decode(bytes: &[u8]) -> (Vec<LidarPoint>, DecoderStats, Option<Ld06Frame>) {
        let mut d = Ld06Decoder::new();
        let mut pts = Vec::new();
        d.feed(bytes, |p| pts.push(p));
        let s = d.stats();
        assert_eq!(
            s.bytes as usize,
            FRAME_LEN * (s.frames_ok + s.bad_frames) as usize
                + s.skipped_bytes as usize
                + d.buffered()
        );
        (pts, s, d.last_frame().copied())
    }

    #[test]
    fn span_bound_is_twelve_samples_at_2250_hz_plus_half() {
        // 1.5 · 12 · v / 2,250 degrees, by hand: 3,600 °/s → 28.8°; 4,680 °/s → 37.44°;
        // 1,800 °/s → 14.4°; 2,152 °/s → 17.216° (rounded down to the hundredth).
        assert_eq!(Ld06Frame::max_span_cdeg(3600), 2880);
        assert_eq!(Ld06Frame::max_span_cdeg(4680), 3744);
        assert_eq!(Ld06Frame::max_span_cdeg(1800), 1440);
        assert_eq!(Ld06Frame::max_span_cdeg(2152), 1721);
    }

    #[test]
    fn plausibility_limits_on_speed_and_span() {
        // (speed, start, end, plausible)
        for (v, a, b, want) in [
            (3600, 1000, 3880, true),    // span 28.80°, the bound
            (3600, 1000, 3881, false),   // 28.81°
            (3600, 35_000, 1880, true),  // 350° → 18.8°, across 0°: 28.80°
            (3600, 35_000, 1881, false), // 28.81° across 0°
            (1800, 0, 1100, true),       // the slowest speed
            (1799, 0, 1100, false),
            (4680, 0, 1100, true), // the fastest
            (4681, 0, 1100, false),
            (0, 0, 0, false),
            (u16::MAX, 0, 1100, false),
            (3600, 10_000, 9_999, false), // 359.99°: the end just behind the start
        ] {
            let f = with(v, a, b);
            assert_eq!(f.is_plausible(), want, "{v} °/s, {a} → {b}");
            let parsed = Ld06Frame::parse(&frame_bytes(&f));
            if want {
                assert_eq!(parsed, Ok(f));
            } else {
                assert_eq!(
                    parsed,
                    Err(Ld06Error::Implausible {
                        speed_deg_per_s: v,
                        span_cdeg: f.span_cdeg()
                    })
                );
            }
        }
    }

    #[test]
    fn crc_valid_frame_with_absurd_span_is_counted_and_yields_no_points() {
        let good = sample_frame();
        // 100° → 300°: twelve points over 200° at 10 Hz; the CRC is right.
        let absurd = with(3600, 10_000, 30_000);
        let mut stream = frame_bytes(&absurd).to_vec();
        let (pts, s, last) = decode(&stream);
        assert!(pts.is_empty());
        assert_eq!(
            (s.frames_ok, s.implausible_frames, s.bad_checksum),
            (0, 1, 0)
        );
        assert_eq!((s.bad_frames, s.points), (0, 0));
        assert_eq!(last, None);
        // A good frame after it is decoded, and `last_frame` is the good one.
        stream.extend_from_slice(&frame_bytes(&good));
        stream.extend_from_slice(&frame_bytes(&absurd));
        let (pts, s, last) = decode(&stream);
        assert_eq!(pts, (0..12).map(|i| good.point(i)).collect::<Vec<_>>());
        assert_eq!((s.frames_ok, s.implausible_frames), (1, 2));
        assert_eq!(last, Some(good));
        // A CRC-valid frame whose speed is out of range, with a normal span.
        let (pts, s, _) = decode(&frame_bytes(&with(20_000, 0, 1100)));
        assert!(pts.is_empty());
        assert_eq!(s.implausible_frames, 1);
    }

    #[test]
    fn implausible_window_gives_back_the_frame_that_starts_inside_it() {
        // A window that opens with `54 2C`, passes its CRC by chance and ends with the first 20
        // bytes of a good frame: its end angle is made of the good frame's bytes 15..17 (sample
        // 3's distance, 1,021 mm → 10.21°), its start is 200°, so its span is 170.21°.
        let good = sample_frame();
        let g = frame_bytes(&good);
        let k = 20;
        let mut w = [0u8; FRAME_LEN];
        w[..6].copy_from_slice(&[HEADER, VER_LEN, 0x10, 0x0E, 0x20, 0x4E]); // 3,600 °/s, 200°
        w[FRAME_LEN - k..].copy_from_slice(&g[..k]);
        // Choose byte 10 so the CRC over bytes 0..46 equals the byte at 46 (one value does: the
        // CRC of a fixed-length message is a bijection of any one of its bytes).
        let fit: Vec<u8> = (0..=255u8)
            .filter(|&x| {
                w[10] = x;
                crc8_bitwise(&w[..46]) == w[46]
            })
            .collect();
        assert_eq!(fit.len(), 1);
        w[10] = fit[0];
        let window = Ld06Frame::parse(&w);
        assert_eq!(
            window,
            Err(Ld06Error::Implausible {
                speed_deg_per_s: 3600,
                span_cdeg: 17_021
            })
        );
        assert!(!w[1..FRAME_LEN - k]
            .windows(2)
            .any(|p| p == [HEADER, VER_LEN]));
        let mut stream = w[..FRAME_LEN - k].to_vec();
        stream.extend_from_slice(&g);
        let (pts, s, last) = decode(&stream);
        assert_eq!(pts, (0..12).map(|i| good.point(i)).collect::<Vec<_>>());
        assert_eq!((s.frames_ok, s.implausible_frames), (1, 1));
        assert_eq!(s.skipped_bytes as usize, FRAME_LEN - k);
        assert_eq!(last, Some(good));
    }

    #[test]
    fn revolution_encoder_lays_out_whole_degrees() {
        let samples: Vec<Ld06Sample> = (0..360)
            .map(|k| Ld06Sample {
                distance_mm: k as u16 + 1,
                intensity: 100,
            })
            .collect();
        let mut out = vec![0u8; revolution_len(360)];
        assert_eq!(
            encode_revolution(&samples, 3600, 100, &mut out),
            Ok(30 * 47)
        );
        let mut d = Ld06Decoder::new();
        let mut pts = Vec::new();
        d.feed(&out, |p| pts.push(p));
        assert_eq!(pts.len(), 360);
        for (k, p) in pts.iter().enumerate() {
            assert!(
                (p.angle_cw_deg - k as f32).abs() < 1e-3,
                "{k}: {}",
                p.angle_cw_deg
            );
            assert!((p.range_m - (k as f32 + 1.0) * 1e-3).abs() < 1e-7);
        }
        // Frame 15 starts at 180°: half a turn at 3,600 °/s is 50 ms after frame 0.
        assert_eq!(pts[180].timestamp_ms, Some(150));
        assert_eq!(
            encode_revolution(&samples[..350], 3600, 0, &mut out),
            Err(EncodeError::BadSampleCount(350))
        );
    }
}
