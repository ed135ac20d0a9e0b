//! The LD06 stream decoder: the shared header hunt (`src/lidar/sync.rs`) finds and buffers the
//! frames; this file only judges each whole frame.
//!
//! Contract: the judge runs [`Ld06Frame::check`], the checks of [`Ld06Frame::parse`]; on
//! acceptance it builds the frame once, keeps it for [`Ld06Decoder::last_frame`] and hands its 12
//! points to the caller; either way it returns a verdict and touches no counter.

use super::{Ld06Frame, Ld06Header, FRAME_LEN, POINTS_PER_FRAME};
use crate::lidar::sync::{HeaderHunt, Verdict};
use crate::lidar::{DecoderStats, LidarPoint};

/// Byte-at-a-time LD06 stream decoder. See the module docs for the frame and the resync rule.
#[derive(Clone, Debug)]
pub struct Ld06Decoder {
    hunt: HeaderHunt<FRAME_LEN, Ld06Header>,
    last: Option<Ld06Frame>,
}

impl Default for Ld06Decoder {
    fn default() -> Self {
        Self::new()
    }
}

/// The verdict on one whole frame held by the hunt (it opens with `0x54 0x2C`). An accepted
/// frame is built once, in `last`, and its points go to `on_point`.
#[inline(always)]
fn judge(
    frame: &[u8; FRAME_LEN],
    last: &mut Option<Ld06Frame>,
    on_point: &mut impl FnMut(LidarPoint),
) -> Verdict {
    match Ld06Frame::check(frame) {
        Ok(()) => {
            let kept = last.get_or_insert_with(Ld06Frame::default);
            kept.read_fields_and_points(frame, on_point);
            Verdict::Accept {
                points: POINTS_PER_FRAME as u32,
            }
        }
        Err(e) => e.verdict(),
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
        let last = &mut self.last;
        self.hunt
            .feed_frames(bytes, |frame| judge(frame, last, &mut on_point));
    }

    /// Feeds one byte (see [`Ld06Decoder::feed`]).
    #[inline]
    pub fn push_byte(&mut self, byte: u8, on_point: &mut impl FnMut(LidarPoint)) {
        let last = &mut self.last;
        self.hunt
            .push_frame_byte(byte, &mut |frame| judge(frame, last, on_point));
    }

    /// The counters so far. `bytes == 47 · (frames_ok + bad_frames) + skipped_bytes +`
    /// [`Ld06Decoder::buffered`] always holds.
    pub fn stats(&self) -> DecoderStats {
        self.hunt.stats()
    }

    /// Bytes of a partial frame held, waiting for the rest.
    pub fn buffered(&self) -> usize {
        self.hunt.len()
    }

    /// The last frame the decoder accepted, the one whose points it emitted last (speed and
    /// timestamp included), if any.
    ///
    /// Frames whose CRC passed but that were then rejected (an angle ≥ 360°, or implausible) are
    /// not kept: the checks that rejected them say their bytes are not a frame the sensor sent
    /// (most likely damage the 8-bit CRC let through), so their speed and timestamp are no more
    /// to be trusted than their points, and a caller that reads the rotation speed here must not
    /// get a value the decoder itself refused.
    pub fn last_frame(&self) -> Option<&Ld06Frame> {
        self.last.as_ref()
    }

    /// Forgets any partial frame and zeroes the counters.
    pub fn reset(&mut self) {
        *self = Self::new();
    }
}
