//! One LD06 frame in the protocol's units: its parse (with every check, in the order the module
//! documents), its emit, its points, and the encoder of a whole revolution.
//!
//! Contract: [`Ld06Frame::parse`] and the stream decoder run the same checks
//! ([`Ld06Frame::check`]); parse and emit place every field through the one table `field` of
//! the module, so the two sides cannot disagree on an offset.

use super::{
    crc8, crc8_frame, field, u16_at, Ld06Error, FRAME_LEN, FULL_TURN_CDEG, HEADER,
    MAX_SPEED_DEG_PER_S, MIN_SPEED_DEG_PER_S, POINTS_PER_FRAME, SAMPLE_RATE_FLOOR_HZ,
    TIMESTAMP_WRAP_MS, VER_LEN,
};
use crate::lidar::{range_units, room, EncodeError, LidarPoint};
use crate::wire;

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

/// The clockwise span from `start` to `end` (both `< 36,000`), hundredths of a degree, in
/// `[0, 36,000)`.
#[inline(always)]
const fn span_between(start: u16, end: u16) -> u16 {
    if end >= start {
        end - start
    } else {
        // end < start < 36,000 in a checked frame, so this neither overflows nor wraps.
        (FULL_TURN_CDEG - start).wrapping_add(end)
    }
}

/// The plausibility rule of [`Ld06Frame::is_plausible`] on the raw fields.
#[inline(always)]
const fn plausible(speed_deg_per_s: u16, span_cdeg: u16) -> bool {
    let v = speed_deg_per_s;
    // span ≤ max_span_cdeg(v) without the division: 2 · rate · span ≤ 3,600 · v.
    v >= MIN_SPEED_DEG_PER_S
        && v <= MAX_SPEED_DEG_PER_S
        && 2 * SAMPLE_RATE_FLOOR_HZ * span_cdeg as u32
            <= 100 * 3 * POINTS_PER_FRAME as u32 * v as u32
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
        if b[field::HEADER] != HEADER || b[field::VER_LEN] != VER_LEN {
            return Err(Ld06Error::BadHeader);
        }
        Self::check(b)?;
        Ok(Self::fields(b))
    }

    /// The checks after the header, on the frame's bytes, in order: CRC, angle ranges,
    /// plausibility. The decoder, which only holds frames that open with the header, runs
    /// exactly these.
    #[inline(always)]
    pub(super) fn check(b: &[u8; FRAME_LEN]) -> Result<(), Ld06Error> {
        let computed = crc8_frame(b);
        let carried = b[field::CRC];
        if computed != carried {
            return Err(Ld06Error::BadChecksum { carried, computed });
        }
        let start = u16_at(b, field::START_ANGLE);
        let end = u16_at(b, field::END_ANGLE);
        if start >= FULL_TURN_CDEG || end >= FULL_TURN_CDEG {
            return Err(Ld06Error::AngleOutOfRange);
        }
        let speed = u16_at(b, field::SPEED);
        let span = span_between(start, end);
        if !plausible(speed, span) {
            return Err(Ld06Error::Implausible {
                speed_deg_per_s: speed,
                span_cdeg: span,
            });
        }
        Ok(())
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
        plausible(self.speed_deg_per_s, self.span_cdeg())
    }

    /// Reads the fields without any check.
    #[inline(always)]
    pub(super) fn fields(b: &[u8; FRAME_LEN]) -> Self {
        let mut f = Self::default();
        f.read_fields(b);
        f
    }

    /// Overwrites every field with the frame's, without any check: in place, so that the
    /// decoder's kept frame is not built aside and then copied.
    #[inline(always)]
    pub(super) fn read_fields(&mut self, b: &[u8; FRAME_LEN]) {
        use field::sample;
        let raw = b.get(field::SAMPLES).unwrap_or(&[]);
        for (s, c) in self.samples.iter_mut().zip(raw.chunks_exact(sample::LEN)) {
            *s = Ld06Sample {
                distance_mm: wire::get_u16(c, sample::DISTANCE),
                intensity: c.get(sample::INTENSITY).copied().unwrap_or(0),
            };
        }
        self.speed_deg_per_s = u16_at(b, field::SPEED);
        self.start_angle_cdeg = u16_at(b, field::START_ANGLE);
        self.end_angle_cdeg = u16_at(b, field::END_ANGLE);
        self.timestamp_ms = u16_at(b, field::TIMESTAMP);
    }

    /// [`Ld06Frame::read_fields`] then [`Ld06Frame::points`], in one pass over the samples:
    /// each is read from the frame's bytes, kept and handed over at once (the decoder's path).
    #[inline(always)]
    pub(super) fn read_fields_and_points(
        &mut self,
        b: &[u8; FRAME_LEN],
        on_point: &mut impl FnMut(LidarPoint),
    ) {
        use field::sample;
        self.speed_deg_per_s = u16_at(b, field::SPEED);
        self.start_angle_cdeg = u16_at(b, field::START_ANGLE);
        self.end_angle_cdeg = u16_at(b, field::END_ANGLE);
        self.timestamp_ms = u16_at(b, field::TIMESTAMP);
        let mut angle = AngleSteps::new(self.start_angle_cdeg, self.span_cdeg());
        let raw = b.get(field::SAMPLES).unwrap_or(&[]);
        for (s, c) in self.samples.iter_mut().zip(raw.chunks_exact(sample::LEN)) {
            *s = Ld06Sample {
                distance_mm: wire::get_u16(c, sample::DISTANCE),
                intensity: c.get(sample::INTENSITY).copied().unwrap_or(0),
            };
            on_point(angle.point(*s, self.timestamp_ms));
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
        use field::sample;
        let given = out.len();
        let o: &mut [u8; FRAME_LEN] = out
            .get_mut(..FRAME_LEN)
            .and_then(|s| s.try_into().ok())
            .ok_or(EncodeError::BufferTooSmall {
                needed: FRAME_LEN,
                given,
            })?;
        o[field::HEADER] = HEADER;
        o[field::VER_LEN] = VER_LEN;
        wire::put_u16(o, field::SPEED, self.speed_deg_per_s);
        wire::put_u16(o, field::START_ANGLE, self.start_angle_cdeg);
        if let Some(raw) = o.get_mut(field::SAMPLES) {
            for (c, s) in raw.chunks_exact_mut(sample::LEN).zip(self.samples.iter()) {
                wire::put_u16(c, sample::DISTANCE, s.distance_mm);
                if let Some(i) = c.get_mut(sample::INTENSITY) {
                    *i = s.intensity;
                }
            }
        }
        wire::put_u16(o, field::END_ANGLE, self.end_angle_cdeg);
        wire::put_u16(o, field::TIMESTAMP, self.timestamp_ms);
        o[field::CRC] = crc8(o.get(field::CHECKED).unwrap_or(&[]));
        Ok(FRAME_LEN)
    }

    /// The span from the start to the end angle, hundredths of a degree, in `[0, 36,000)`
    /// (clockwise, across 0° when the end angle is smaller than the start angle).
    pub fn span_cdeg(&self) -> u16 {
        span_between(self.start_angle_cdeg, self.end_angle_cdeg)
    }

    /// Hands the 12 points to `on_point`, in order: the same values as [`Ld06Frame::point`],
    /// with the angle stepped instead of recomputed.
    #[inline]
    pub fn points(&self, on_point: &mut impl FnMut(LidarPoint)) {
        let mut angle = AngleSteps::new(self.start_angle_cdeg, self.span_cdeg());
        for s in &self.samples {
            on_point(angle.point(*s, self.timestamp_ms));
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

/// The angles of a frame's points, stepped from the start angle: in integers of 1/1,100 degree
/// (`start · 11 + span · i`, reduced modulo 360°), converted once per point.
struct AngleSteps {
    /// The next point's angle, 1/1,100 degree, below `FULL`.
    a: u32,
    /// The span of the frame, hundredths of a degree (the step in 1/1,100 degree).
    span: u32,
}

impl AngleSteps {
    /// Steps between the first and the last point.
    const STEPS: u32 = POINTS_PER_FRAME as u32 - 1;
    /// A full turn, 1/1,100 degree.
    const FULL: u32 = FULL_TURN_CDEG as u32 * Self::STEPS;

    #[inline(always)]
    fn new(start_cdeg: u16, span_cdeg: u16) -> Self {
        Self {
            a: u32::from(start_cdeg) * Self::STEPS,
            span: u32::from(span_cdeg),
        }
    }

    /// The point of sample `s` at the current angle; steps to the next angle.
    #[inline(always)]
    fn point(&mut self, s: Ld06Sample, timestamp_ms: u16) -> LidarPoint {
        let p = LidarPoint {
            angle_cw_deg: self.a as f32 * (1.0 / (100.0 * Self::STEPS as f32)),
            range_m: f32::from(s.distance_mm) * 0.001,
            quality: u16::from(s.intensity),
            valid: s.distance_mm != 0,
            timestamp_ms: Some(timestamp_ms),
        };
        self.a += self.span;
        if self.a >= Self::FULL {
            self.a -= Self::FULL;
        }
        p
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
