//! Fuzzes the RPLIDAR decoder and the assembler behind it: fuzz bytes become scan nodes with the
//! start/inverse-start flags and the check bit set right (so mutations reach angles, distances
//! and quality), descriptors and responses, raw runs and cut nodes; see `fuzz/src/lidar_common.rs`.
//!
//! Run: `cargo +nightly fuzz run rplidar_decode` from the repository root.

#![no_main]

use beamfield::lidar::rplidar::{self, RplidarDecoder, RplidarNode};
use libfuzzer_sys::fuzz_target;

use beamfield_fuzz::lidar_common;

fuzz_target!(|data: &[u8]| {
    let (sizes, body) = data.split_at(data.len().min(4));
    let mut stream = rplidar::SCAN_DESCRIPTOR.to_vec();
    stream.extend(lidar_common::build_stream(body, 5, |b| {
        let get = |i: usize| b.get(i).copied().unwrap_or(0);
        match get(0) % 16 {
            // Now and then a response to another request in the middle of the stream.
            0 => {
                let mut out = vec![0u8; 27];
                let info = rplidar::DeviceInfo {
                    model: get(1),
                    ..Default::default()
                };
                let n = info.emit_response(&mut out).expect("27 bytes");
                out.truncate(n);
                out
            }
            1 => rplidar::SCAN_DESCRIPTOR.to_vec(),
            _ => {
                let node = RplidarNode {
                    start: get(0) & 0x80 != 0,
                    quality: get(0) & 0x3F,
                    angle_q6: u16::from_le_bytes([get(1), get(2)]) & 0x7FFF,
                    distance_q2: u16::from_le_bytes([get(3), get(4)]),
                };
                let mut out = vec![0u8; 5];
                node.emit(&mut out).expect("5 bytes");
                out
            }
        }
    }));
    lidar_common::check(RplidarDecoder::new(), &stream, sizes, 1, |d, s| {
        // frames_ok counts nodes and single responses; the responses' bytes are in
        // response_bytes, so count nodes as points.
        5 * (s.points + s.bad_frames) as usize
            + d.response_bytes() as usize
            + s.skipped_bytes as usize
            + d.buffered()
    });
});
