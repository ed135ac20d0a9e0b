//! What the decoders share: finding a two-byte frame header in a byte stream, and counting the
//! bytes skipped while doing so.
//!
//! [`SkipCounter`] owns a decoder's [`DecoderStats`] and the "currently skipping" flag that
//! turns runs of discarded bytes into one `resyncs` count each. [`HeaderHunt`] adds the frame
//! buffer of a fixed-length frame that opens with a fixed byte followed by a byte a predicate
//! accepts (LD06: `0x54 0x2C`; XV-11: `0xFA` and an index byte): it buffers bytes from such a
//! header on, and after a rejected frame looks for the next header inside the rejected bytes.

use super::{bump, DecoderStats};

/// A decoder's counters and the state that counts runs of skipped bytes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SkipCounter {
    /// The counters reported by the decoder's `stats()`.
    pub(crate) stats: DecoderStats,
    /// Bytes are being discarded: a further skipped byte starts no new resync.
    skipping: bool,
}

impl SkipCounter {
    /// Zero counters, not skipping.
    pub(crate) const fn new() -> Self {
        Self {
            stats: DecoderStats {
                bytes: 0,
                frames_ok: 0,
                bad_checksum: 0,
                bad_frames: 0,
                implausible_frames: 0,
                skipped_bytes: 0,
                resyncs: 0,
                points: 0,
            },
            skipping: false,
        }
    }

    /// Counts `n` discarded bytes; the first discarded byte after a good frame (or at start-up)
    /// also counts one resync.
    #[inline(always)]
    pub(crate) fn skip(&mut self, n: usize) {
        if !self.skipping {
            bump(&mut self.stats.resyncs);
            self.skipping = true;
        }
        self.stats.skipped_bytes = self.stats.skipped_bytes.saturating_add(n as u32);
    }

    /// A frame was accepted: the next skipped byte starts a new resync.
    #[inline(always)]
    pub(crate) fn synced(&mut self) {
        self.skipping = false;
    }
}

/// The frame buffer and counters of a decoder of `LEN`-byte frames with a two-byte header.
#[derive(Clone, Debug)]
// Declaration order kept (the buffer first), as in `RplidarDecoder`: on a Cortex-M4 it takes
// fewer instructions per byte than the compiler's own order (`cargo xtask insns`, regions 13-16).
#[repr(C)]
pub(crate) struct HeaderHunt<const LEN: usize> {
    /// The frame being received: `buf[..len]` holds its bytes, header first.
    pub(crate) buf: [u8; LEN],
    /// Bytes of the frame held (2 or more once the header is complete).
    pub(crate) len: usize,
    /// Counters and the skip state.
    pub(crate) counter: SkipCounter,
}

impl<const LEN: usize> HeaderHunt<LEN> {
    /// Empty buffer, zero counters.
    pub(crate) const fn new() -> Self {
        Self {
            buf: [0; LEN],
            len: 0,
            counter: SkipCounter::new(),
        }
    }

    /// Takes one byte (counting it in `bytes`): looks for the header `first` followed by a byte
    /// `second` accepts, skipping what cannot start a frame, then buffers the frame's bytes.
    /// Returns true when the byte completed a frame of `LEN` bytes (the caller checks it, then
    /// calls [`HeaderHunt::accept`], [`HeaderHunt::drop_frame`] or [`HeaderHunt::rehunt`]).
    #[inline(always)]
    pub(crate) fn push(&mut self, byte: u8, first: u8, second: impl Fn(u8) -> bool) -> bool {
        bump(&mut self.counter.stats.bytes);
        match self.len {
            0 => {
                if byte == first {
                    if let Some(slot) = self.buf.first_mut() {
                        *slot = byte;
                    }
                    self.len = 1;
                } else {
                    self.counter.skip(1);
                }
                false
            }
            1 => {
                if second(byte) {
                    if let Some(slot) = self.buf.get_mut(1) {
                        *slot = byte;
                    }
                    self.len = 2;
                } else {
                    // The first byte was not a header; this byte may start one.
                    self.counter.skip(1);
                    if byte == first {
                        self.len = 1;
                    } else {
                        self.len = 0;
                        self.counter.skip(1);
                    }
                }
                false
            }
            n => {
                if let Some(slot) = self.buf.get_mut(n) {
                    *slot = byte;
                }
                self.len = n + 1;
                self.len == LEN
            }
        }
    }

    /// The frame held was good: empty the buffer and end any run of skipped bytes.
    #[inline]
    pub(crate) fn accept(&mut self) {
        self.len = 0;
        self.counter.synced();
    }

    /// The frame held was whole (its checksum passed) but its content was rejected: empty the
    /// buffer, its bytes count as a frame, not as skipped.
    #[inline]
    pub(crate) fn drop_frame(&mut self) {
        self.len = 0;
    }

    /// The frame held failed its checksum: keep, as the start of the next frame, the first
    /// header candidate after its first byte (`first` followed by a byte `second` accepts, or a
    /// `first` that ends the bytes held); the bytes before it are skipped.
    pub(crate) fn rehunt(&mut self, first: u8, second: impl Fn(u8) -> bool) {
        let held = self.len.min(LEN);
        let next = 1 + Self::candidate(self.buf.get(1..held).unwrap_or(&[]), first, second);
        self.counter.skip(next);
        self.buf.copy_within(next.min(held)..held, 0);
        self.len = held.saturating_sub(next);
    }

    /// Frames of varying length: the first `n` bytes held were a whole frame (counted by the
    /// caller, not skipped); keep what follows from its first header candidate on (the bytes
    /// before it are skipped). Only a frame that was read back from the bytes of a rejected one
    /// leaves bytes behind it.
    pub(crate) fn take_front(&mut self, n: usize, first: u8, second: impl Fn(u8) -> bool) {
        let held = self.len.min(LEN);
        let n = n.min(held);
        let p = Self::candidate(self.buf.get(n..held).unwrap_or(&[]), first, second);
        self.counter.synced();
        if p > 0 {
            self.counter.skip(p);
        }
        self.buf.copy_within((n + p).min(held)..held, 0);
        self.len = held.saturating_sub(n + p);
    }

    /// Where the first header candidate of `bytes` starts (`bytes.len()` when there is none).
    fn candidate(bytes: &[u8], first: u8, second: impl Fn(u8) -> bool) -> usize {
        bytes
            .windows(2)
            .position(|w| matches!(*w, [a, b] if a == first && second(b)))
            .or_else(|| (bytes.last() == Some(&first)).then(|| bytes.len() - 1))
            .unwrap_or(bytes.len())
    }
}
