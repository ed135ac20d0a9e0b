//! The XV-11 stream decoder: the shared header hunt (`src/lidar/sync.rs`) finds and buffers the
//! packets; this file only judges each whole packet.
//!
//! Contract: the judge is [`Xv11Packet::parse`]; on acceptance it records the speed and hands
//! the 4 readings to the caller; either way it returns a verdict and touches no counter.

use super::{Xv11Header, Xv11Packet, PACKET_LEN, READINGS_PER_PACKET};
use crate::lidar::sync::{HeaderHunt, Verdict};
use crate::lidar::{DecoderStats, LidarPoint};

/// Byte-at-a-time XV-11 stream decoder. See the module docs.
#[derive(Clone, Debug)]
pub struct Xv11Decoder {
    hunt: HeaderHunt<PACKET_LEN, Xv11Header>,
    last_speed_rpm_q6: Option<u16>,
    /// [`Xv11Decoder::feed_received`]: the receiver's time of the chunk in which the packet
    /// being buffered started, ms.
    started_ms: u16,
}

impl Default for Xv11Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Xv11Decoder {
    /// A decoder waiting for a start byte.
    pub const fn new() -> Self {
        Self {
            hunt: HeaderHunt::new(),
            last_speed_rpm_q6: None,
            started_ms: 0,
        }
    }

    /// Feeds received bytes; `on_point` is called for the 4 readings of every packet whose
    /// checksum passed.
    pub fn feed(&mut self, bytes: &[u8], mut on_point: impl FnMut(LidarPoint)) {
        for &b in bytes {
            self.push_byte(b, &mut on_point);
        }
    }

    /// Feeds a chunk of received bytes, stamping the readings with the receiver's clock (the
    /// protocol has no timestamps): `received_ms` is the receiver's millisecond clock (wrapping
    /// at 2¹⁶) when the chunk was read, and every reading of a packet is stamped with the time
    /// of the chunk in which the packet's first byte arrived, so that a revolution's first
    /// stamp is that of the chunk its first packet started in, however the bytes are split.
    ///
    /// The stamps lag the readings by up to a chunk: give them to a [`ScanAssembler`] with
    /// [`AssemblerConfig::sensor_timestamps`] `false` and
    /// [`AssemblerConfig::timestamp_wrap_ms`] 0, which then cuts revolutions by the angles
    /// alone (its scans do not depend on the chunks) and only times them with the stamps.
    ///
    /// [`ScanAssembler`]: crate::lidar::ScanAssembler
    /// [`AssemblerConfig::sensor_timestamps`]: crate::lidar::AssemblerConfig::sensor_timestamps
    /// [`AssemblerConfig::timestamp_wrap_ms`]: crate::lidar::AssemblerConfig::timestamp_wrap_ms
    pub fn feed_received(
        &mut self,
        bytes: &[u8],
        received_ms: u16,
        mut on_point: impl FnMut(LidarPoint),
    ) {
        for &b in bytes {
            if self.hunt.len() == 0 {
                // This byte may open a packet (a byte that does not is skipped, and the next
                // one sets the time again).
                self.started_ms = received_ms;
            }
            let started = self.started_ms;
            self.push_byte(b, &mut |mut p: LidarPoint| {
                p.timestamp_ms = Some(started);
                on_point(p);
            });
        }
    }

    /// Feeds one byte (see [`Xv11Decoder::feed`]).
    pub fn push_byte(&mut self, byte: u8, on_point: &mut impl FnMut(LidarPoint)) {
        let speed = &mut self.last_speed_rpm_q6;
        self.hunt.push_frame_byte(byte, &mut |packet| {
            // The verdict on a whole packet held by the hunt (it opens with `0xFA` and an
            // index byte); an accepted packet's readings go to `on_point`.
            match Xv11Packet::parse(packet) {
                Ok(p) => {
                    *speed = Some(p.speed_rpm_q6);
                    for j in 0..READINGS_PER_PACKET {
                        on_point(p.point(j));
                    }
                    Verdict::Accept {
                        points: READINGS_PER_PACKET as u32,
                    }
                }
                Err(e) => e.verdict(),
            }
        });
    }

    /// The counters. `bytes == 22 · frames_ok + skipped_bytes +` [`Xv11Decoder::buffered`]
    /// always holds (an index is checked before the packet is buffered, so `bad_frames` stays 0).
    pub fn stats(&self) -> DecoderStats {
        self.hunt.stats()
    }

    /// Bytes of a partial packet held.
    pub fn buffered(&self) -> usize {
        self.hunt.len()
    }

    /// Rotation speed of the last good packet, rpm × 64.
    pub fn last_speed_rpm_q6(&self) -> Option<u16> {
        self.last_speed_rpm_q6
    }

    /// Forgets any partial packet and zeroes the counters.
    pub fn reset(&mut self) {
        *self = Self::new();
    }
}
