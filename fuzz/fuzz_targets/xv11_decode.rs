//! Fuzzes the XV-11 decoder and the assembler behind it: fuzz bytes become packets with a
//! correct checksum and a valid index (so mutations reach the readings and flags), raw runs and
//! cut packets; see `fuzz/src/lidar_common.rs` for what is checked.
//!
//! Run: `cargo +nightly fuzz run xv11_decode` from the repository root.

#![no_main]

use beamfield::lidar::xv11::{self, Xv11Decoder};
use libfuzzer_sys::fuzz_target;

use beamfield_fuzz::lidar_common;

fuzz_target!(|data: &[u8]| {
    let (sizes, body) = data.split_at(data.len().min(4));
    let stream = lidar_common::build_stream(body, 19, |fields| {
        let mut f = vec![0u8; xv11::PACKET_LEN];
        f[0] = xv11::START;
        f[2..2 + fields.len().min(18)].copy_from_slice(&fields[..fields.len().min(18)]);
        // The index from the last field byte, kept valid.
        f[1] = xv11::FIRST_INDEX + fields.get(18).copied().unwrap_or(0) % 90;
        let c = xv11::checksum(&f);
        f[20..22].copy_from_slice(&c.to_le_bytes());
        f
    });
    lidar_common::check(Xv11Decoder::new(), &stream, sizes, 4, |d, s| {
        xv11::PACKET_LEN * (s.frames_ok + s.bad_frames) as usize
            + s.skipped_bytes as usize
            + d.buffered()
    });
});
