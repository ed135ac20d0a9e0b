//! One YDLIDAR packet, checked and read in place; the packet and revolution encoders.
//!
//! Contract: [`YdlidarPacket::parse`] is the one check of a packet (the decoder runs it on the
//! bytes it holds); parse and [`emit_packet`] place every field through the one table `field` of
//! the module.

use super::{
    angle_correction_deg, checksum, field, packet_len, AngleCorrection, YdlidarError, FULL_TURN_Q6,
    HEADER_LEN, MAX_SAMPLES, PH0, PH1, SAMPLE_LEN,
};
use crate::lidar::{range_units, room, EncodeError, LidarPoint};
use crate::wire;

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
        let (Some(&lsn), Some(&ct)) = (bytes.get(field::LSN), bytes.get(field::CT)) else {
            return Err(truncated);
        };
        if bytes.get(field::PH) != Some(&[PH0, PH1][..]) {
            return Err(YdlidarError::BadHeader);
        }
        let b = bytes.get(..packet_len(lsn)).ok_or(truncated)?;
        let samples = b.get(field::SAMPLES).ok_or(truncated)?;
        let carried = wire::get_u16(b, field::CS);
        let computed = checksum(b);
        if carried != computed {
            return Err(YdlidarError::BadChecksum { carried, computed });
        }
        let (fsa, lsa) = (wire::get_u16(b, field::FSA), wire::get_u16(b, field::LSA));
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
        let at = SAMPLE_LEN * i;
        let distance = field::sample::DISTANCE;
        wire::get_u16(self.samples, at + distance.start..at + distance.end)
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
    wire::put(o, field::PH, &[PH0, PH1]);
    if let Some(ct) = o.get_mut(field::CT) {
        *ct = packet_type;
    }
    if let Some(n) = o.get_mut(field::LSN) {
        *n = lsn;
    }
    wire::put_u16(o, field::FSA, (start_angle_q6 << 1) | 1);
    wire::put_u16(o, field::LSA, (end_angle_q6 << 1) | 1);
    wire::put_u16(o, field::CS, 0);
    if let Some(body) = o.get_mut(field::SAMPLES) {
        for (c, &s) in body.chunks_exact_mut(SAMPLE_LEN).zip(samples_q2) {
            wire::put_u16(c, field::sample::DISTANCE, s);
        }
    }
    wire::put_u16(o, field::CS, checksum(o));
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
