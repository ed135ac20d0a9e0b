//! Scan nodes: one node's fields, its check bits, and the encoder of a whole revolution.

use super::field::node;
use super::{RplidarError, FULL_TURN_Q6, NODE_LEN};
use crate::lidar::{range_units, room, EncodeError, LidarPoint};
use crate::wire;

/// One scan node, in the protocol's units.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RplidarNode {
    /// First node of a new revolution (the `S` flag).
    pub start: bool,
    /// Quality, 0..=63 (the sensor reports 0 for no measurement).
    pub quality: u8,
    /// Angle, 1/64 degree clockwise, `< 23,040`.
    pub angle_q6: u16,
    /// Distance, 1/4 millimetre; 0 means no measurement.
    pub distance_q2: u16,
}

impl RplidarNode {
    /// Parses and checks one node (flags, check bit, angle range).
    ///
    /// # Errors
    /// [`RplidarError::Truncated`], [`RplidarError::BadStartFlag`],
    /// [`RplidarError::BadCheckBit`], [`RplidarError::AngleOutOfRange`].
    pub fn parse(bytes: &[u8]) -> Result<Self, RplidarError> {
        let b: &[u8; NODE_LEN] = bytes
            .get(..NODE_LEN)
            .and_then(|s| s.try_into().ok())
            .ok_or(RplidarError::Truncated(bytes.len()))?;
        let (flags, low) = (b[node::FLAGS], b[node::ANGLE_LOW]);
        if (flags & 1) == ((flags >> 1) & 1) {
            return Err(RplidarError::BadStartFlag);
        }
        if low & 1 == 0 {
            return Err(RplidarError::BadCheckBit);
        }
        let angle_q6 = u16::from(low >> 1) | (u16::from(b[node::ANGLE_HIGH]) << 7);
        if angle_q6 >= FULL_TURN_Q6 {
            return Err(RplidarError::AngleOutOfRange);
        }
        Ok(Self {
            start: flags & 1 == 1,
            quality: flags >> 2,
            angle_q6,
            distance_q2: wire::get_u16(b, node::DISTANCE),
        })
    }

    /// Writes the node; returns [`NODE_LEN`]. The quality is cut to 6 bits and the angle to 15
    /// (an angle ≥ 360° is written as given, for tests of the decoder's range check).
    ///
    /// # Errors
    /// [`EncodeError::BufferTooSmall`].
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        let o = room(out, NODE_LEN)?;
        let s = u8::from(self.start);
        let fields = [
            (
                node::FLAGS,
                ((self.quality & 0x3F) << 2) | ((s ^ 1) << 1) | s,
            ),
            (node::ANGLE_LOW, (((self.angle_q6 & 0x7F) as u8) << 1) | 1),
            (node::ANGLE_HIGH, ((self.angle_q6 >> 7) & 0xFF) as u8),
        ];
        for (at, byte) in fields {
            if let Some(b) = o.get_mut(at) {
                *b = byte;
            }
        }
        wire::put_u16(o, node::DISTANCE, self.distance_q2);
        Ok(NODE_LEN)
    }

    /// The node as a point: angle `angle_q6 / 64`°, range `distance_q2 / 4000` m, valid when the
    /// distance is not 0.
    pub fn point(&self) -> LidarPoint {
        LidarPoint {
            angle_cw_deg: f32::from(self.angle_q6) * (1.0 / 64.0),
            range_m: f32::from(self.distance_q2) * (1.0 / 4000.0),
            quality: u16::from(self.quality),
            valid: self.distance_q2 != 0,
            timestamp_ms: None,
        }
    }

    /// The node an RPLIDAR would send for a range (metres) at `angle_q6`: the distance rounded
    /// to the quarter millimetre; NaN, negative, 0 and anything past 16,383.75 mm become "no
    /// measurement" with quality 0.
    pub fn from_range_m(range_m: f32, angle_q6: u16, quality: u8, start: bool) -> Self {
        let distance_q2 = range_units(range_m, 4000.0, u16::MAX);
        Self {
            start,
            quality: if distance_q2 == 0 { 0 } else { quality & 0x3F },
            angle_q6,
            distance_q2,
        }
    }
}

/// Bytes needed by [`encode_revolution`] for `nodes` points.
pub const fn revolution_len(nodes: usize) -> usize {
    nodes * NODE_LEN
}

/// Writes one revolution of scan nodes (no descriptor): `ranges_m[k]` at `k · 360° / len`
/// clockwise, the first with the start flag, every measured node with `quality`. Returns the
/// bytes written.
///
/// # Errors
/// [`EncodeError::BadSampleCount`] unless `ranges_m.len()` divides 23,040 (so every angle is a
/// whole q6 value: 360 nodes give 1°, 720 give 0.5°); [`EncodeError::BufferTooSmall`].
pub fn encode_revolution(
    ranges_m: &[f32],
    quality: u8,
    out: &mut [u8],
) -> Result<usize, EncodeError> {
    let n = ranges_m.len();
    if n == 0 || usize::from(FULL_TURN_Q6) % n != 0 {
        return Err(EncodeError::BadSampleCount(n));
    }
    let needed = revolution_len(n);
    let out = room(out, needed)?;
    let step = FULL_TURN_Q6 / n as u16;
    for (k, (&r, dst)) in ranges_m
        .iter()
        .zip(out.chunks_exact_mut(NODE_LEN))
        .enumerate()
    {
        RplidarNode::from_range_m(r, k as u16 * step, quality, k == 0).emit(dst)?;
    }
    Ok(needed)
}
