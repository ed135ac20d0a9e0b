//! SLAMTEC RPLIDAR (A1, A2, C1, …) standard scan mode: stream decoder, node encoder, and the
//! few commands a controller sends with their responses.
//!
//! Protocol as published by SLAMTEC in *RPLIDAR Interface Protocol and Application Notes*
//! (document LR001, "standard scan" request `0x20` and its response). All multi-byte fields are
//! little-endian.
//!
//! - A **request** is `0xA5`, a command byte, and for the few commands that carry a payload a
//!   size, the payload and an XOR checksum; the commands here carry none ([`Command`]).
//! - A **response descriptor** is 7 bytes: `0xA5 0x5A`, a 32-bit word whose low 30 bits are the
//!   response length and whose top 2 bits are the send mode (0 single, 1 multiple), and a data
//!   type byte. The scan's descriptor is [`SCAN_DESCRIPTOR`] = `A5 5A 05 00 00 40 81`; GET_INFO
//!   answers `A5 5A 14 00 00 00 04` then 20 bytes ([`DeviceInfo`]); GET_HEALTH answers
//!   `A5 5A 03 00 00 00 06` then 3 bytes ([`Health`]).
//! - After the scan descriptor come 5-byte **nodes** until the controller stops the scan:
//!
//! | byte | bits |
//! |---:|---|
//! | 0 | quality (6 bits) · `!S` · `S` (S = first node of a new revolution) |
//! | 1 | angle_q6 bits 6..0 · check bit `C` (always 1) |
//! | 2 | angle_q6 bits 14..7 |
//! | 3–4 | distance_q2 (`u16`) |
//!
//! angle = angle_q6 / 64 degrees (clockwise), distance = distance_q2 / 4 millimetres; a distance
//! of 0 means no measurement. A node has no checksum: the decoder checks that `S` and `!S`
//! differ and that `C` is 1 before it emits the point, and rejects an angle ≥ 360°. Those checks
//! are weaker than a CRC (a random 5-byte window passes them one time in four), so after a failed
//! node the decoder slides by one byte, and the assembler's rotor tracking keeps stray points from
//! merging revolutions.

use super::sync::SkipCounter;
use super::{bump, DecoderStats, EncodeError, LidarPoint};

/// First byte of every request and of every response descriptor.
pub const SYNC: u8 = 0xA5;
/// Second byte of a response descriptor.
pub const SYNC2: u8 = 0x5A;
/// Bytes per scan node.
pub const NODE_LEN: usize = 5;
/// Bytes per response descriptor.
pub const DESCRIPTOR_LEN: usize = 7;
/// The response descriptor of a standard scan: 5-byte nodes, multiple responses, type `0x81`.
pub const SCAN_DESCRIPTOR: [u8; DESCRIPTOR_LEN] = [0xA5, 0x5A, 0x05, 0x00, 0x00, 0x40, 0x81];
/// Bytes of a GET_INFO response payload.
pub const INFO_LEN: usize = 20;
/// Bytes of a GET_HEALTH response payload.
pub const HEALTH_LEN: usize = 3;
/// A full turn in angle_q6 units (360 · 64).
pub const FULL_TURN_Q6: u16 = 23_040;

/// Why bytes were rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum RplidarError {
    /// Fewer bytes than the structure needs.
    Truncated(usize),
    /// A node whose start flag and inverted start flag are equal.
    BadStartFlag,
    /// A node whose check bit is 0.
    BadCheckBit,
    /// A node angle ≥ 360°.
    AngleOutOfRange,
    /// A descriptor that does not start with `0xA5 0x5A`.
    BadSync,
    /// A well-formed descriptor of a response this module does not decode.
    UnknownResponse(Descriptor),
    /// Not a request this module knows.
    UnknownCommand(u8),
}

impl core::fmt::Display for RplidarError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Truncated(n) => write!(f, "truncated at {n} bytes"),
            Self::BadStartFlag => f.write_str("start flag and inverted start flag agree"),
            Self::BadCheckBit => f.write_str("check bit is 0"),
            Self::AngleOutOfRange => f.write_str("angle of 360 degrees or more"),
            Self::BadSync => f.write_str("descriptor does not start with 0xa5 0x5a"),
            Self::UnknownResponse(d) => write!(
                f,
                "unknown response: length {}, mode {}, type {:#04x}",
                d.len, d.mode, d.data_type
            ),
            Self::UnknownCommand(c) => write!(f, "unknown command {c:#04x}"),
        }
    }
}

impl core::error::Error for RplidarError {}

/// The requests a controller sends. Each is two bytes, `0xA5` and the command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Command {
    /// `0x25`: stop scanning (no response).
    Stop,
    /// `0x40`: reset the core (no response; the sensor prints its boot banner).
    Reset,
    /// `0x20`: start a standard scan (answered by [`SCAN_DESCRIPTOR`] and nodes).
    Scan,
    /// `0x21`: start scanning whether or not the motor speed is stable.
    ForceScan,
    /// `0x50`: device information (answered by a descriptor and [`DeviceInfo`]).
    GetInfo,
    /// `0x52`: health (answered by a descriptor and [`Health`]).
    GetHealth,
}

impl Command {
    /// The command byte.
    pub const fn code(self) -> u8 {
        match self {
            Self::Stop => 0x25,
            Self::Reset => 0x40,
            Self::Scan => 0x20,
            Self::ForceScan => 0x21,
            Self::GetInfo => 0x50,
            Self::GetHealth => 0x52,
        }
    }

    /// Writes the request (`0xA5`, code) into `out`; returns 2.
    ///
    /// # Errors
    /// [`EncodeError::BufferTooSmall`].
    pub fn emit(self, out: &mut [u8]) -> Result<usize, EncodeError> {
        let given = out.len();
        match out.get_mut(..2) {
            Some(o) => {
                o.copy_from_slice(&[SYNC, self.code()]);
                Ok(2)
            }
            None => Err(EncodeError::BufferTooSmall { needed: 2, given }),
        }
    }

    /// Parses a request (what a sensor, or a simulator of one, receives).
    ///
    /// # Errors
    /// [`RplidarError::Truncated`], [`RplidarError::BadSync`], [`RplidarError::UnknownCommand`].
    pub fn parse(bytes: &[u8]) -> Result<Self, RplidarError> {
        match bytes {
            [SYNC, c, ..] => Ok(match *c {
                0x25 => Self::Stop,
                0x40 => Self::Reset,
                0x20 => Self::Scan,
                0x21 => Self::ForceScan,
                0x50 => Self::GetInfo,
                0x52 => Self::GetHealth,
                other => return Err(RplidarError::UnknownCommand(other)),
            }),
            [_, _, ..] => Err(RplidarError::BadSync),
            _ => Err(RplidarError::Truncated(bytes.len())),
        }
    }
}

/// A response descriptor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Descriptor {
    /// Length of one response (30 bits).
    pub len: u32,
    /// Send mode: 0 single response, 1 multiple responses (2 bits).
    pub mode: u8,
    /// Data type.
    pub data_type: u8,
}

impl Descriptor {
    /// The scan descriptor's fields.
    pub const SCAN: Self = Self {
        len: NODE_LEN as u32,
        mode: 1,
        data_type: 0x81,
    };
    /// The GET_INFO descriptor's fields.
    pub const INFO: Self = Self {
        len: INFO_LEN as u32,
        mode: 0,
        data_type: 0x04,
    };
    /// The GET_HEALTH descriptor's fields.
    pub const HEALTH: Self = Self {
        len: HEALTH_LEN as u32,
        mode: 0,
        data_type: 0x06,
    };

    /// Parses 7 descriptor bytes.
    ///
    /// # Errors
    /// [`RplidarError::Truncated`], [`RplidarError::BadSync`].
    pub fn parse(bytes: &[u8]) -> Result<Self, RplidarError> {
        match bytes {
            [SYNC, SYNC2, a, b, c, d, t, ..] => {
                let word = u32::from_le_bytes([*a, *b, *c, *d]);
                Ok(Self {
                    len: word & 0x3FFF_FFFF,
                    mode: (word >> 30) as u8,
                    data_type: *t,
                })
            }
            [_, _, _, _, _, _, _, ..] => Err(RplidarError::BadSync),
            _ => Err(RplidarError::Truncated(bytes.len())),
        }
    }

    /// Writes the 7 descriptor bytes; returns [`DESCRIPTOR_LEN`].
    ///
    /// # Errors
    /// [`EncodeError::BufferTooSmall`].
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        let given = out.len();
        let o = out
            .get_mut(..DESCRIPTOR_LEN)
            .ok_or(EncodeError::BufferTooSmall {
                needed: DESCRIPTOR_LEN,
                given,
            })?;
        let word = (self.len & 0x3FFF_FFFF) | (u32::from(self.mode & 3) << 30);
        let [a, b, c, d] = word.to_le_bytes();
        o.copy_from_slice(&[SYNC, SYNC2, a, b, c, d, self.data_type]);
        Ok(DESCRIPTOR_LEN)
    }
}

/// The GET_INFO response.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DeviceInfo {
    /// Model id.
    pub model: u8,
    /// Firmware version, minor part.
    pub firmware_minor: u8,
    /// Firmware version, major part.
    pub firmware_major: u8,
    /// Hardware version.
    pub hardware: u8,
    /// 128-bit serial number, as sent.
    pub serial: [u8; 16],
}

impl DeviceInfo {
    /// Parses the 20-byte payload.
    ///
    /// # Errors
    /// [`RplidarError::Truncated`].
    pub fn parse(bytes: &[u8]) -> Result<Self, RplidarError> {
        match bytes.get(..INFO_LEN) {
            Some([model, fw_minor, fw_major, hw, serial @ ..]) => {
                let mut s = [0u8; 16];
                s.copy_from_slice(serial);
                Ok(Self {
                    model: *model,
                    firmware_minor: *fw_minor,
                    firmware_major: *fw_major,
                    hardware: *hw,
                    serial: s,
                })
            }
            _ => Err(RplidarError::Truncated(bytes.len())),
        }
    }

    /// Writes the descriptor and the payload (27 bytes); returns the count.
    ///
    /// # Errors
    /// [`EncodeError::BufferTooSmall`].
    pub fn emit_response(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        let needed = DESCRIPTOR_LEN + INFO_LEN;
        let given = out.len();
        let o = out
            .get_mut(..needed)
            .ok_or(EncodeError::BufferTooSmall { needed, given })?;
        let (d, p) = o.split_at_mut(DESCRIPTOR_LEN);
        Descriptor::INFO.emit(d)?;
        let (head, serial) = p.split_at_mut(4);
        head.copy_from_slice(&[
            self.model,
            self.firmware_minor,
            self.firmware_major,
            self.hardware,
        ]);
        serial.copy_from_slice(&self.serial);
        Ok(needed)
    }
}

/// The GET_HEALTH response.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Health {
    /// 0 good, 1 warning, 2 error (the sensor's protection stop; send [`Command::Reset`]).
    pub status: u8,
    /// The sensor's error code, meaningful when `status` is not 0.
    pub error_code: u16,
}

impl Health {
    /// Parses the 3-byte payload.
    ///
    /// # Errors
    /// [`RplidarError::Truncated`].
    pub fn parse(bytes: &[u8]) -> Result<Self, RplidarError> {
        match bytes {
            [status, lo, hi, ..] => Ok(Self {
                status: *status,
                error_code: u16::from_le_bytes([*lo, *hi]),
            }),
            _ => Err(RplidarError::Truncated(bytes.len())),
        }
    }

    /// Writes the descriptor and the payload (10 bytes); returns the count.
    ///
    /// # Errors
    /// [`EncodeError::BufferTooSmall`].
    pub fn emit_response(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        let needed = DESCRIPTOR_LEN + HEALTH_LEN;
        let given = out.len();
        let o = out
            .get_mut(..needed)
            .ok_or(EncodeError::BufferTooSmall { needed, given })?;
        let (d, p) = o.split_at_mut(DESCRIPTOR_LEN);
        Descriptor::HEALTH.emit(d)?;
        let [lo, hi] = self.error_code.to_le_bytes();
        p.copy_from_slice(&[self.status, lo, hi]);
        Ok(needed)
    }
}

/// One scan node, in the protocol's units.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RplidarNode {
    /// First node of a new revolution (the `S` flag).
    pub start: bool,
    /// Quality, 0..=63 (the sensor reports 0 for no measurement).
    pub quality: u8,
    /// Angle, 1/64 degree clockwise, `< 23,040`.
    pub angle_q6: u16,
    /// Distance, 1/4 millimetre; 0 means no measurement.
    pub distance_q2: u16,
}

impl RplidarNode {
    /// Parses and checks one node (flags, check bit, angle range).
    ///
    /// # Errors
    /// [`RplidarError::Truncated`], [`RplidarError::BadStartFlag`],
    /// [`RplidarError::BadCheckBit`], [`RplidarError::AngleOutOfRange`].
    pub fn parse(bytes: &[u8]) -> Result<Self, RplidarError> {
        let [b0, b1, b2, b3, b4] = match bytes.get(..NODE_LEN) {
            Some(&[a, b, c, d, e]) => [a, b, c, d, e],
            _ => return Err(RplidarError::Truncated(bytes.len())),
        };
        if (b0 & 1) == ((b0 >> 1) & 1) {
            return Err(RplidarError::BadStartFlag);
        }
        if b1 & 1 == 0 {
            return Err(RplidarError::BadCheckBit);
        }
        let angle_q6 = u16::from(b1 >> 1) | (u16::from(b2) << 7);
        if angle_q6 >= FULL_TURN_Q6 {
            return Err(RplidarError::AngleOutOfRange);
        }
        Ok(Self {
            start: b0 & 1 == 1,
            quality: b0 >> 2,
            angle_q6,
            distance_q2: u16::from_le_bytes([b3, b4]),
        })
    }

    /// Writes the node; returns [`NODE_LEN`]. The quality is cut to 6 bits and the angle to 15
    /// (an angle ≥ 360° is written as given, for tests of the decoder's range check).
    ///
    /// # Errors
    /// [`EncodeError::BufferTooSmall`].
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        let given = out.len();
        let o = out.get_mut(..NODE_LEN).ok_or(EncodeError::BufferTooSmall {
            needed: NODE_LEN,
            given,
        })?;
        let s = u8::from(self.start);
        let b0 = ((self.quality & 0x3F) << 2) | ((s ^ 1) << 1) | s;
        let b1 = (((self.angle_q6 & 0x7F) as u8) << 1) | 1;
        let b2 = ((self.angle_q6 >> 7) & 0xFF) as u8;
        let [b3, b4] = self.distance_q2.to_le_bytes();
        o.copy_from_slice(&[b0, b1, b2, b3, b4]);
        Ok(NODE_LEN)
    }

    /// The node as a point: angle `angle_q6 / 64`°, range `distance_q2 / 4000` m, valid when the
    /// distance is not 0.
    pub fn point(&self) -> LidarPoint {
        LidarPoint {
            angle_cw_deg: f32::from(self.angle_q6) * (1.0 / 64.0),
            range_m: f32::from(self.distance_q2) * (1.0 / 4000.0),
            quality: u16::from(self.quality),
            valid: self.distance_q2 != 0,
            timestamp_ms: None,
        }
    }

    /// The node an RPLIDAR would send for a range (metres) at `angle_q6`: the distance rounded
    /// to the quarter millimetre; NaN, negative, 0 and anything past 16,383.75 mm become "no
    /// measurement" with quality 0.
    pub fn from_range_m(range_m: f32, angle_q6: u16, quality: u8, start: bool) -> Self {
        let q2 = range_m * 4000.0;
        let distance_q2 = if (0.5..65_535.5).contains(&q2) {
            (q2 + 0.5) as u16
        } else {
            0
        };
        Self {
            start,
            quality: if distance_q2 == 0 { 0 } else { quality & 0x3F },
            angle_q6,
            distance_q2,
        }
    }
}

/// Bytes needed by [`encode_revolution`] for `nodes` points.
pub const fn revolution_len(nodes: usize) -> usize {
    nodes * NODE_LEN
}

/// Writes one revolution of scan nodes (no descriptor): `ranges_m[k]` at `k · 360° / len`
/// clockwise, the first with the start flag, every measured node with `quality`. Returns the
/// bytes written.
///
/// # Errors
/// [`EncodeError::BadSampleCount`] unless `ranges_m.len()` divides 23,040 (so every angle is a
/// whole q6 value: 360 nodes give 1°, 720 give 0.5°); [`EncodeError::BufferTooSmall`].
pub fn encode_revolution(
    ranges_m: &[f32],
    quality: u8,
    out: &mut [u8],
) -> Result<usize, EncodeError> {
    let n = ranges_m.len();
    if n == 0 || usize::from(FULL_TURN_Q6) % n != 0 {
        return Err(EncodeError::BadSampleCount(n));
    }
    let needed = revolution_len(n);
    if out.len() < needed {
        return Err(EncodeError::BufferTooSmall {
            needed,
            given: out.len(),
        });
    }
    let step = FULL_TURN_Q6 / n as u16;
    for (k, (&r, dst)) in ranges_m
        .iter()
        .zip(out.chunks_exact_mut(NODE_LEN))
        .enumerate()
    {
        RplidarNode::from_range_m(r, k as u16 * step, quality, k == 0).emit(dst)?;
    }
    Ok(needed)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_are_two_bytes_and_parse_back() {
        let all = [
            (Command::Stop, 0x25),
            (Command::Reset, 0x40),
            (Command::Scan, 0x20),
            (Command::ForceScan, 0x21),
            (Command::GetInfo, 0x50),
            (Command::GetHealth, 0x52),
        ];
        for (c, code) in all {
            let mut out = [0u8; 2];
            assert_eq!(c.emit(&mut out), Ok(2));
            assert_eq!(out, [0xA5, code]);
            assert_eq!(Command::parse(&out), Ok(c));
        }
        assert_eq!(
            Command::parse(&[0xA5, 0x99]),
            Err(RplidarError::UnknownCommand(0x99))
        );
        assert!(Command::Stop.emit(&mut [0u8; 1]).is_err());
    }

    #[test]
    fn descriptors_match_the_protocol_bytes() {
        let mut out = [0u8; 7];
        Descriptor::SCAN.emit(&mut out).unwrap();
        assert_eq!(out, SCAN_DESCRIPTOR);
        Descriptor::INFO.emit(&mut out).unwrap();
        assert_eq!(out, [0xA5, 0x5A, 0x14, 0x00, 0x00, 0x00, 0x04]);
        Descriptor::HEALTH.emit(&mut out).unwrap();
        assert_eq!(out, [0xA5, 0x5A, 0x03, 0x00, 0x00, 0x00, 0x06]);
        assert_eq!(Descriptor::parse(&SCAN_DESCRIPTOR), Ok(Descriptor::SCAN));
    }

    #[test]
    fn node_bits_by_hand() {
        // quality 15, S = 1; angle 90.5° = 5,792 q6; distance 1,234.25 mm = 4,937 q2.
        let n = RplidarNode {
            start: true,
            quality: 15,
            angle_q6: 5792,
            distance_q2: 4937,
        };
        let mut b = [0u8; 5];
        n.emit(&mut b).unwrap();
        // b0 = 15<<2 | !S<<1 | S = 0x3D; b1 = (5792 & 0x7F)<<1 | 1 = 0x41; b2 = 5792>>7 = 45.
        assert_eq!(b, [0x3D, 0x41, 0x2D, 0x49, 0x13]);
        assert_eq!(RplidarNode::parse(&b), Ok(n));
        let p = n.point();
        assert_eq!(p.angle_cw_deg, 90.5);
        // f32 spacing at 1.2 m is 1.2e-7 m: two roundings (the reciprocal and the product).
        assert!((p.range_m - 1.23425).abs() <= 2.5e-7);
        let mut bad = b;
        bad[0] |= 0x02;
        assert_eq!(RplidarNode::parse(&bad), Err(RplidarError::BadStartFlag));
        let mut bad = b;
        bad[1] &= !1;
        assert_eq!(RplidarNode::parse(&bad), Err(RplidarError::BadCheckBit));
    }

    #[test]
    fn decoder_reads_info_health_then_scan() {
        let mut s = Vec::new();
        let mut buf = [0u8; 64];
        s.extend_from_slice(&[0x00, 0xA5, 0x13]); // garbage
        let info = DeviceInfo {
            model: 0x18,
            firmware_minor: 29,
            firmware_major: 1,
            hardware: 7,
            serial: [0xAB; 16],
        };
        let n = info.emit_response(&mut buf).unwrap();
        s.extend_from_slice(&buf[..n]);
        let health = Health {
            status: 1,
            error_code: 0x1234,
        };
        let n = health.emit_response(&mut buf).unwrap();
        s.extend_from_slice(&buf[..n]);
        s.extend_from_slice(&SCAN_DESCRIPTOR);
        let ranges: Vec<f32> = (0..360).map(|k| 0.5 + k as f32 * 0.01).collect();
        let mut rev = vec![0u8; revolution_len(360)];
        encode_revolution(&ranges, 40, &mut rev).unwrap();
        s.extend_from_slice(&rev);
        let mut d = RplidarDecoder::new();
        let mut pts = Vec::new();
        d.feed(&s, |p| pts.push(p));
        assert_eq!(d.info(), Some(info));
        assert_eq!(d.health(), Some(health));
        assert_eq!(pts.len(), 360);
        assert_eq!(d.start_flags(), 1);
        for (k, p) in pts.iter().enumerate() {
            assert_eq!(p.angle_cw_deg, k as f32);
            assert!((p.range_m - ranges[k]).abs() <= 0.125e-3 + 1e-6);
            assert_eq!(p.quality, 40);
        }
        let st = d.stats();
        assert_eq!(st.skipped_bytes, 3);
        assert_eq!(
            st.bytes as usize,
            5 * (st.frames_ok as usize - 2 + st.bad_frames as usize)
                + d.response_bytes() as usize
                + st.skipped_bytes as usize
                + d.buffered()
        );
    }
}
