//! The assembler's settings, counters, error and per-revolution report.

use crate::scan::BeamLayout;

/// Why an assembler could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AssemblerError {
    /// The layout's bearings are not evenly spaced with a positive step (index of the first beam
    /// that is off).
    NotUniform(usize),
    /// The layout's beams span more than one turn.
    MoreThanOneTurn,
    /// A range threshold that is NaN, negative, or a minimum above the maximum.
    BadRange,
}

impl core::fmt::Display for AssemblerError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NotUniform(i) => write!(f, "layout bearing {i} is not evenly spaced"),
            Self::MoreThanOneTurn => f.write_str("layout spans more than one turn"),
            Self::BadRange => f.write_str("range thresholds must satisfy 0 <= min <= max"),
        }
    }
}

impl core::error::Error for AssemblerError {}

/// Per-sensor acceptance thresholds.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AssemblerConfig {
    /// Points nearer than this are rejected, metres (the LD06 is specified from 0.02 m).
    pub min_range_m: f32,
    /// Points farther than this are rejected, metres.
    pub max_range_m: f32,
    /// Points whose quality (protocol units) is below this are rejected.
    pub min_quality: u16,
    /// The point timestamps wrap to 0 at this many milliseconds (LD06: 30,000; a caller that
    /// stamps points with its own `u16` millisecond clock: 0, meaning 65,536).
    pub timestamp_wrap_ms: u16,
    /// Whether the points' timestamps are the sensor's own, taken as each point was measured
    /// (`true`, the LD06's): then a gap between two points tells how many turns went by, and
    /// turns lost in it are counted. `false` for a receiver's clock read once per received
    /// chunk of bytes (a protocol without timestamps, e.g. [`crate::lidar::xv11`]): such a
    /// stamp can lag the points by a whole chunk, so revolutions follow the angles alone, as
    /// without timestamps, and the stamps only time them ([`Revolution`]).
    pub sensor_timestamps: bool,
}

impl AssemblerConfig {
    /// Accepts every valid point from 0 up to the layout's maximum range, any quality.
    pub fn for_layout<const N: usize>(layout: &BeamLayout<N>) -> Self {
        Self {
            min_range_m: 0.0,
            max_range_m: layout.max_range_m(),
            min_quality: 0,
            timestamp_wrap_ms: crate::lidar::ld06::TIMESTAMP_WRAP_MS,
            sensor_timestamps: true,
        }
    }
}

/// Counters of an assembler, readable at any time. Every pushed point is counted once in
/// `points` and once in exactly one of `accepted`, `flagged_invalid`, `out_of_range`,
/// `low_quality`, `bad_angle`, `outside_layout`; every accepted point ends up in a bin of an
/// emitted scan, in `replaced`, or in the pending revolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AssemblerStats {
    /// Points pushed.
    pub points: u32,
    /// Points stored in a bin.
    pub accepted: u32,
    /// Points the sensor flagged as no measurement.
    pub flagged_invalid: u32,
    /// Valid points outside `[min_range_m, max_range_m]` (or with a NaN range).
    pub out_of_range: u32,
    /// Valid points in range below the quality threshold.
    pub low_quality: u32,
    /// Points whose angle is not in `[0, 360)` (NaN included); they do not move the rotor angle.
    pub bad_angle: u32,
    /// Accepted-quality points farther than half a step from every beam.
    pub outside_layout: u32,
    /// Accepted points displaced from their bin by a point nearer to the beam's bearing (or
    /// that lost to an earlier one).
    pub replaced: u32,
    /// Scans emitted.
    pub revolutions: u32,
    /// Whole turns that went by without a single point (data lost across the wrap for longer
    /// than a turn, detected from the timestamps).
    pub missed_revolutions: u32,
}

/// What is known about the last emitted revolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Revolution {
    /// Sequence number of the revolution, from 0.
    pub index: u32,
    /// Points pushed during the revolution (all of them, accepted or not).
    pub points: u32,
    /// Beams that received a point (the others are NaN).
    pub filled: u16,
    /// Sensor timestamp of the first point, milliseconds (protocol clock), if it has one.
    pub start_timestamp_ms: Option<u16>,
    /// Sensor timestamp of the last point, milliseconds, if it has one.
    pub end_timestamp_ms: Option<u16>,
}

/// When the beams of the last emitted revolution were measured, as two anchors on the rotor:
/// the revolution's first timestamp and the position of the point that carried it, and the
/// position of the first point that carried its last timestamp.
///
/// Protocols such as the LD06 stamp a frame (twelve points) with the time of its first point,
/// so the second anchor is the last frame's first point, not the revolution's last point. At a
/// steady rotation rate the time of a point at rotor position `p` is then
/// `start + (p − start_deg) / (end_deg − start_deg) · (end − start)` (points after the last
/// stamp extrapolate the same line). `end_deg > start_deg` always.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RevolutionTiming {
    /// Rotor position of the first timestamped point, degrees clockwise from the sensor's 0°
    /// (within the revolution: about 0 after a wrap, slightly negative after a backward jitter).
    pub start_deg: f32,
    /// Its timestamp, milliseconds (protocol clock).
    pub start_timestamp_ms: u16,
    /// Rotor position of the first point that carried the revolution's last timestamp, degrees
    /// clockwise, on the same unwrapped scale as `start_deg`.
    pub end_deg: f32,
    /// That timestamp, milliseconds (protocol clock).
    pub end_timestamp_ms: u16,
}
