//! The byte-at-a-time decoder of a response stream: descriptors, single responses, then scan
//! nodes.

use super::messages::{Descriptor, DeviceInfo, Health};
use super::node::RplidarNode;
use super::{RplidarError, DESCRIPTOR_LEN, HEALTH_LEN, INFO_LEN, NODE_LEN, SYNC, SYNC2};
use crate::lidar::sync::SkipCounter;
use crate::lidar::{bump, DecoderStats, LidarPoint};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Waiting for, or reading, a response descriptor.
    Descriptor,
    /// Reading a single response of this many bytes, of this type.
    Payload(u8),
    /// Reading scan nodes.
    Nodes,
}

/// Byte-at-a-time RPLIDAR response decoder: descriptors, GET_INFO and GET_HEALTH responses, and
/// the nodes of a standard scan.
#[derive(Clone, Debug)]
// Declaration order kept: the buffer at offset 0 spares the byte loop a base register (on a
// Cortex-M4 the compiler's own field order cost about 4% more instructions per byte).
#[repr(C)]
pub struct RplidarDecoder {
    buf: [u8; INFO_LEN],
    len: usize,
    counter: SkipCounter,
    state: State,
    response_bytes: u32,
    info: Option<DeviceInfo>,
    health: Option<Health>,
    revolutions_flagged: u32,
    /// A scan descriptor was seen (or the decoder was built scanning): a failed descriptor is
    /// node data.
    scanning: bool,
}

impl Default for RplidarDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl RplidarDecoder {
    /// A decoder waiting for a response descriptor (after the controller sent a request).
    pub const fn new() -> Self {
        Self {
            state: State::Descriptor,
            buf: [0; INFO_LEN],
            len: 0,
            counter: SkipCounter::new(),
            response_bytes: 0,
            info: None,
            health: None,
            revolutions_flagged: 0,
            scanning: false,
        }
    }

    /// A decoder that takes nodes straight away (a receiver attached to a sensor that is
    /// already scanning, whose descriptor went by).
    pub const fn scanning() -> Self {
        let mut d = Self::new();
        d.state = State::Nodes;
        d.scanning = true;
        d
    }

    /// Feeds received bytes; `on_point` is called for each node that passed its checks.
    pub fn feed(&mut self, bytes: &[u8], mut on_point: impl FnMut(LidarPoint)) {
        for &b in bytes {
            self.push_byte(b, &mut on_point);
        }
    }

    /// Feeds one byte (see [`RplidarDecoder::feed`]).
    pub fn push_byte(&mut self, byte: u8, on_point: &mut impl FnMut(LidarPoint)) {
        bump(&mut self.counter.stats.bytes);
        if let Some(slot) = self.buf.get_mut(self.len) {
            *slot = byte;
            self.len += 1;
        }
        // Each pass consumes bytes, or waits for more, or moves to a state that will.
        loop {
            match self.state {
                State::Descriptor => {
                    if !self.descriptor() {
                        break;
                    }
                }
                State::Payload(n) => {
                    if self.len < usize::from(n) {
                        break;
                    }
                    self.response_bytes = self.response_bytes.saturating_add(u32::from(n));
                    let p = self.buf.get(..usize::from(n)).unwrap_or(&[]);
                    if usize::from(n) == INFO_LEN {
                        self.info = DeviceInfo::parse(p).ok();
                    } else {
                        self.health = Health::parse(p).ok();
                    }
                    bump(&mut self.counter.stats.frames_ok);
                    self.consume(usize::from(n));
                    self.state = State::Descriptor;
                }
                State::Nodes => {
                    if self.len < NODE_LEN {
                        break;
                    }
                    self.node(on_point);
                }
            }
        }
    }

    /// Works on a (possible) descriptor at the front of the buffer; false when it needs more
    /// bytes.
    fn descriptor(&mut self) -> bool {
        let head = self.buf.get(..self.len).unwrap_or(&[]);
        let ok_prefix = matches!(head, [SYNC] | [SYNC, SYNC2, ..]);
        if !ok_prefix {
            if head.is_empty() {
                return false;
            }
            if self.scanning {
                // Not a descriptor after all: back to nodes, from the same bytes.
                self.state = State::Nodes;
            } else {
                self.drop_front(1);
            }
            return true;
        }
        if self.len < DESCRIPTOR_LEN {
            return false;
        }
        let next = match Descriptor::parse(head) {
            Ok(Descriptor::SCAN) => Some(State::Nodes),
            Ok(Descriptor::INFO) => Some(State::Payload(INFO_LEN as u8)),
            Ok(Descriptor::HEALTH) => Some(State::Payload(HEALTH_LEN as u8)),
            _ => None,
        };
        match next {
            Some(state) => {
                self.counter.synced();
                self.response_bytes = self.response_bytes.saturating_add(DESCRIPTOR_LEN as u32);
                self.consume(DESCRIPTOR_LEN);
                self.scanning = state == State::Nodes;
                self.state = state;
            }
            None if self.scanning => {
                // `A5 5A` inside node data: slide by one byte and read nodes again.
                self.drop_front(1);
                self.state = State::Nodes;
            }
            None => self.drop_front(1),
        }
        true
    }

    fn node(&mut self, on_point: &mut impl FnMut(LidarPoint)) {
        match RplidarNode::parse(self.buf.get(..NODE_LEN).unwrap_or(&[])) {
            Ok(node) => {
                self.consume(NODE_LEN);
                self.counter.synced();
                bump(&mut self.counter.stats.frames_ok);
                bump(&mut self.counter.stats.points);
                if node.start {
                    bump(&mut self.revolutions_flagged);
                }
                on_point(node.point());
            }
            Err(RplidarError::AngleOutOfRange) => {
                self.consume(NODE_LEN);
                bump(&mut self.counter.stats.bad_frames);
            }
            Err(_) => {
                bump(&mut self.counter.stats.bad_checksum);
                if self.buf.starts_with(&[SYNC, SYNC2]) {
                    // Perhaps a new response descriptor (the scan was restarted).
                    self.state = State::Descriptor;
                } else {
                    self.drop_front(1);
                }
            }
        }
    }

    /// Removes `n` bytes that were used.
    fn consume(&mut self, n: usize) {
        let n = n.min(self.len);
        self.buf.copy_within(n..self.len, 0);
        self.len -= n;
    }

    fn drop_front(&mut self, n: usize) {
        let n = n.min(self.len);
        self.counter.skip(n);
        self.buf.copy_within(n..self.len, 0);
        self.len -= n;
    }

    /// The counters. `frames_ok` counts nodes and single responses. Every byte is accounted
    /// for: `bytes == 5·(nodes ok + bad_frames) + response_bytes() + skipped_bytes + buffered()`,
    /// where nodes ok is `frames_ok` minus the single responses.
    pub fn stats(&self) -> DecoderStats {
        self.counter.stats
    }

    /// Bytes of descriptors and single-response payloads consumed.
    pub fn response_bytes(&self) -> u32 {
        self.response_bytes
    }

    /// Bytes held of an incomplete node, descriptor or response.
    pub fn buffered(&self) -> usize {
        self.len
    }

    /// The last GET_INFO response received.
    pub fn info(&self) -> Option<DeviceInfo> {
        self.info
    }

    /// The last GET_HEALTH response received.
    pub fn health(&self) -> Option<Health> {
        self.health
    }

    /// Nodes received with the start flag set (one per revolution the sensor began).
    pub fn start_flags(&self) -> u32 {
        self.revolutions_flagged
    }

    /// Forgets everything and waits for a descriptor.
    pub fn reset(&mut self) {
        *self = Self::new();
    }
}
