//! The receiving side over a byte stream: frames cut at each `0x00`, decoded, counted.

use super::{decode, Frame, LinkError, DELIMITER, MAX_ENCODED_LEN};
use heapless::Vec;

/// What became of the bytes a [`Decoder`] was fed. Every counter wraps at `u32::MAX`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkStats {
    /// Bytes fed.
    pub bytes: u32,
    /// Frames decoded and handed out.
    pub frames: u32,
    /// Runs of bytes longer than any frame ([`LinkError::Oversized`]).
    pub oversized: u32,
    /// [`LinkError::BadCobs`].
    pub bad_cobs: u32,
    /// [`LinkError::TooShort`].
    pub too_short: u32,
    /// [`LinkError::BadCrc`].
    pub bad_crc: u32,
    /// [`LinkError::WrongVersion`].
    pub wrong_version: u32,
    /// [`LinkError::UnknownType`].
    pub unknown_type: u32,
    /// [`LinkError::WrongLength`].
    pub wrong_length: u32,
    /// [`LinkError::ValueOutOfRange`].
    pub out_of_range: u32,
    /// Frames whose sequence number was not one more than that of the previous decoded frame
    /// (frames lost or refused in between, or the sender restarted).
    pub sequence_gaps: u32,
}

impl LinkStats {
    /// Every refused frame, all causes (a [`Heartbeat::link_errors`](super::Heartbeat)).
    pub fn errors(&self) -> u32 {
        self.oversized
            .wrapping_add(self.bad_cobs)
            .wrapping_add(self.too_short)
            .wrapping_add(self.bad_crc)
            .wrapping_add(self.wrong_version)
            .wrapping_add(self.unknown_type)
            .wrapping_add(self.wrong_length)
            .wrapping_add(self.out_of_range)
    }

    fn count(&mut self, e: &LinkError) {
        let c = match e {
            LinkError::Oversized => &mut self.oversized,
            LinkError::BadCobs => &mut self.bad_cobs,
            LinkError::TooShort => &mut self.too_short,
            LinkError::BadCrc => &mut self.bad_crc,
            LinkError::WrongVersion { .. } => &mut self.wrong_version,
            LinkError::UnknownType { .. } => &mut self.unknown_type,
            LinkError::WrongLength { .. } => &mut self.wrong_length,
            LinkError::ValueOutOfRange { .. } => &mut self.out_of_range,
            // Encoding only; never produced by `decode`.
            LinkError::BufferTooSmall => return,
        };
        *c = c.wrapping_add(1);
    }
}

/// Cuts a byte stream into frames at each `0x00` and decodes them: one call per byte or per
/// slice, from an interrupt, a DMA ring or a polled read. Holds at most
/// [`MAX_ENCODED_LEN`] bytes (a run longer than that is refused as
/// [`LinkError::Oversized`] and skipped up to the next `0x00`). Empty frames (`0x00 0x00`) are
/// ignored, so a sender may send a `0x00` at any time to put the receiver in step.
#[derive(Clone, Debug, Default)]
pub struct Decoder {
    buf: Vec<u8, MAX_ENCODED_LEN>,
    skipping: bool,
    last_seq: Option<u16>,
    stats: LinkStats,
}

impl Decoder {
    /// A decoder waiting for the first byte of a frame.
    pub const fn new() -> Self {
        Self {
            buf: Vec::new(),
            skipping: false,
            last_seq: None,
            stats: LinkStats {
                bytes: 0,
                frames: 0,
                oversized: 0,
                bad_cobs: 0,
                too_short: 0,
                bad_crc: 0,
                wrong_version: 0,
                unknown_type: 0,
                wrong_length: 0,
                out_of_range: 0,
                sequence_gaps: 0,
            },
        }
    }

    /// Takes one byte; returns a frame or the reason one was refused when `byte` ended one (or
    /// made a run too long), `None` otherwise.
    pub fn push(&mut self, byte: u8) -> Option<Result<Frame, LinkError>> {
        self.stats.bytes = self.stats.bytes.wrapping_add(1);
        if byte != DELIMITER {
            if self.skipping {
                return None;
            }
            if self.buf.push(byte).is_err() {
                self.buf.clear();
                self.skipping = true;
                return Some(Err(self.refused(LinkError::Oversized)));
            }
            return None;
        }
        if core::mem::take(&mut self.skipping) || self.buf.is_empty() {
            return None;
        }
        let result = decode(&self.buf);
        self.buf.clear();
        Some(match result {
            Ok(frame) => {
                self.stats.frames = self.stats.frames.wrapping_add(1);
                if self
                    .last_seq
                    .is_some_and(|s| s.wrapping_add(1) != frame.seq)
                {
                    self.stats.sequence_gaps = self.stats.sequence_gaps.wrapping_add(1);
                }
                self.last_seq = Some(frame.seq);
                Ok(frame)
            }
            Err(e) => Err(self.refused(e)),
        })
    }

    /// [`Decoder::push`] for every byte of `bytes`, handing each result to `on_frame`.
    pub fn feed<F: FnMut(Result<Frame, LinkError>)>(&mut self, bytes: &[u8], mut on_frame: F) {
        for &b in bytes {
            if let Some(r) = self.push(b) {
                on_frame(r);
            }
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> LinkStats {
        self.stats
    }

    /// Bytes held of a frame not yet ended.
    pub fn buffered(&self) -> usize {
        self.buf.len()
    }

    fn refused(&mut self, e: LinkError) -> LinkError {
        self.stats.count(&e);
        e
    }
}
