//! Fuzzes the robot application itself (`beamfield::robot::Robot::poll`, docs/robot.md) on two
//! byte streams the harness builds from the fuzz bytes: link frames with a correct CRC (so that
//! mutations reach the application: odometry with any time and pose, initial poses with any
//! covariance, commands in any order) and LD06 revolutions and single frames with a correct CRC
//! (any ranges, speed and timestamp: clock jumps, wrong stamps, silences), plus raw runs on
//! either line, handed over in chunks whose sizes come from the input.
//!
//! Record tags (one byte each, then the record's bytes; zero-padded when the input runs out):
//! - `0`: a link frame: type byte (mod 6 + 1: the six messages to the device), 2 bytes of
//!   sequence number, then the type's payload.
//! - `1`: an LD06 revolution: speed (2 bytes), start stamp (2 bytes, mod 30,000), 8 range bytes
//!   repeated over the 360 points (range = byte · 3 cm).
//! - `2`: one LD06 frame: start angle (2 bytes, mod 36,000), speed (2), stamp (2), 12 ranges (2
//!   bytes each, mm).
//! - `3`: a raw run on the LiDAR line: length byte (mod 64), then the bytes.
//! - `4`: a raw run on the link: length byte (mod 64), then the bytes.
//! - `5`: poll: the next byte's low 4 bits are the number of polls (LiDAR and link bytes handed
//!   over as far as they go, up to 2^(high 4 bits) bytes each per poll).
//! - the first byte, when odd, is followed by a seed (x, y, θ, c_xx, c_yy, c_θθ as f32).
//!
//! Checks: no panic; after every poll, every particle's pose and weight is finite, the
//! estimate is finite, every estimate sent has a finite pose, covariance and ESS, and every seed
//! saved is finite.
//!
//! Run: `cargo +nightly fuzz run robot_poll` from `fuzz/`.

#![no_main]

use beamfield::field::free_space::{emit_free_space, free_space_len, FreeSpaceGrid};
use beamfield::field::{emit_blob, FieldHeader, FieldView, FreeSpace};
use beamfield::lidar::assembler::full_turn_layout;
use beamfield::lidar::ld06::{self, Ld06Frame, Ld06Sample};
use beamfield::link::{crc32, Message, MessageType};
use beamfield::mcl::Particles;
use beamfield::robot::{ByteSource, Robot, RobotConfig, Seed, Sink};
use beamfield::{Pose, SensorMount};
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

const W: usize = 60;
const H: usize = 40;
const CELL: f32 = 0.1;
const BEAMS: usize = 360;
const CAP: usize = 32;

fn occupied(ix: usize, iy: usize) -> bool {
    ix == 0 || iy == 0 || ix == W - 1 || iy == H - 1 || (ix == 30 && iy < 25)
}

/// A 6 m × 4 m room with a wall half across: the distance field and its free space.
fn maps() -> &'static (Vec<u8>, Vec<u8>) {
    static MAPS: OnceLock<(Vec<u8>, Vec<u8>)> = OnceLock::new();
    MAPS.get_or_init(|| {
        let header = FieldHeader::new(W as u32, H as u32, CELL, 0.0, 0.0);
        let walls: Vec<(f32, f32)> = (0..W * H)
            .filter(|&i| occupied(i % W, i / W))
            .map(|i| ((i % W) as f32, (i / W) as f32))
            .collect();
        let codes: Vec<u8> = (0..W * H)
            .map(|i| {
                let (x, y) = ((i % W) as f32, (i / W) as f32);
                let d = walls
                    .iter()
                    .map(|&(a, b)| ((a - x).powi(2) + (b - y).powi(2)).sqrt())
                    .fold(f32::INFINITY, f32::min)
                    * CELL;
                (d.min(header.max_dist_m) / header.max_dist_m * 255.0).round() as u8
            })
            .collect();
        let mut blob = vec![0u8; 64 + W * H];
        let n = emit_blob(&header, &codes, &mut blob).expect("blob");
        blob.truncate(n);
        let view = FieldView::parse(&blob).expect("view");
        let grid = FreeSpaceGrid::of_view(&view);
        let cells: Vec<bool> = (0..W * H).map(|i| !occupied(i % W, i / W)).collect();
        let mut free = vec![0u8; free_space_len(&grid, &cells).expect("free len")];
        emit_free_space(&grid, &cells, &mut free).expect("free");
        (blob, free)
    })
}

struct Input<'a>(&'a [u8]);

impl Input<'_> {
    fn byte(&mut self) -> Option<u8> {
        let (&b, rest) = self.0.split_first()?;
        self.0 = rest;
        Some(b)
    }
    fn u8(&mut self) -> u8 {
        self.byte().unwrap_or(0)
    }
    fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.u8(), self.u8()])
    }
    fn f32(&mut self) -> f32 {
        f32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }
}

/// A link frame with a correct CRC, COBS-encoded and delimited.
fn link_frame(input: &mut Input, out: &mut Vec<u8>) {
    let msg_type = input.u8() % 6 + 1;
    let len = MessageType::from_u8(msg_type).map_or(0, |t| t.payload_len());
    let mut raw = vec![1, msg_type, input.u8(), input.u8()];
    for _ in 0..len {
        raw.push(input.u8());
    }
    raw.extend_from_slice(&crc32(&raw).to_le_bytes());
    let mut encoded = vec![0u8; cobs::max_encoding_length(raw.len())];
    let n = cobs::try_encode(&raw, &mut encoded).expect("cobs");
    out.extend_from_slice(&encoded[..n]);
    out.push(0);
}

fn ld06_revolution(input: &mut Input, out: &mut Vec<u8>) {
    let speed = input.u16();
    let stamp = input.u16() % ld06::TIMESTAMP_WRAP_MS;
    let pattern: Vec<u8> = (0..8).map(|_| input.u8()).collect();
    let samples: Vec<Ld06Sample> = (0..BEAMS)
        .map(|i| Ld06Sample::from_range_m(f32::from(pattern[i % 8]) * 0.03, 200))
        .collect();
    let mut rev = vec![0u8; ld06::revolution_len(BEAMS)];
    if let Ok(n) = ld06::encode_revolution(&samples, speed, stamp, &mut rev) {
        out.extend_from_slice(&rev[..n]);
    }
}

fn ld06_frame(input: &mut Input, out: &mut Vec<u8>) {
    let start = input.u16() % 36_000;
    let speed = input.u16();
    let timestamp_ms = input.u16() % ld06::TIMESTAMP_WRAP_MS;
    let mut frame = Ld06Frame {
        speed_deg_per_s: speed,
        start_angle_cdeg: start,
        samples: [Ld06Sample::default(); 12],
        end_angle_cdeg: (start + 1100) % 36_000,
        timestamp_ms,
    };
    for s in frame.samples.iter_mut() {
        *s = Ld06Sample::from_range_m(f32::from(input.u16()) * 1e-3, 200);
    }
    let mut bytes = [0u8; ld06::FRAME_LEN];
    if let Ok(n) = frame.emit(&mut bytes) {
        out.extend_from_slice(&bytes[..n]);
    }
}

/// Hands out up to `per_poll` bytes of a stream per poll.
struct Chunk<'b> {
    bytes: &'b [u8],
    at: usize,
    left: usize,
}

impl ByteSource for Chunk<'_> {
    fn next_byte(&mut self) -> Option<u8> {
        if self.left == 0 {
            return None;
        }
        let b = *self.bytes.get(self.at)?;
        self.at += 1;
        self.left -= 1;
        Some(b)
    }
}

#[derive(Default)]
struct Check;

fn finite_cov(c: &[[f32; 3]; 3]) -> bool {
    c.iter().flatten().all(|v| v.is_finite())
}

impl Sink for Check {
    fn send(&mut self, message: &Message, _wire: &[u8]) {
        if let Message::Estimate(e) = message {
            assert!(e.pose.is_finite(), "{e:?}");
            assert!(finite_cov(&e.covariance), "{e:?}");
            assert!(e.ess.is_finite(), "{e:?}");
            assert!(e.odometry.is_finite(), "{e:?}");
        }
    }
    fn save(&mut self, seed: &Seed) {
        assert!(seed.pose.is_finite() && finite_cov(&seed.covariance), "{seed:?}");
    }
}

fuzz_target!(|data: &[u8]| {
    let (blob, free) = maps();
    let mut input = Input(data);
    let seed = if input.u8() % 2 == 1 {
        let pose = Pose::new(input.f32(), input.f32(), input.f32());
        let (xx, yy, tt) = (input.f32(), input.f32(), input.f32());
        Some(Seed {
            pose,
            covariance: [[xx, 0.0, 0.0], [0.0, yy, 0.0], [0.0, 0.0, tt]],
        })
    } else {
        None
    };
    let view = FieldView::parse(blob).expect("view");
    let free = FreeSpace::parse(free).expect("free");
    let layout = full_turn_layout::<BEAMS>(BEAMS, 8.0, SensorMount::CENTERED).expect("layout");
    let mut config = RobotConfig::new(8.0).expect("config");
    config.particles = CAP;
    config.heartbeat_period_us = 300_000;
    let mut store = Particles::<CAP>::new();
    let Ok(mut robot) = Robot::<CAP, BEAMS>::new(&mut store, view, Some(free), layout, config, seed)
    else {
        return;
    };
    let (mut lidar, mut link) = (Vec::new(), Vec::new());
    let (mut lidar_at, mut link_at) = (0usize, 0usize);
    let mut sink = Check;
    let mut polls = 0u32;
    let mut board_us = 0u64;
    while let Some(tag) = input.byte() {
        match tag % 6 {
            0 => link_frame(&mut input, &mut link),
            1 => ld06_revolution(&mut input, &mut lidar),
            2 => ld06_frame(&mut input, &mut lidar),
            3 | 4 => {
                let n = input.u8() % 64;
                let line = if tag % 6 == 3 { &mut lidar } else { &mut link };
                for _ in 0..n {
                    line.push(input.u8());
                }
            }
            _ => {
                let b = input.u8();
                let per_poll = 1usize << (b >> 4);
                for _ in 0..(b & 0x0F) {
                    let mut l = Chunk { bytes: &lidar, at: lidar_at, left: per_poll };
                    let mut k = Chunk { bytes: &link, at: link_at, left: per_poll };
                    // The board's clock: 0 to 1.27 s per poll, heartbeats and silence with it.
                    board_us += u64::from(b & 0x7F) * 10_000;
                    robot.tick(board_us, &mut sink);
                    robot.poll(&mut l, &mut k, &mut sink);
                    lidar_at = l.at;
                    link_at = k.at;
                    polls += 1;
                    if polls > 2_000 {
                        return;
                    }
                    let mcl = robot.filter();
                    assert!(mcl.poses().iter().all(Pose::is_finite));
                    assert!(mcl.weights().iter().all(|w| w.is_finite()));
                    let e = mcl.estimate();
                    assert!(e.pose.is_finite() && finite_cov(&e.covariance), "{e:?}");
                }
            }
        }
    }
    // Whatever is left, to the end.
    for _ in 0..200 {
        let mut l = Chunk { bytes: &lidar, at: lidar_at, left: usize::MAX };
        let mut k = Chunk { bytes: &link, at: link_at, left: usize::MAX };
        let p = robot.poll(&mut l, &mut k, &mut sink);
        lidar_at = l.at;
        link_at = k.at;
        let mcl = robot.filter();
        assert!(mcl.poses().iter().all(Pose::is_finite));
        assert!(mcl.weights().iter().all(|w| w.is_finite()));
        if p.is_idle() {
            break;
        }
    }
});
