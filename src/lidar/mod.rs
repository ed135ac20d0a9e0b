//! 2-D LiDAR byte-stream decoders, their encoders, and the assembly of points into a [`Scan`].
//!
//! The spinning 2-D LiDARs that small robots carry stream angle-stamped points over a UART,
//! clockwise, at their own rotation speed, in frames protected by a checksum. This module turns
//! such a stream into the crate's [`Scan<N>`](crate::scan::Scan) on a caller's
//! [`BeamLayout<N>`](crate::scan::BeamLayout) in two independent steps:
//!
//! 1. a **decoder** per sensor family ([`ld06`], [`rplidar`], [`xv11`], [`ydlidar`]) is a byte-at-a-time state machine. Feed it any
//!    slice of received bytes (an interrupt's byte, a DMA half-buffer) with `feed`; it finds the
//!    frame header, resynchronises after garbage or lost bytes, verifies the frame's checksum and
//!    only then hands every point of the frame to the caller's closure as a [`LidarPoint`]. It
//!    never allocates and keeps [`DecoderStats`] readable at any time;
//! 2. the [`ScanAssembler`] bins the points of one revolution into the layout's beams and hands
//!    back a finished scan when the angle wraps.
//!
//! Each sensor file holds the parse and the emit side of its frames together (the encoder writes
//! into a caller's `&mut [u8]`), so tests, the host tools and the stream fed to the firmware all
//! produce frames through the same code. The protocol documents followed are cited in each file
//! and in `docs/lidar.md`.
//!
//! ```
//! use beamfield::lidar::{ld06::Ld06Decoder, AssemblerConfig, ScanAssembler};
//! use beamfield::{BeamLayout, SensorMount};
//!
//! // 360 beams, 1° apart, counter-clockwise from the sensor's zero direction.
//! let layout = BeamLayout::<360>::uniform(0.0, 1f32.to_radians(), 360, 12.0, SensorMount::CENTERED)?;
//! let mut assembler = ScanAssembler::new(&layout, AssemblerConfig::for_layout(&layout))?;
//! let mut decoder = Ld06Decoder::new();
//! let received: &[u8] = &[0x00, 0x54]; // bytes from the UART
//! let mut scans = 0;
//! decoder.feed(received, |point| {
//!     if let Some(_scan) = assembler.push(point) {
//!         scans += 1; // score `_scan` here
//!     }
//! });
//! assert_eq!(scans, 0);
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```
//!
//! [`Scan`]: crate::scan::Scan

pub mod assembler;
pub mod deskew;
#[cfg(feature = "hal")]
pub mod io;
pub mod ld06;
pub mod rplidar;
mod sync;
pub mod xv11;
pub mod ydlidar;

pub use assembler::{
    AssemblerConfig, AssemblerError, AssemblerStats, Revolution, RevolutionTiming, ScanAssembler,
};
pub use deskew::{DeskewError, DeskewReport, Deskewer, Sweep};

/// One point as a LiDAR reports it, in the sensor's own (clockwise) convention.
///
/// Decoders emit only points of frames whose checksum passed. A point with `valid == false` is
/// one the sensor itself flagged as "no measurement" (LD06: distance 0); it still tells the
/// assembler where the rotor is.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LidarPoint {
    /// Angle clockwise from the sensor's zero direction (seen from above), degrees, in `[0, 360)`.
    pub angle_cw_deg: f32,
    /// Measured distance, metres (0 when the sensor reported no measurement).
    pub range_m: f32,
    /// The sensor's quality or intensity figure, in the protocol's own unit (LD06: intensity
    /// 0..=255).
    pub quality: u16,
    /// False when the sensor flagged the point as carrying no measurement.
    pub valid: bool,
    /// The sensor's timestamp of the point's frame, milliseconds, when the protocol has one
    /// (LD06: wraps at 30,000 ms).
    pub timestamp_ms: Option<u16>,
}

/// Counters of a decoder, readable at any time.
///
/// Every byte fed is accounted for: `bytes == frame_len · (frames_ok + bad_frames) +
/// skipped_bytes + buffered`, where `buffered` is the length of the partial frame the decoder
/// holds (bytes of a frame whose checksum failed are either skipped or re-examined as the start
/// of the next frame). YDLIDAR packets differ in length: there the first term is the decoder's
/// `frame_bytes()`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DecoderStats {
    /// Bytes fed so far.
    pub bytes: u32,
    /// Frames whose checksum passed and whose content was valid; their points were emitted.
    pub frames_ok: u32,
    /// Complete frames whose checksum failed; none of their points was emitted.
    pub bad_checksum: u32,
    /// Frames whose checksum passed but whose content is impossible (e.g. an angle ≥ 360°); none
    /// of their points was emitted.
    pub bad_frames: u32,
    /// Frames whose checksum passed but which the sensor cannot have sent (LD06: a rotation
    /// speed or an angular span outside the protocol's limits), taken for damage the checksum
    /// missed: none of their points was emitted, and their bytes were treated as those of a
    /// frame whose checksum failed (skipped up to the next header candidate). Always 0 for the
    /// decoders without such a check.
    pub implausible_frames: u32,
    /// Bytes discarded while searching for a frame header (start-up garbage, the rest of a
    /// frame whose checksum failed up to the next header candidate, lost alignment).
    pub skipped_bytes: u32,
    /// How many times the decoder started discarding bytes (one per run of skipped bytes; a
    /// frame consumed as a frame, counted in `frames_ok` or `bad_frames`, ends a run).
    pub resyncs: u32,
    /// Points handed to the caller.
    pub points: u32,
}

/// Errors writing a frame into a caller's buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EncodeError {
    /// The output buffer is too small.
    BufferTooSmall {
        /// Bytes needed.
        needed: usize,
        /// Bytes available.
        given: usize,
    },
    /// A revolution whose sample count the protocol cannot lay out evenly (see the encoder's
    /// documentation for the rule).
    BadSampleCount(usize),
}

impl core::fmt::Display for EncodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BufferTooSmall { needed, given } => {
                write!(f, "output buffer holds {given} bytes, {needed} needed")
            }
            Self::BadSampleCount(n) => write!(f, "{n} samples cannot form whole frames"),
        }
    }
}

impl core::error::Error for EncodeError {}

/// What every decoder of this module does: take bytes one at a time and hand out the points of
/// frames that passed their checks. Lets adapters and tools work with any of them.
pub trait StreamDecoder {
    /// Feeds one byte; `on_point` is called for each point of a frame this byte completed.
    fn push_byte(&mut self, byte: u8, on_point: &mut impl FnMut(LidarPoint));
    /// Feeds received bytes; the same as [`StreamDecoder::push_byte`] for each byte in turn
    /// (a decoder may take a frame's body in one block, as the LD06 decoder does).
    fn feed(&mut self, bytes: &[u8], mut on_point: impl FnMut(LidarPoint)) {
        for &b in bytes {
            self.push_byte(b, &mut on_point);
        }
    }
    /// The decoder's counters.
    fn stats(&self) -> DecoderStats;
}

macro_rules! stream_decoder {
    ($t:ty) => {
        impl StreamDecoder for $t {
            #[inline]
            fn push_byte(&mut self, byte: u8, on_point: &mut impl FnMut(LidarPoint)) {
                <$t>::push_byte(self, byte, on_point)
            }
            #[inline]
            fn feed(&mut self, bytes: &[u8], on_point: impl FnMut(LidarPoint)) {
                <$t>::feed(self, bytes, on_point)
            }
            fn stats(&self) -> DecoderStats {
                <$t>::stats(self)
            }
        }
    };
}
stream_decoder!(ld06::Ld06Decoder);
stream_decoder!(rplidar::RplidarDecoder);
stream_decoder!(xv11::Xv11Decoder);
stream_decoder!(ydlidar::YdlidarDecoder);

/// `out[..needed]`: the room an encoder writes into.
///
/// # Errors
/// [`EncodeError::BufferTooSmall`] when `out` is shorter than `needed`.
pub(crate) fn room(out: &mut [u8], needed: usize) -> Result<&mut [u8], EncodeError> {
    let given = out.len();
    out.get_mut(..needed)
        .ok_or(EncodeError::BufferTooSmall { needed, given })
}

/// A range (metres) in a protocol's distance unit (`units_per_m` to the metre), rounded to the
/// nearest unit; 0 ("no measurement") for NaN, negative, or anything that rounds to 0 or past
/// `max_units`. What each encoder writes for a range.
pub(crate) fn range_units(range_m: f32, units_per_m: f32, max_units: u16) -> u16 {
    let v = range_m * units_per_m;
    if (0.5..f32::from(max_units) + 0.5).contains(&v) {
        // In [0.5, max + 0.5): rounds to 1..=max.
        (v + 0.5) as u16
    } else {
        0
    }
}

/// Adds one to a counter, saturating (counters never wrap to a misleading small value).
#[inline(always)]
pub(crate) fn bump(counter: &mut u32) {
    *counter = counter.saturating_add(1);
}

#[cfg(test)]
mod tests {
    use super::range_units;

    #[test]
    fn range_units_rounds_to_the_unit_and_zeroes_what_the_field_cannot_carry() {
        // Millimetres: 1.2344 m → 1,234 mm, 1.2346 m → 1,235 mm.
        assert_eq!(range_units(1.2344, 1000.0, u16::MAX), 1234);
        assert_eq!(range_units(1.2346, 1000.0, u16::MAX), 1235);
        // Quarter millimetres: 1 m is 4,000.
        assert_eq!(range_units(1.0, 4000.0, u16::MAX), 4000);
        // Below half a unit, NaN, negative: no measurement.
        assert_eq!(range_units(0.0004, 1000.0, u16::MAX), 0);
        assert_eq!(range_units(f32::NAN, 1000.0, u16::MAX), 0);
        assert_eq!(range_units(-2.0, 1000.0, u16::MAX), 0);
        // The field's largest value, and past it (a 14-bit field: 16,383 mm).
        assert_eq!(range_units(16.383, 1000.0, 16_383), 16_383);
        assert_eq!(range_units(16.384, 1000.0, 16_383), 0);
        assert_eq!(range_units(65.535, 1000.0, u16::MAX), u16::MAX);
        assert_eq!(range_units(65.536, 1000.0, u16::MAX), 0);
    }
}
