//! The byte-at-a-time decoder of a response stream: descriptors, single responses, then scan
//! nodes.
//!
//! Contract: the buffer and every counter of [`DecoderStats`] belong to the shared header hunt
//! (`src/lidar/sync.rs`); this file keeps the response state machine, judges each node
//! ([`RplidarNode::parse`]) and hands the verdict to the hunt, which counts it and slides past a
//! rejected node.

use super::messages::{Descriptor, DeviceInfo, Health};
use super::node::RplidarNode;
use super::{RplidarError, DESCRIPTOR_LEN, HEALTH_LEN, INFO_LEN, NODE_LEN, SYNC, SYNC2};
use crate::lidar::sync::{Header, HeaderHunt, Verdict};
use crate::lidar::{bump, DecoderStats, LidarPoint};

/// The start of a response descriptor, `A5 5A`: what a rejected node may turn out to be.
#[derive(Clone, Copy, Debug)]
struct DescriptorSync;

impl Header for DescriptorSync {
    const FIRST: u8 = SYNC;
    #[inline(always)]
    fn second(byte: u8) -> bool {
        byte == SYNC2
    }
}

impl RplidarError {
    /// What a node's rejection means for the stream (see [`Verdict`]).
    #[inline(always)]
    const fn verdict(self) -> Verdict {
        match self {
            // The node's only check of its bytes: its flag and check bits.
            Self::Truncated(_) | Self::BadStartFlag | Self::BadCheckBit => Verdict::BadChecksum,
            Self::AngleOutOfRange => Verdict::Impossible,
            // Not node errors; never returned by `RplidarNode::parse`.
            Self::BadSync | Self::UnknownResponse(_) | Self::UnknownCommand(_) => {
                Verdict::BadChecksum
            }
        }
    }
}

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
// Declaration order kept: the buffer (at offset 0 of the hunt) first spares the byte loop a base
// register (on a Cortex-M4 the compiler's own field order cost about 4% more instructions per
// byte).
#[repr(C)]
pub struct RplidarDecoder {
    hunt: HeaderHunt<INFO_LEN, DescriptorSync>,
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
            hunt: HeaderHunt::new(),
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
        self.hunt.append(byte);
        // Each pass consumes bytes, or waits for more, or moves to a state that will.
        loop {
            match self.state {
                State::Descriptor => {
                    if !self.descriptor() {
                        break;
                    }
                }
                State::Payload(n) => {
                    let n = usize::from(n);
                    if self.hunt.len() < n {
                        break;
                    }
                    self.response_bytes = self.response_bytes.saturating_add(n as u32);
                    let p = self.hunt.buf().get(..n).unwrap_or(&[]);
                    if n == INFO_LEN {
                        self.info = DeviceInfo::parse(p).ok();
                    } else {
                        self.health = Health::parse(p).ok();
                    }
                    // A single response counts in `frames_ok`, with no point.
                    self.hunt.settle_sliding(Verdict::Accept { points: 0 }, n);
                    self.state = State::Descriptor;
                }
                State::Nodes => {
                    if self.hunt.len() < NODE_LEN {
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
        let head = self.hunt.held();
        let ok_prefix = matches!(head, [SYNC] | [SYNC, SYNC2, ..]);
        if !ok_prefix {
            if head.is_empty() {
                return false;
            }
            if self.scanning {
                // Not a descriptor after all: back to nodes, from the same bytes.
                self.state = State::Nodes;
            } else {
                self.hunt.skip_front(1);
            }
            return true;
        }
        if self.hunt.len() < DESCRIPTOR_LEN {
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
                self.response_bytes = self.response_bytes.saturating_add(DESCRIPTOR_LEN as u32);
                self.hunt.accept_header(DESCRIPTOR_LEN);
                self.scanning = state == State::Nodes;
                self.state = state;
            }
            None if self.scanning => {
                // `A5 5A` inside node data: slide by one byte and read nodes again.
                self.hunt.skip_front(1);
                self.state = State::Nodes;
            }
            None => self.hunt.skip_front(1),
        }
        true
    }

    /// Judges the node at the front of the buffer; the hunt settles the verdict (after a
    /// rejected node it slides by one byte, unless `A5 5A` starts there: perhaps a new response
    /// descriptor, the scan was restarted).
    fn node(&mut self, on_point: &mut impl FnMut(LidarPoint)) {
        let verdict = match RplidarNode::parse(self.hunt.buf()) {
            Ok(node) => {
                if node.start {
                    bump(&mut self.revolutions_flagged);
                }
                on_point(node.point());
                Verdict::Accept { points: 1 }
            }
            Err(e) => e.verdict(),
        };
        if self.hunt.settle_sliding(verdict, NODE_LEN) {
            self.state = State::Descriptor;
        }
    }

    /// The counters. `frames_ok` counts nodes and single responses. Every byte is accounted
    /// for: `bytes == 5·(nodes ok + bad_frames) + response_bytes() + skipped_bytes + buffered()`,
    /// where nodes ok is `frames_ok` minus the single responses.
    pub fn stats(&self) -> DecoderStats {
        self.hunt.stats()
    }

    /// Bytes of descriptors and single-response payloads consumed.
    pub fn response_bytes(&self) -> u32 {
        self.response_bytes
    }

    /// Bytes held of an incomplete node, descriptor or response.
    pub fn buffered(&self) -> usize {
        self.hunt.len()
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
