//! Fuzzes the LD06 decoder and the assembler behind it: fuzz bytes become LD06 frames with a
//! correct CRC (so mutations reach the fields: angles, distances, timestamps), raw runs and cut
//! frames; about half the frames have their speed and angles pinned plausible
//! (`lidar_common::ld06_pin_plausible`), the rest stay random; see `fuzz/src/lidar_common.rs` for what is
//! checked.
//!
//! Run: `cargo +nightly fuzz run ld06_decode` from the repository root.

#![no_main]

use beamfield::lidar::ld06::{self, Ld06Decoder};
use libfuzzer_sys::fuzz_target;

use beamfield_fuzz::lidar_common;

fuzz_target!(|data: &[u8]| {
    let (sizes, body) = data.split_at(data.len().min(4));
    let stream = lidar_common::build_stream(body, 44, |fields| {
        let mut f = vec![0u8; ld06::FRAME_LEN];
        f[0] = ld06::HEADER;
        f[1] = ld06::VER_LEN;
        f[2..2 + fields.len()].copy_from_slice(fields);
        // Half the frames pinned plausible, so points reach the assemblers.
        lidar_common::ld06_pin_plausible(&mut f[2..46]);
        f[46] = ld06::crc8(&f[..46]);
        f
    });
    lidar_common::check(Ld06Decoder::new(), &stream, sizes, 12, |d, s| {
        ld06::FRAME_LEN * (s.frames_ok + s.bad_frames) as usize
            + s.skipped_bytes as usize
            + d.buffered()
    });
});
