//! What the decoders share: the header hunt, the frame buffer, and the settling of each frame's
//! [`Verdict`] (what to count, what to skip, how to resynchronise).
//!
//! Contract: a decoder's frame check only judges the bytes of one frame and returns a
//! [`Verdict`]; it never touches [`DecoderStats`]. [`HeaderHunt`] owns the counters: it counts
//! every byte fed, the bytes skipped and their runs, and settles each verdict the same way for
//! every protocol (LD06, RPLIDAR, XV-11, YDLIDAR), so each counter has the one meaning
//! `DecoderStats` documents. The verdict is a plain `Copy` enum matched right after it is made:
//! once inlined it is a branch, no value is stored.
//!
//! [`HeaderHunt`] buffers frames that open with a fixed byte followed by a byte a predicate
//! accepts ([`Header`]; LD06: `0x54 0x2C`; XV-11: `0xFA` and an index byte; YDLIDAR: `AA 55`):
//! it skips what cannot start a frame, buffers bytes from such a header on, and after a rejected
//! frame looks for the next header inside the rejected bytes. Nodes without a header (RPLIDAR)
//! use the same buffer and counters, and slide by one byte after a rejected node.

use super::{bump, DecoderStats};
use core::marker::PhantomData;

/// What a decoder's check concluded about one whole frame (or node, or packet).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Verdict {
    /// The frame passed every check and its `points` were handed to the caller: counted in
    /// `frames_ok` and `points`; its bytes are consumed and any run of skipped bytes ends.
    Accept {
        /// Points the frame carried.
        points: u32,
    },
    /// The bytes failed the frame's integrity check (checksum, CRC, the check bits that stand in
    /// for one in an RPLIDAR node, or the header that must follow a YDLIDAR packet): counted in
    /// `bad_checksum`; the bytes are searched for the next header, those before it skipped.
    BadChecksum,
    /// The checksum vouches for the bytes but their content is impossible (an angle ≥ 360°, a
    /// check bit of 0, no sample): counted in `bad_frames`; the bytes are consumed as a frame
    /// (not skipped), which ends any run of skipped bytes.
    Impossible,
    /// The checksum passed but the sensor cannot have sent the frame (LD06's plausibility check),
    /// taken for damage the checksum missed: counted in `implausible_frames`; the bytes are
    /// treated as after a failed checksum.
    Implausible,
}

impl Verdict {
    /// True when the frame's bytes are consumed as a frame (accepted, or whole with impossible
    /// content); false when they are re-examined for the next header.
    #[inline(always)]
    pub(crate) const fn consumes_frame(self) -> bool {
        matches!(self, Self::Accept { .. } | Self::Impossible)
    }
}

/// A decoder's counters and the state that counts runs of skipped bytes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Counters {
    /// The counters reported by the decoder's `stats()`.
    stats: DecoderStats,
    /// Bytes are being discarded: a further skipped byte starts no new resync.
    skipping: bool,
}

impl Counters {
    /// Zero counters, not skipping.
    const fn new() -> Self {
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

    /// Counts `n` bytes fed.
    #[inline(always)]
    fn fed(&mut self, n: usize) {
        self.stats.bytes = self.stats.bytes.saturating_add(n as u32);
    }

    /// Counts `n` discarded bytes; the first discarded byte after a frame was consumed (or at
    /// start-up) also counts one resync.
    #[inline(always)]
    fn skip(&mut self, n: usize) {
        if !self.skipping {
            bump(&mut self.stats.resyncs);
            self.skipping = true;
        }
        self.stats.skipped_bytes = self.stats.skipped_bytes.saturating_add(n as u32);
    }

    /// Bytes were consumed as a frame or a header: the next skipped byte starts a new resync.
    #[inline(always)]
    fn synced(&mut self) {
        self.skipping = false;
    }

    /// Counts a verdict in its counter (see [`Verdict`]).
    #[inline(always)]
    fn count(&mut self, verdict: Verdict) {
        let s = &mut self.stats;
        match verdict {
            Verdict::Accept { points } => {
                bump(&mut s.frames_ok);
                s.points = s.points.saturating_add(points);
            }
            Verdict::BadChecksum => bump(&mut s.bad_checksum),
            Verdict::Impossible => bump(&mut s.bad_frames),
            Verdict::Implausible => bump(&mut s.implausible_frames),
        }
        if verdict.consumes_frame() {
            self.synced();
        }
    }
}

/// The two bytes that open a frame: [`Header::FIRST`], then a byte [`Header::second`] accepts.
pub(crate) trait Header {
    /// The first byte of every frame.
    const FIRST: u8;
    /// Whether `byte` may follow [`Header::FIRST`] at the start of a frame.
    fn second(byte: u8) -> bool;
}

/// The frame buffer and counters of a decoder of frames of at most `LEN` bytes that open with
/// the header `H`.
#[derive(Clone, Debug)]
// Declaration order kept (the buffer first), as in `RplidarDecoder`: on a Cortex-M4 it takes
// fewer instructions per byte than the compiler's own order (`cargo xtask insns`, regions 13-16).
#[repr(C)]
pub(crate) struct HeaderHunt<const LEN: usize, H> {
    /// The frame being received: `buf[..len]` holds its bytes, header first.
    buf: [u8; LEN],
    /// Bytes of the frame held (2 or more once the header is complete).
    len: usize,
    /// Counters and the skip state.
    counter: Counters,
    header: PhantomData<H>,
}

impl<const LEN: usize, H: Header> HeaderHunt<LEN, H> {
    /// Empty buffer, zero counters.
    pub(crate) const fn new() -> Self {
        Self {
            buf: [0; LEN],
            len: 0,
            counter: Counters::new(),
            header: PhantomData,
        }
    }

    /// The counters.
    #[inline]
    pub(crate) fn stats(&self) -> DecoderStats {
        self.counter.stats
    }

    /// Bytes held.
    #[inline(always)]
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// The whole buffer; `buf()[..len()]` are the bytes held.
    #[inline(always)]
    pub(crate) fn buf(&self) -> &[u8; LEN] {
        &self.buf
    }

    /// The bytes held.
    #[inline(always)]
    pub(crate) fn held(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }

    /// Takes one byte (counting it in `bytes`): looks for the header, skipping what cannot
    /// start a frame, then buffers the frame's bytes. Returns true when the byte completed a
    /// frame of `LEN` bytes (judge it, then [`HeaderHunt::settle`] the verdict).
    #[inline(always)]
    pub(crate) fn push(&mut self, byte: u8) -> bool {
        self.counter.fed(1);
        match self.len {
            0 => {
                if byte == H::FIRST {
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
                if H::second(byte) {
                    if let Some(slot) = self.buf.get_mut(1) {
                        *slot = byte;
                    }
                    self.len = 2;
                } else {
                    // The first byte was not a header; this byte may start one.
                    self.counter.skip(1);
                    if byte == H::FIRST {
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

    /// Feeds one byte of a stream of `LEN`-byte frames: [`HeaderHunt::push`], and when the byte
    /// completed a frame, `judge`s it and settles the verdict.
    #[inline(always)]
    pub(crate) fn push_frame_byte(
        &mut self,
        byte: u8,
        judge: &mut impl FnMut(&[u8; LEN]) -> Verdict,
    ) {
        if self.push(byte) {
            let verdict = judge(&self.buf);
            self.settle(verdict);
        }
    }

    /// Feeds bytes of a stream of `LEN`-byte frames: a whole frame that starts where a frame
    /// may start is judged in place; otherwise the header byte by byte, then the rest of the
    /// frame copied in one block; each whole frame is `judge`d and its verdict settled. The same
    /// outcome as [`HeaderHunt::push_frame_byte`] for each byte in turn.
    #[inline]
    pub(crate) fn feed_frames(
        &mut self,
        bytes: &[u8],
        mut judge: impl FnMut(&[u8; LEN]) -> Verdict,
    ) {
        let mut rest = bytes;
        while !rest.is_empty() {
            if self.len == 0 {
                // A whole frame that opens right here is judged where it lies, not copied: the
                // same counts and the same state as taking its bytes one by one.
                if let Some((frame, tail)) = rest.split_first_chunk::<LEN>() {
                    if matches!(frame.as_slice(), [a, b, ..] if *a == H::FIRST && H::second(*b)) {
                        self.counter.fed(LEN);
                        let verdict = judge(frame);
                        if verdict.consumes_frame() {
                            self.counter.count(verdict);
                        } else {
                            // Rejected: the buffer's re-hunt looks for the next header inside.
                            self.buf = *frame;
                            self.len = LEN;
                            self.settle(verdict);
                        }
                        rest = tail;
                        continue;
                    }
                }
            }
            if self.len >= 2 {
                let take = LEN.saturating_sub(self.len).min(rest.len());
                let (head, tail) = rest.split_at(take);
                if let Some(dst) = self.buf.get_mut(self.len..self.len + take) {
                    dst.copy_from_slice(head);
                }
                self.counter.fed(take);
                self.len += take;
                rest = tail;
                if self.len == LEN {
                    let verdict = judge(&self.buf);
                    self.settle(verdict);
                }
            } else if let Some((&b, tail)) = rest.split_first() {
                self.push_frame_byte(b, &mut judge);
                rest = tail;
            }
        }
    }

    /// Settles the verdict on the whole `LEN`-byte frame held: counts it; a consumed frame
    /// empties the buffer, a rejected one is searched for the next header
    /// ([`HeaderHunt::rehunt`]).
    #[inline]
    pub(crate) fn settle(&mut self, verdict: Verdict) {
        self.counter.count(verdict);
        if verdict.consumes_frame() {
            self.len = 0;
        } else {
            self.rehunt();
        }
    }

    /// Frames of varying length: settles the verdict on the frame of `n` bytes at the front of
    /// the buffer. Counts it; a consumed frame is removed and what follows it is kept from its
    /// first header candidate on (the bytes before that are skipped: only a frame read back from
    /// the bytes of a rejected one leaves bytes behind it); a rejected frame is searched for the
    /// next header ([`HeaderHunt::rehunt`]).
    ///
    /// Not inlined: it runs once per packet, and kept out of the YDLIDAR decoder's byte loop it
    /// leaves that loop its registers (inlined, the loop spilled its input pointer: `cargo xtask
    /// insns` region 17 took 797,348 instructions instead of 769,744, 4.2 more per byte).
    #[inline(never)]
    pub(crate) fn settle_front(&mut self, verdict: Verdict, n: usize) {
        self.counter.count(verdict);
        if verdict.consumes_frame() {
            let held = self.len.min(LEN);
            let n = n.min(held);
            let p = Self::candidate(self.buf.get(n..held).unwrap_or(&[]));
            if p > 0 {
                self.counter.skip(p);
            }
            self.buf.copy_within((n + p).min(held)..held, 0);
            self.len = held.saturating_sub(n + p);
        } else {
            self.rehunt();
        }
    }

    /// After a rejected frame: keep, as the start of the next frame, the first header candidate
    /// after its first byte (a header, or [`Header::FIRST`] ending the bytes held); the bytes
    /// before it are skipped.
    fn rehunt(&mut self) {
        let held = self.len.min(LEN);
        let next = 1 + Self::candidate(self.buf.get(1..held).unwrap_or(&[]));
        self.counter.skip(next);
        self.buf.copy_within(next.min(held)..held, 0);
        self.len = held.saturating_sub(next);
    }

    /// Where the first header candidate of `bytes` starts (`bytes.len()` when there is none).
    fn candidate(bytes: &[u8]) -> usize {
        bytes
            .windows(2)
            .position(|w| matches!(*w, [a, b] if a == H::FIRST && H::second(b)))
            .or_else(|| (bytes.last() == Some(&H::FIRST)).then(|| bytes.len() - 1))
            .unwrap_or(bytes.len())
    }

    /// Streams without a header on every frame (RPLIDAR): appends `byte` to the bytes held
    /// (counting it in `bytes`; a byte that finds the buffer full is counted and dropped, which
    /// a decoder that judges the front whenever it holds a whole frame never lets happen).
    #[inline(always)]
    pub(crate) fn append(&mut self, byte: u8) {
        self.counter.fed(1);
        if let Some(slot) = self.buf.get_mut(self.len) {
            *slot = byte;
            self.len += 1;
        }
    }

    /// Streams without a header on every frame: settles the verdict on the `n`-byte frame at the
    /// front of the buffer. Counts it; a consumed frame is removed; after a rejected one, returns
    /// true when the bytes held start with a header `H` (they are kept for the caller to read as
    /// one), else slides by one byte (skipped) and returns false.
    #[inline]
    pub(crate) fn settle_sliding(&mut self, verdict: Verdict, n: usize) -> bool {
        self.counter.count(verdict);
        if verdict.consumes_frame() {
            self.consume(n);
            false
        } else if matches!(*self.buf.as_slice(), [a, b, ..] if a == H::FIRST && H::second(b)) {
            true
        } else {
            self.skip_front(1);
            false
        }
    }

    /// A header of `n` bytes at the front was accepted (RPLIDAR's response descriptor): removes
    /// it; it ends any run of skipped bytes.
    #[inline]
    pub(crate) fn accept_header(&mut self, n: usize) {
        self.counter.synced();
        self.consume(n);
    }

    /// Removes `n` bytes that were used (a frame or a header).
    fn consume(&mut self, n: usize) {
        let held = self.len.min(LEN);
        let n = n.min(held);
        self.buf.copy_within(n..held, 0);
        self.len = held - n;
    }

    /// Skips the first `n` bytes held (discarded while searching).
    pub(crate) fn skip_front(&mut self, n: usize) {
        let held = self.len.min(LEN);
        let n = n.min(held);
        self.counter.skip(n);
        self.buf.copy_within(n..held, 0);
        self.len = held - n;
    }
}
