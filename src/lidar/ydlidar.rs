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

use super::sync::HeaderHunt;
use super::{bump, range_units, room, DecoderStats, EncodeError, LidarPoint};

/// First byte of a packet (the low byte of `0x55AA`).
pub const PH0: u8 = 0xAA;
/// Second byte of a packet.
pub const PH1: u8 = 0x55;
/// Bytes of a packet before its samples.
pub const HEADER_LEN: usize = 10;
/// Bytes per sample.
pub const SAMPLE_LEN: usize = 2;
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

/// Bytes after a packet the decoder waits for (the next packet's header) before it takes it.
const LOOKAHEAD: usize = 2;

/// Bytes of a packet of `samples` samples.
pub const fn packet_len(samples: u8) -> usize {
    HEADER_LEN + SAMPLE_LEN * samples as usize
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
            if k != 4 {
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

/// One checked packet, its samples read in place from the received bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct YdlidarPacket<'a> {
    /// CT, the packet type byte (bit 0: zero packet).
    pub packet_type: u8,
    /// Angle of the first sample, 1/64 degree clockwise, `< 23,040` (FSA without its check bit).
    pub start_angle_q6: u16,
    /// Angle of the last sample, 1/64 degree clockwise, `< 23,040`.
    pub end_angle_q6: u16,
    /// The samples' bytes, 2 per sample.
    samples: &'a [u8],
}

impl<'a> YdlidarPacket<'a> {
    /// Parses and checks one packet at the start of `bytes`: header, length, check code, then
    /// check bits, angle ranges and sample count.
    ///
    /// # Errors
    /// [`YdlidarError::Truncated`], [`YdlidarError::BadHeader`], [`YdlidarError::BadChecksum`],
    /// [`YdlidarError::BadCheckBit`], [`YdlidarError::AngleOutOfRange`],
    /// [`YdlidarError::NoSamples`].
    pub fn parse(bytes: &'a [u8]) -> Result<Self, YdlidarError> {
        let truncated = YdlidarError::Truncated(bytes.len());
        let [h0, h1, ct, lsn, ..] = *bytes else {
            return Err(truncated);
        };
        if h0 != PH0 || h1 != PH1 {
            return Err(YdlidarError::BadHeader);
        }
        let b = bytes.get(..packet_len(lsn)).ok_or(truncated)?;
        let [_, _, _, _, f0, f1, l0, l1, c0, c1, samples @ ..] = b else {
            return Err(truncated);
        };
        let carried = u16::from_le_bytes([*c0, *c1]);
        let computed = checksum(b);
        if carried != computed {
            return Err(YdlidarError::BadChecksum { carried, computed });
        }
        let (fsa, lsa) = (
            u16::from_le_bytes([*f0, *f1]),
            u16::from_le_bytes([*l0, *l1]),
        );
        if fsa & 1 == 0 || lsa & 1 == 0 {
            return Err(YdlidarError::BadCheckBit);
        }
        if fsa >> 1 >= FULL_TURN_Q6 || lsa >> 1 >= FULL_TURN_Q6 {
            return Err(YdlidarError::AngleOutOfRange);
        }
        if lsn == 0 {
            return Err(YdlidarError::NoSamples);
        }
        Ok(Self {
            packet_type: ct,
            start_angle_q6: fsa >> 1,
            end_angle_q6: lsa >> 1,
            samples,
        })
    }

    /// Samples in the packet (LSN).
    pub fn sample_count(&self) -> usize {
        self.samples.len() / SAMPLE_LEN
    }

    /// Bytes of the packet.
    pub fn len_bytes(&self) -> usize {
        HEADER_LEN + self.samples.len()
    }

    /// The zero packet that opens a revolution (CT bit 0).
    pub fn is_start(&self) -> bool {
        self.packet_type & 1 != 0
    }

    /// The scan frequency a zero packet reports, 0.1 Hz (CT bits 7..1), when it reports one.
    pub fn scan_freq_decihz(&self) -> Option<u8> {
        let f = self.packet_type >> 1;
        (self.is_start() && f != 0).then_some(f)
    }

    /// Sample `i`'s raw value: distance in quarter millimetres (0 past the last sample).
    pub fn distance_q2(&self, i: usize) -> u16 {
        match self.samples.get(SAMPLE_LEN * i..SAMPLE_LEN * i + 2) {
            Some(&[lo, hi]) => u16::from_le_bytes([lo, hi]),
            _ => 0,
        }
    }

    /// The clockwise span from the first to the last sample, 1/64 degree, in `[0, 23,040)`.
    pub fn span_q6(&self) -> u16 {
        let (s, e) = (self.start_angle_q6, self.end_angle_q6);
        if e >= s {
            e - s
        } else {
            // e < s < 23,040 in a checked packet.
            (FULL_TURN_Q6 - s).wrapping_add(e)
        }
    }

    /// Sample `i` (`< LSN`) as a point: first-level angle interpolated between FSA and LSA (in
    /// integers of 1/(64·(LSN − 1)) degree, converted once), then `correction`, then wrapped into
    /// `[0, 360)`.
    pub fn point(&self, i: usize, correction: AngleCorrection) -> LidarPoint {
        let n = self.sample_count().max(1) as u32;
        let step = (n - 1).max(1);
        let full = u32::from(FULL_TURN_Q6) * step;
        let mut a = u32::from(self.start_angle_q6) * step + u32::from(self.span_q6()) * i as u32;
        if a >= full {
            a -= full;
        }
        let q2 = self.distance_q2(i);
        let range_m = f32::from(q2) * 0.000_25;
        let mut angle = a as f32 / (64 * step) as f32;
        if correction == AngleCorrection::Triangulation && q2 != 0 {
            angle = wrap_deg(angle + angle_correction_deg(f32::from(q2) * 0.25));
        }
        LidarPoint {
            angle_cw_deg: angle,
            range_m,
            quality: 0,
            valid: q2 != 0,
            timestamp_ms: None,
        }
    }

    /// Hands every sample to `on_point`, in order (the values of [`YdlidarPacket::point`]).
    #[inline]
    pub fn points(&self, correction: AngleCorrection, on_point: &mut impl FnMut(LidarPoint)) {
        for i in 0..self.sample_count() {
            on_point(self.point(i, correction));
        }
    }
}

/// `angle` (degrees, within one turn of `[0, 360)`) wrapped into `[0, 360)`.
fn wrap_deg(angle: f32) -> f32 {
    let mut a = angle;
    if a < 0.0 {
        a += 360.0;
    }
    if a >= 360.0 {
        a -= 360.0;
    }
    // -1e-6 + 360 rounds to 360.0 in f32.
    if (0.0..360.0).contains(&a) {
        a
    } else {
        0.0
    }
}

/// Writes one packet, check code included; returns its length, [`packet_len`]`(samples.len())`.
///
/// The angles (1/64 degree) are written with their check bits set, cut to 15 bits; CT is written
/// as given. An angle ≥ 360° is written too, so tests can build packets the decoder must reject.
///
/// # Errors
/// [`EncodeError::BadSampleCount`] for more than 255 samples; [`EncodeError::BufferTooSmall`].
pub fn emit_packet(
    packet_type: u8,
    start_angle_q6: u16,
    end_angle_q6: u16,
    samples_q2: &[u16],
    out: &mut [u8],
) -> Result<usize, EncodeError> {
    let lsn = u8::try_from(samples_q2.len())
        .map_err(|_| EncodeError::BadSampleCount(samples_q2.len()))?;
    let needed = packet_len(lsn);
    let o = room(out, needed)?;
    let [f0, f1] = ((start_angle_q6 << 1) | 1).to_le_bytes();
    let [l0, l1] = ((end_angle_q6 << 1) | 1).to_le_bytes();
    if let Some(head) = o.get_mut(..HEADER_LEN) {
        head.copy_from_slice(&[PH0, PH1, packet_type, lsn, f0, f1, l0, l1, 0, 0]);
    }
    if let Some(body) = o.get_mut(HEADER_LEN..) {
        for (c, s) in body.chunks_exact_mut(SAMPLE_LEN).zip(samples_q2) {
            c.copy_from_slice(&s.to_le_bytes());
        }
    }
    let [c0, c1] = checksum(o).to_le_bytes();
    if let Some(cs) = o.get_mut(8..10) {
        cs.copy_from_slice(&[c0, c1]);
    }
    Ok(needed)
}

/// A range (metres) as a sample: quarter millimetres, rounded; 0 ("no measurement") for NaN,
/// negative, or anything that rounds to 0 or past 65,535.
pub fn distance_q2_from_range_m(range_m: f32) -> u16 {
    range_units(range_m, 4000.0, u16::MAX)
}

/// Bytes needed by [`encode_revolution`] for `samples` samples, at most `per_packet` per cloud
/// packet.
pub const fn revolution_len(samples: usize, per_packet: usize) -> usize {
    if samples == 0 || per_packet == 0 {
        return 0;
    }
    let rest = samples - 1;
    packet_len(1) + HEADER_LEN * rest.div_ceil(per_packet) + SAMPLE_LEN * rest
}

/// Writes one revolution: `distances_q2[k]` measured at rotor angle `k · 360° / n` clockwise.
/// Sample 0 goes in a zero packet (CT = 1, with `scan_freq_decihz` in bits 7..1), the others in
/// cloud packets of at most `per_packet` samples, FSA and LSA their first and last rotor
/// angles. Returns the bytes written, [`revolution_len`]`(n, per_packet)`.
///
/// These are first-level angles: a triangulation model's decoder moves each measured sample by
/// [`angle_correction_deg`], as it would for the real sensor's rotor angles.
///
/// # Errors
/// [`EncodeError::BadSampleCount`] unless `n ≥ 2` divides 23,040 (every rotor angle a whole
/// 1/64 degree: 360 samples give 1° steps) and `per_packet` is in `1..=255`;
/// [`EncodeError::BufferTooSmall`].
pub fn encode_revolution(
    distances_q2: &[u16],
    per_packet: usize,
    scan_freq_decihz: u8,
    out: &mut [u8],
) -> Result<usize, EncodeError> {
    let n = distances_q2.len();
    if n < 2 || usize::from(FULL_TURN_Q6) % n != 0 || !(1..=MAX_SAMPLES).contains(&per_packet) {
        return Err(EncodeError::BadSampleCount(n));
    }
    let needed = revolution_len(n, per_packet);
    let given = out.len();
    let out = room(out, needed)?;
    let step = FULL_TURN_Q6 / n as u16;
    let (first, rest) = distances_q2
        .split_first()
        .ok_or(EncodeError::BadSampleCount(n))?;
    let mut at = emit_packet(1 | (scan_freq_decihz << 1), 0, 0, &[*first], out)?;
    for (p, chunk) in rest.chunks(per_packet).enumerate() {
        let k0 = 1 + p * per_packet;
        let start = k0 as u16 * step;
        let end = (k0 + chunk.len() - 1) as u16 * step;
        let dst = out
            .get_mut(at..)
            .ok_or(EncodeError::BufferTooSmall { needed, given })?;
        at += emit_packet(0, start, end, chunk, dst)?;
    }
    Ok(at)
}

/// Byte-at-a-time YDLIDAR packet decoder. See the module docs for the packet and the resync rule.
#[derive(Clone, Debug)]
pub struct YdlidarDecoder {
    hunt: HeaderHunt<{ MAX_PACKET_LEN + LOOKAHEAD }>,
    correction: AngleCorrection,
    frame_bytes: u32,
    start_packets: u32,
    scan_freq_decihz: Option<u8>,
}

impl Default for YdlidarDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl YdlidarDecoder {
    /// A decoder for the triangulation models (X4, X2, G4): angles corrected for distance.
    pub const fn new() -> Self {
        Self::with_correction(AngleCorrection::Triangulation)
    }

    /// A decoder applying `correction`.
    pub const fn with_correction(correction: AngleCorrection) -> Self {
        Self {
            hunt: HeaderHunt::new(),
            correction,
            frame_bytes: 0,
            start_packets: 0,
            scan_freq_decihz: None,
        }
    }

    /// Feeds received bytes; `on_point` is called for each sample of every packet whose check
    /// code passed and that is followed by the next packet's header, in order, as soon as those
    /// two bytes arrive (at the end of a recording, [`YdlidarDecoder::flush`] takes the last
    /// packet).
    pub fn feed(&mut self, bytes: &[u8], mut on_point: impl FnMut(LidarPoint)) {
        for &b in bytes {
            self.push_byte(b, &mut on_point);
        }
    }

    /// Feeds one byte (see [`YdlidarDecoder::feed`]).
    #[inline]
    pub fn push_byte(&mut self, byte: u8, on_point: &mut impl FnMut(LidarPoint)) {
        self.hunt.push(byte, PH0, |b| b == PH1);
        if self.hunt.len > 3 && self.hunt.len == self.needed() + LOOKAHEAD {
            self.complete(on_point, false);
        }
    }

    /// The end of a recording: takes a whole packet held without the header that would follow
    /// it (its check code still has to pass).
    pub fn flush(&mut self, mut on_point: impl FnMut(LidarPoint)) {
        self.complete(&mut on_point, true);
    }

    /// Bytes of the packet whose header is held (after its LSN byte has arrived).
    #[inline]
    fn needed(&self) -> usize {
        packet_len(self.hunt.buf.get(3).copied().unwrap_or(0))
    }

    /// Works on the held bytes while they hold a whole packet and the two bytes after it (more
    /// than one packet only after a rejected packet handed back the bytes behind its header);
    /// with `flush`, the two bytes after the last packet are not waited for.
    fn complete(&mut self, on_point: &mut impl FnMut(LidarPoint), flush: bool) {
        loop {
            let len = self.hunt.len;
            let need = self.needed();
            if len < 4 || len < need || (!flush && len < need + LOOKAHEAD) {
                return;
            }
            let buf = &self.hunt.buf;
            // A packet is only taken when the next one's header follows it: a 16-bit XOR lets
            // a cut packet through whenever the bytes that fill it XOR to the missing ones (an
            // intact packet of "no measurement" samples XORs to 0 with its own check code).
            let after = buf.get(need..len.min(need + LOOKAHEAD)).unwrap_or(&[]);
            let parsed = if [PH0, PH1].starts_with(after) {
                YdlidarPacket::parse(buf.get(..need).unwrap_or(&[]))
            } else {
                Err(YdlidarError::BadHeader)
            };
            match parsed {
                Ok(p) => {
                    let stats = &mut self.hunt.counter.stats;
                    bump(&mut stats.frames_ok);
                    stats.points = stats.points.saturating_add(p.sample_count() as u32);
                    if p.is_start() {
                        bump(&mut self.start_packets);
                        self.scan_freq_decihz = p.scan_freq_decihz().or(self.scan_freq_decihz);
                    }
                    p.points(self.correction, on_point);
                    self.frame_bytes = self.frame_bytes.saturating_add(need as u32);
                    self.hunt.take_front(need, PH0, |b| b == PH1);
                }
                Err(
                    YdlidarError::BadChecksum { .. }
                    | YdlidarError::Truncated(_)
                    | YdlidarError::BadHeader,
                ) => {
                    bump(&mut self.hunt.counter.stats.bad_checksum);
                    self.hunt.rehunt(PH0, |b| b == PH1);
                }
                Err(_) => {
                    // The check code vouches for the bytes: a whole packet with impossible content.
                    bump(&mut self.hunt.counter.stats.bad_frames);
                    self.frame_bytes = self.frame_bytes.saturating_add(need as u32);
                    self.hunt.take_front(need, PH0, |b| b == PH1);
                }
            }
        }
    }

    /// The counters. `bytes ==` [`YdlidarDecoder::frame_bytes`] `+ skipped_bytes +`
    /// [`YdlidarDecoder::buffered`] always holds; `frames_ok` counts packets.
    pub fn stats(&self) -> DecoderStats {
        self.hunt.counter.stats
    }

    /// Bytes of the packets counted in `frames_ok` and `bad_frames` (packets differ in length).
    pub fn frame_bytes(&self) -> u32 {
        self.frame_bytes
    }

    /// Bytes of a partial packet held.
    pub fn buffered(&self) -> usize {
        self.hunt.len
    }

    /// Zero packets received (one per revolution the sensor began).
    pub fn start_packets(&self) -> u32 {
        self.start_packets
    }

    /// The scan frequency of the last zero packet that reported one, 0.1 Hz.
    pub fn scan_freq_decihz(&self) -> Option<u8> {
        self.scan_freq_decihz
    }

    /// The angle correction applied.
    pub fn correction(&self) -> AngleCorrection {
        self.correction
    }

    /// Forgets any partial packet and zeroes the counters (the correction is kept).
    pub fn reset(&mut self) {
        *self = Self::with_correction(self.correction);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The manual's worked example: bytes 3..8 of a packet are `28 E5 6F BD 79`.
    fn manual_packet(first_mm_q2: u16, last_mm_q2: u16) -> Vec<u8> {
        let mut s = vec![0x6FE5u16; 40];
        s[0] = first_mm_q2;
        s[39] = last_mm_q2;
        let mut out = vec![0u8; packet_len(40)];
        // FSA 0x6FE5 = (0x37F2 << 1) | 1, LSA 0x79BD = (0x3CDE << 1) | 1.
        emit_packet(0, 0x37F2, 0x3CDE, &s, &mut out).unwrap();
        out
    }

    #[test]
    fn the_manual_example_by_hand() {
        let b = manual_packet(4000, 32_000);
        assert_eq!(&b[3..8], &[0x28, 0xE5, 0x6F, 0xBD, 0x79]);
        let p = YdlidarPacket::parse(&b).unwrap();
        assert_eq!(p.sample_count(), 40);
        // FSA: 0x37F2 = 14,322 → 223.78125°; LSA: 0x3CDE = 15,582 → 243.46875°; diff 19.6875°.
        assert_eq!(p.span_q6(), 1260);
        let raw = p.point(0, AngleCorrection::None);
        assert_eq!(raw.angle_cw_deg, 223.781_25);
        assert_eq!(p.point(39, AngleCorrection::None).angle_cw_deg, 243.468_75);
        // Sample 2 (i = 1): 223.78125 + 19.6875/39 = 224.286057…°.
        assert!((p.point(1, AngleCorrection::None).angle_cw_deg - 224.286_06).abs() < 1e-4);
        // Second level, the manual's distances 1,000 and 8,000 mm: AngCorrect −6.7622° and
        // −7.8374° (atan(21.8·(155.3 − 1000)/155,300) = atan(−0.118576) = −6.76219°), so
        // 217.0191° and 235.6313° (the manual prints 217.0178° and 235.6326°, from first-level
        // angles rounded to 223.78° and 243.47°).
        let first = p.point(0, AngleCorrection::Triangulation);
        let last = p.point(39, AngleCorrection::Triangulation);
        assert!((first.angle_cw_deg - 217.019_06).abs() < 2e-4, "{first:?}");
        assert!((last.angle_cw_deg - 235.631_32).abs() < 2e-4, "{last:?}");
        assert!((first.angle_cw_deg - 217.0178).abs() < 0.002);
        assert!((last.angle_cw_deg - 235.6326).abs() < 0.002);
        assert_eq!(first.range_m, 1.0);
        assert_eq!(last.range_m, 8.0);
        // The manual's sample E5 6F: 0x6FE5 / 4 = 7,161.25 mm.
        assert!((p.point(5, AngleCorrection::None).range_m - 7.161_25).abs() < 1e-6);
    }

    #[test]
    fn the_sdk_document_zero_packet() {
        // The YDLidar-SDK protocol document's example zero packet: CS 0x54AB =
        // 0x55AA ^ 0x0101 ^ 0xAE53 ^ 0xAE53 ^ 0x0000; FSA 0xAE53 >> 1 = 22,313 → 348.640625°.
        let b = [
            0xAA, 0x55, 0x01, 0x01, 0x53, 0xAE, 0x53, 0xAE, 0xAB, 0x54, 0x00, 0x00,
        ];
        let p = YdlidarPacket::parse(&b).unwrap();
        assert!(p.is_start());
        assert_eq!(p.scan_freq_decihz(), None);
        let pt = p.point(0, AngleCorrection::Triangulation);
        assert_eq!(pt.angle_cw_deg, 22_313.0 / 64.0);
        assert!(!pt.valid);
        let mut out = [0u8; 12];
        assert_eq!(emit_packet(1, 22_313, 22_313, &[0], &mut out), Ok(12));
        assert_eq!(out, b);
    }

    #[test]
    fn bad_fields_are_typed() {
        let mut b = manual_packet(4000, 4000);
        assert_eq!(
            YdlidarPacket::parse(&b[..50]),
            Err(YdlidarError::Truncated(50))
        );
        assert_eq!(
            YdlidarPacket::parse(&b[..3]),
            Err(YdlidarError::Truncated(3))
        );
        b[20] ^= 0x10;
        assert!(matches!(
            YdlidarPacket::parse(&b),
            Err(YdlidarError::BadChecksum { .. })
        ));
        let mut out = [0u8; 12];
        emit_packet(0, 23_040, 0, &[8], &mut out).unwrap();
        assert_eq!(
            YdlidarPacket::parse(&out),
            Err(YdlidarError::AngleOutOfRange)
        );
        emit_packet(0, 0, 0, &[], &mut out).unwrap();
        assert_eq!(
            YdlidarPacket::parse(&out[..10]),
            Err(YdlidarError::NoSamples)
        );
        emit_packet(0, 5, 5, &[8], &mut out).unwrap();
        out[4] &= !1;
        let cs = checksum(&out).to_le_bytes();
        out[8..10].copy_from_slice(&cs);
        assert_eq!(YdlidarPacket::parse(&out), Err(YdlidarError::BadCheckBit));
        out[0] = 0x55;
        assert_eq!(YdlidarPacket::parse(&out), Err(YdlidarError::BadHeader));
        assert_eq!(
            emit_packet(0, 0, 0, &[0; 256], &mut [0u8; 600]),
            Err(EncodeError::BadSampleCount(256))
        );
    }

    #[test]
    fn revolution_round_trip_and_accounting() {
        let d: Vec<u16> = (0..360).map(|k| 2000 + 40 * k as u16).collect();
        let mut out = vec![0u8; revolution_len(360, 40)];
        assert_eq!(out.len(), 12 + 9 * 10 + 2 * 359);
        assert_eq!(encode_revolution(&d, 40, 70, &mut out), Ok(out.len()));
        let mut stream = vec![0x00, 0xAA, 0x13, 0xAA];
        stream.extend_from_slice(&out);
        // Then the zero packet (12 bytes) and 88 of the 90 bytes of the next packet.
        stream.extend_from_slice(&out[..100]);
        let mut dec = YdlidarDecoder::with_correction(AngleCorrection::None);
        let mut pts = Vec::new();
        dec.feed(&stream, |p| pts.push(p));
        assert_eq!(pts.len(), 360 + 1);
        assert_eq!(dec.buffered(), 88);
        for (k, p) in pts.iter().take(360).enumerate() {
            assert_eq!(p.angle_cw_deg, k as f32);
            assert_eq!(p.range_m, f32::from(d[k]) * 0.25e-3);
        }
        assert_eq!(dec.start_packets(), 2);
        assert_eq!(dec.scan_freq_decihz(), Some(70));
        let s = dec.stats();
        assert_eq!(s.skipped_bytes, 4);
        assert_eq!(
            s.bytes as usize,
            dec.frame_bytes() as usize + s.skipped_bytes as usize + dec.buffered()
        );
        // With the correction, each point moves by the correction of its own distance.
        let mut c = YdlidarDecoder::new();
        let mut cpts = Vec::new();
        c.feed(&out, |p| cpts.push(p));
        c.flush(|p| cpts.push(p));
        assert_eq!(cpts.len(), 360);
        for (k, p) in cpts.iter().enumerate().skip(1) {
            let dmm = f64::from(d[k]) / 4.0;
            let corr = (21.8 * (155.3 - dmm) / (155.3 * dmm)).atan().to_degrees();
            let want = (k as f64 + corr).rem_euclid(360.0);
            assert!(
                (f64::from(p.angle_cw_deg) - want).abs() < 1e-3,
                "{k}: {p:?}"
            );
        }
    }

    #[test]
    fn a_false_header_with_a_long_packet_gives_back_what_it_swallowed() {
        let d: Vec<u16> = (0..360).map(|k| 1000 + k as u16).collect();
        let mut rev = vec![0u8; revolution_len(360, 40)];
        encode_revolution(&d, 40, 0, &mut rev).unwrap();
        // `AA 55`, CT 0, LSN 250: announces 510 bytes, swallows the whole revolution.
        let mut stream = vec![0xAA, 0x55, 0x00, 250];
        stream.extend_from_slice(&rev);
        stream.extend_from_slice(&rev);
        let mut dec = YdlidarDecoder::with_correction(AngleCorrection::None);
        let mut pts = Vec::new();
        dec.feed(&stream, |p| pts.push(p));
        // The last packet waits for the header that would follow it.
        assert_eq!(pts.len(), 720 - 39);
        assert_eq!(dec.buffered(), 88);
        dec.flush(|p| pts.push(p));
        assert_eq!(pts.len(), 720);
        let s = dec.stats();
        assert_eq!(s.bad_checksum, 1);
        assert_eq!(s.skipped_bytes, 4);
        assert_eq!(dec.buffered(), 0);
        assert_eq!(dec.frame_bytes() as usize, 2 * rev.len());
    }
}
