//! Unit tests of the free-space section: round trips, sampling, membership and every check of
//! the parser.

use super::*;
use crate::mcl::SplitMix64;

/// The little-endian `u32` at byte `at`, read by hand (independently of the module's table).
fn u32_at(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap())
}

fn grid(w: u32, h: u32) -> FreeSpaceGrid {
    FreeSpaceGrid {
        width: w,
        height: h,
        cell_size_m: 0.5,
        origin_x_m: -1.0,
        origin_y_m: 2.0,
    }
}

/// 4 × 3, free cells marked `#` (row 0 at the bottom):
/// ```text
/// row 2: # # . #
/// row 1: . . . .
/// row 0: . # # .
/// ```
fn sample_flags() -> Vec<bool> {
    let rows = [".##.", "....", "##.#"];
    rows.iter()
        .flat_map(|r| r.chars().map(|c| c == '#'))
        .collect()
}

fn emitted(g: &FreeSpaceGrid, f: &[bool]) -> Vec<u8> {
    let n = free_space_len(g, f).unwrap();
    let mut out = vec![0u8; n];
    assert_eq!(emit_free_space(g, f, &mut out).unwrap(), n);
    out
}

#[test]
fn round_trip_and_layout() {
    let g = grid(4, 3);
    let f = sample_flags();
    let bytes = emitted(&g, &f);
    // Three runs: cell 1 (len 2), cell 8 (len 2), cell 11 (len 1); 5 free cells.
    assert_eq!(bytes.len(), 48 + 3 * 8);
    assert_eq!(&bytes[..4], b"BFFS");
    assert_eq!(u32_at(&bytes, 28), 3);
    assert_eq!(u32_at(&bytes, 32), 5);
    let runs: Vec<u32> = (0..6).map(|i| u32_at(&bytes, 48 + 4 * i)).collect();
    assert_eq!(runs, [1, 0, 8, 2, 11, 4]);
    let fs = FreeSpace::parse(&bytes).unwrap();
    assert_eq!(fs.free_count(), 5);
    let cells: Vec<_> = (0..5).map(|k| fs.nth_free_cell(k)).collect();
    assert_eq!(cells, [(1, 0), (2, 0), (0, 2), (1, 2), (3, 2)]);
    for iy in 0..3u32 {
        for ix in 0..4u32 {
            let x = -1.0 + (ix as f32 + 0.5) * 0.5;
            let y = 2.0 + (iy as f32 + 0.5) * 0.5;
            assert_eq!(fs.is_free(x, y), f[(iy * 4 + ix) as usize], "{ix},{iy}");
        }
    }
    assert!(!fs.is_free(f32::NAN, 2.1));
    assert!(!fs.is_free(-1.1, 2.1));
}

#[test]
fn samples_are_uniform_over_free_cells() {
    let g = grid(4, 3);
    let f = sample_flags();
    let bytes = emitted(&g, &f);
    let fs = FreeSpace::parse(&bytes).unwrap();
    let mut rng = SplitMix64::new(3);
    let mut hits = [0u32; 12];
    let n = 50_000;
    for _ in 0..n {
        let p = fs.sample_pose(&mut rng);
        assert!(fs.is_free(p.x_m, p.y_m));
        assert!((-PI..PI).contains(&p.theta_rad));
        let ix = ((p.x_m + 1.0) / 0.5) as usize;
        let iy = ((p.y_m - 2.0) / 0.5) as usize;
        hits[iy * 4 + ix] += 1;
    }
    for (i, &h) in hits.iter().enumerate() {
        if f[i] {
            // Expected n/5 = 10000, σ ≈ 89: 5σ.
            assert!((h as i32 - 10_000).abs() < 450, "cell {i}: {h}");
        } else {
            assert_eq!(h, 0);
        }
    }
}

#[test]
fn every_truncation_and_bit_flip_is_a_typed_error() {
    let g = grid(4, 3);
    let bytes = emitted(&g, &sample_flags());
    for n in 0..bytes.len() {
        assert!(FreeSpace::parse(&bytes[..n]).is_err(), "prefix {n}");
    }
    for i in 0..bytes.len() * 8 {
        let mut b = bytes.clone();
        b[i / 8] ^= 1 << (i % 8);
        assert!(FreeSpace::parse(&b).is_err(), "bit {i}");
    }
    let mut long = bytes.clone();
    long.push(0);
    assert_eq!(
        FreeSpace::parse(&long).err(),
        Some(FreeSpaceError::TrailingBytes)
    );
    let (_, rest) = FreeSpace::parse_prefix(&long).unwrap();
    assert_eq!(rest, [0]);
}

#[test]
fn writer_errors() {
    let g = grid(4, 3);
    assert_eq!(
        free_space_len(&g, &[false; 12]),
        Err(FreeSpaceError::NoFreeCell)
    );
    assert_eq!(
        free_space_len(&g, &[true; 11]),
        Err(FreeSpaceError::CellCountMismatch)
    );
    let mut small = [0u8; 50];
    assert_eq!(
        emit_free_space(&g, &sample_flags(), &mut small),
        Err(FreeSpaceError::BufferTooSmall)
    );
    assert_eq!(
        free_space_len(&grid(0, 3), &[]),
        Err(FreeSpaceError::ZeroSize)
    );
}
