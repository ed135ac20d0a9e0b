//! The YDLIDAR stream decoder: the shared header hunt (`src/lidar/sync.rs`) finds and buffers
//! the packets; this file decides when a packet is whole (its LSN, and the two bytes after it)
//! and judges it.
//!
//! Contract: the judge is [`YdlidarPacket::parse`] on the bytes held, plus the rule that the next
//! packet's header follows; its verdict is settled by the hunt, which does all the counting of
//! [`DecoderStats`]. This file counts only what is YDLIDAR's own (`frame_bytes`, the zero
//! packets, the scan frequency).

use super::{
    field, packet_len, AngleCorrection, YdlidarError, YdlidarHeader, YdlidarPacket, MAX_PACKET_LEN,
    PH0, PH1,
};
use crate::lidar::sync::{HeaderHunt, Verdict};
use crate::lidar::{bump, DecoderStats, LidarPoint};

/// Bytes after a packet the decoder waits for (the next packet's header) before it takes it.
const LOOKAHEAD: usize = 2;

/// Byte-at-a-time YDLIDAR packet decoder. See the module docs for the packet and the resync rule.
#[derive(Clone, Debug)]
pub struct YdlidarDecoder {
    hunt: HeaderHunt<{ MAX_PACKET_LEN + LOOKAHEAD }, YdlidarHeader>,
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
        self.hunt.push(byte);
        let len = self.hunt.len();
        if len > field::LSN && len == self.needed() + LOOKAHEAD {
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
        packet_len(self.hunt.buf().get(field::LSN).copied().unwrap_or(0))
    }

    /// Works on the held bytes while they hold a whole packet and the two bytes after it (more
    /// than one packet only after a rejected packet handed back the bytes behind its header);
    /// with `flush`, the two bytes after the last packet are not waited for.
    fn complete(&mut self, on_point: &mut impl FnMut(LidarPoint), flush: bool) {
        loop {
            let len = self.hunt.len();
            let need = self.needed();
            if len <= field::LSN || len < need || (!flush && len < need + LOOKAHEAD) {
                return;
            }
            let buf = self.hunt.buf();
            // A packet is only taken when the next one's header follows it: a 16-bit XOR lets
            // a cut packet through whenever the bytes that fill it XOR to the missing ones (an
            // intact packet of "no measurement" samples XORs to 0 with its own check code).
            let after = buf.get(need..len.min(need + LOOKAHEAD)).unwrap_or(&[]);
            let verdict = if [PH0, PH1].starts_with(after) {
                match YdlidarPacket::parse(buf.get(..need).unwrap_or(&[])) {
                    Ok(p) => {
                        if p.is_start() {
                            bump(&mut self.start_packets);
                            self.scan_freq_decihz = p.scan_freq_decihz().or(self.scan_freq_decihz);
                        }
                        p.points(self.correction, on_point);
                        Verdict::Accept {
                            points: p.sample_count() as u32,
                        }
                    }
                    Err(e) => e.verdict(),
                }
            } else {
                // No next header where this packet ends: taken for a packet cut short.
                YdlidarError::BadHeader.verdict()
            };
            if verdict.consumes_frame() {
                self.frame_bytes = self.frame_bytes.saturating_add(need as u32);
            }
            self.hunt.settle_front(verdict, need);
        }
    }

    /// The counters. `bytes ==` [`YdlidarDecoder::frame_bytes`] `+ skipped_bytes +`
    /// [`YdlidarDecoder::buffered`] always holds; `frames_ok` counts packets.
    pub fn stats(&self) -> DecoderStats {
        self.hunt.stats()
    }

    /// Bytes of the packets counted in `frames_ok` and `bad_frames` (packets differ in length).
    pub fn frame_bytes(&self) -> u32 {
        self.frame_bytes
    }

    /// Bytes of a partial packet held.
    pub fn buffered(&self) -> usize {
        self.hunt.len()
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
