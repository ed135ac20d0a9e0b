//! Fuzzes the YDLIDAR decoder and the assemblers behind it: fuzz bytes become packets of fuzzed
//! type, sample count (0..=40), angles (check bits set, 15-bit angles, so some are ≥ 360°) and
//! samples with a correct check code (so mutations reach the contents, the angle correction and
//! the assemblers), raw runs and cut packets; see `fuzz/src/lidar_common.rs` for what is checked. The byte
//! accounting of packets of varying length uses the decoder's `frame_bytes()`.
//!
//! Run: `cargo +nightly fuzz run ydlidar_decode` from the repository root.

#![no_main]

use beamfield::lidar::ydlidar::{self, YdlidarDecoder};
use libfuzzer_sys::fuzz_target;

use beamfield_fuzz::lidar_common;

/// Type, count, FSA, LSA, then up to 40 samples.
const FIELDS: usize = 6 + 2 * 40;

fuzz_target!(|data: &[u8]| {
    let (sizes, body) = data.split_at(data.len().min(4));
    let stream = lidar_common::build_stream(body, FIELDS, |fields| {
        let byte = |i: usize| fields.get(i).copied().unwrap_or(0);
        let word = |i: usize| u16::from_le_bytes([byte(i), byte(i + 1)]);
        let n = usize::from(byte(1)) % 41;
        let samples: Vec<u16> = (0..n).map(|i| word(6 + 2 * i)).collect();
        let mut f = vec![0u8; ydlidar::packet_len(n as u8)];
        // `emit_packet` sets the check bits and the check code.
        ydlidar::emit_packet(byte(0), word(2) >> 1, word(4) >> 1, &samples, &mut f)
            .expect("room for the packet");
        f
    });
    lidar_common::check(YdlidarDecoder::new(), &stream, sizes, 0, |d, s| {
        d.frame_bytes() as usize + s.skipped_bytes as usize + d.buffered()
    });
});
