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
        }
    }

    /// Feeds received bytes; `on_point` is called for the 4 readings of every packet whose
    /// checksum passed.
    pub fn feed(&mut self, bytes: &[u8], mut on_point: impl FnMut(LidarPoint)) {
        for &b in bytes {
            self.push_byte(b, &mut on_point);
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
