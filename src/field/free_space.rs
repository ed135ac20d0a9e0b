//! The free-space section: which cells of the map are known free, packed for uniform sampling on
//! the device. Parse and emit live side by side; the layout is specified for other languages in
//! `docs/free-space-format.md`.
//!
//! The distance-field blob says how far every cell is from an obstacle but not whether it was
//! ever seen: unknown space (outside the walls) and free space both read "far from anything".
//! A localizer that spreads particles uniformly (global initialization, augmented MCL's random
//! particles, Thrun Table 8.3) needs the known-free cells. This section carries them as runs of
//! consecutive free cells within a row, each with the number of free cells before it, so a
//! uniform free cell is one random integer and a binary search away: O(log R) for R runs, no
//! table in RAM.
//!
//! ```text
//! offset size type    field
//!      0    4 [u8; 4] magic "BFFS"
//!      4    2 u16     format version = 1
//!      6    2 u16     header length = 48
//!      8    4 u32     width W, cells (x direction), 1 ..= 2^24
//!     12    4 u32     height H, cells (y direction), 1 ..= 2^24
//!     16    4 f32     cell size, metres, finite, > 0
//!     20    4 f32     origin x, metres: lower-left corner of cell (0, 0)
//!     24    4 f32     origin y, metres
//!     28    4 u32     run count R, ≥ 1
//!     32    4 u32     free cell count F, ≥ 1 (the sum of the run lengths)
//!     36    4 u32     payload length, bytes = 8·R
//!     40    4 u32     CRC-32 of the payload
//!     44    4 u32     CRC-32 of header bytes 0..44
//!     48  8·R         runs, by increasing first cell: (u32 first cell = iy·W + ix,
//!                     u32 free cells in all earlier runs)
//! ```
//!
//! Little-endian integers, IEEE 754 binary32 floats, CRC-32/ISO-HDLC: the conventions of the
//! distance-field blob (`docs/blob-format.md`). It can be linked on its own or appended right
//! after a blob in one file ([`FieldView::parse_prefix`](super::FieldView::parse_prefix) returns
//! the bytes after the blob; [`FreeSpace::parse`] reads them).

use super::blob::CRC32;
use super::grid::check_grid;
use super::FieldView;
use crate::gaussian::uniform_f32;
use crate::pose::Pose;
use core::f32::consts::PI;
use rand_core::Rng;

/// The four magic bytes at offset 0.
pub const FREE_SPACE_MAGIC: [u8; 4] = *b"BFFS";
/// The format version this crate writes and reads.
pub const FREE_SPACE_VERSION: u16 = 1;
/// Header length, bytes; the runs start here.
pub const FREE_SPACE_HEADER_LEN: usize = 48;
/// Bytes per run.
pub const FREE_SPACE_RUN_LEN: usize = 8;

/// Errors parsing or writing a free-space section.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FreeSpaceError {
    /// Fewer bytes than the header or the payload needs.
    Truncated,
    /// The first four bytes are not `BFFS`.
    BadMagic,
    /// A format version this crate does not read.
    UnsupportedVersion(u16),
    /// The header length field is not 48.
    BadHeaderLength,
    /// The header CRC does not match header bytes 0..44.
    HeaderChecksum,
    /// Width or height is zero.
    ZeroSize,
    /// Width or height above 2²⁴, or `W·H` not representable.
    TooLarge,
    /// Cell size not finite and positive.
    BadCellSize,
    /// Origin (or the far corner) not finite.
    BadOrigin,
    /// No free cell: nothing to sample from.
    NoFreeCell,
    /// The payload length is not `8·R`.
    PayloadLengthMismatch,
    /// The payload CRC does not match.
    PayloadChecksum,
    /// Run `i` is empty, out of order, overlaps the previous one or leaves its row.
    BadRun(u32),
    /// The runs do not add up to the free cell count.
    FreeCountMismatch,
    /// Bytes after the payload ([`FreeSpace::parse`] only).
    TrailingBytes,
    /// Writer: the output buffer is too short.
    BufferTooSmall,
    /// Writer: the number of cells given is not `width · height`.
    CellCountMismatch,
}

impl core::fmt::Display for FreeSpaceError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Truncated => f.write_str("free-space section truncated"),
            Self::BadMagic => f.write_str("not a free-space section (bad magic)"),
            Self::UnsupportedVersion(v) => write!(f, "unsupported free-space version {v}"),
            Self::BadHeaderLength => f.write_str("bad header length"),
            Self::HeaderChecksum => f.write_str("header checksum mismatch"),
            Self::ZeroSize => f.write_str("width or height is zero"),
            Self::TooLarge => f.write_str("grid too large"),
            Self::BadCellSize => f.write_str("cell size must be finite and > 0"),
            Self::BadOrigin => f.write_str("origin must be finite"),
            Self::NoFreeCell => f.write_str("no free cell"),
            Self::PayloadLengthMismatch => {
                f.write_str("payload length is not 8 times the run count")
            }
            Self::PayloadChecksum => f.write_str("payload checksum mismatch"),
            Self::BadRun(i) => write!(f, "run {i} is empty, out of order or leaves its row"),
            Self::FreeCountMismatch => f.write_str("runs do not add up to the free cell count"),
            Self::TrailingBytes => f.write_str("trailing bytes after the payload"),
            Self::BufferTooSmall => f.write_str("output buffer too small"),
            Self::CellCountMismatch => f.write_str("cell count is not width times height"),
        }
    }
}

impl core::error::Error for FreeSpaceError {}

/// The grid a free-space section describes: the same numbers as a distance-field blob's.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FreeSpaceGrid {
    /// Cells per row (x direction).
    pub width: u32,
    /// Rows (y direction).
    pub height: u32,
    /// Side of a square cell, metres.
    pub cell_size_m: f32,
    /// x of the lower-left corner of cell (0, 0), metres.
    pub origin_x_m: f32,
    /// y of the lower-left corner of cell (0, 0), metres.
    pub origin_y_m: f32,
}

impl FreeSpaceGrid {
    /// The grid of a distance-field view.
    pub fn of_view(view: &FieldView<'_>) -> Self {
        let h = view.header();
        Self {
            width: h.width,
            height: h.height,
            cell_size_m: h.cell_size_m,
            origin_x_m: h.origin_x_m,
            origin_y_m: h.origin_y_m,
        }
    }

    /// Checks the fields as the parser does; returns `W·H`.
    ///
    /// # Errors
    /// [`FreeSpaceError::ZeroSize`], [`FreeSpaceError::TooLarge`],
    /// [`FreeSpaceError::BadCellSize`], [`FreeSpaceError::BadOrigin`].
    pub fn validate(&self) -> Result<u32, FreeSpaceError> {
        Ok(check_grid(
            self.width,
            self.height,
            self.cell_size_m,
            self.origin_x_m,
            self.origin_y_m,
            u32::checked_mul,
        )?)
    }
}

/// A validated free-space section (zero-copy, any alignment): uniform sampling of a free cell in
/// O(log R), membership tests, all infallible after [`FreeSpace::parse`].
#[derive(Clone, Copy, Debug)]
pub struct FreeSpace<'a> {
    grid: FreeSpaceGrid,
    runs: &'a [u8],
    run_count: u32,
    free_count: u32,
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    let mut w = [0u8; 4];
    if let Some(s) = bytes.get(at..at + 4) {
        w.copy_from_slice(s);
    }
    u32::from_le_bytes(w)
}

impl<'a> FreeSpace<'a> {
    /// Parses and checks a whole section: header, both checksums, every run, exact length.
    ///
    /// # Errors
    /// Any [`FreeSpaceError`] of the format, [`FreeSpaceError::TrailingBytes`] included. Never
    /// panics, whatever the bytes.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, FreeSpaceError> {
        let (fs, rest) = Self::parse_prefix(bytes)?;
        if rest.is_empty() {
            Ok(fs)
        } else {
            Err(FreeSpaceError::TrailingBytes)
        }
    }

    /// As [`FreeSpace::parse`], for a section at the start of a longer region; returns the
    /// bytes after it.
    ///
    /// # Errors
    /// As [`FreeSpace::parse`], without [`FreeSpaceError::TrailingBytes`].
    pub fn parse_prefix(bytes: &'a [u8]) -> Result<(Self, &'a [u8]), FreeSpaceError> {
        let head = bytes
            .get(..FREE_SPACE_HEADER_LEN)
            .ok_or(FreeSpaceError::Truncated)?;
        if head.get(..4) != Some(&FREE_SPACE_MAGIC[..]) {
            return Err(FreeSpaceError::BadMagic);
        }
        let word = u32_at(head, 4);
        let version = (word & 0xFFFF) as u16;
        if version != FREE_SPACE_VERSION {
            return Err(FreeSpaceError::UnsupportedVersion(version));
        }
        if (word >> 16) as usize != FREE_SPACE_HEADER_LEN {
            return Err(FreeSpaceError::BadHeaderLength);
        }
        if CRC32.checksum(head.get(..44).unwrap_or(&[])) != u32_at(head, 44) {
            return Err(FreeSpaceError::HeaderChecksum);
        }
        let grid = FreeSpaceGrid {
            width: u32_at(head, 8),
            height: u32_at(head, 12),
            cell_size_m: f32::from_bits(u32_at(head, 16)),
            origin_x_m: f32::from_bits(u32_at(head, 20)),
            origin_y_m: f32::from_bits(u32_at(head, 24)),
        };
        let cells = grid.validate()?;
        let run_count = u32_at(head, 28);
        let free_count = u32_at(head, 32);
        if run_count == 0 || free_count == 0 {
            return Err(FreeSpaceError::NoFreeCell);
        }
        let payload_len = u32_at(head, 36) as usize;
        let expected = (run_count as usize)
            .checked_mul(FREE_SPACE_RUN_LEN)
            .ok_or(FreeSpaceError::PayloadLengthMismatch)?;
        if payload_len != expected {
            return Err(FreeSpaceError::PayloadLengthMismatch);
        }
        let end = FREE_SPACE_HEADER_LEN
            .checked_add(payload_len)
            .ok_or(FreeSpaceError::Truncated)?;
        let runs = bytes
            .get(FREE_SPACE_HEADER_LEN..end)
            .ok_or(FreeSpaceError::Truncated)?;
        if CRC32.checksum(runs) != u32_at(head, 40) {
            return Err(FreeSpaceError::PayloadChecksum);
        }
        // Every run: non-empty, after the previous one, inside its row.
        let mut prev_end = 0u64;
        for i in 0..run_count {
            let at = i as usize * FREE_SPACE_RUN_LEN;
            let first = u32_at(runs, at);
            let before = u32_at(runs, at + 4);
            let next_before = if i + 1 < run_count {
                u32_at(runs, at + 4 + FREE_SPACE_RUN_LEN)
            } else {
                free_count
            };
            let bad = FreeSpaceError::BadRun(i);
            if (i == 0 && before != 0) || next_before <= before {
                return Err(if i + 1 == run_count && next_before <= before {
                    FreeSpaceError::FreeCountMismatch
                } else {
                    bad
                });
            }
            let len = next_before - before;
            if u64::from(first) < prev_end || first >= cells {
                return Err(bad);
            }
            let col = first % grid.width;
            if u64::from(col) + u64::from(len) > u64::from(grid.width) {
                return Err(bad);
            }
            prev_end = u64::from(first) + u64::from(len);
        }
        let rest = bytes.get(end..).unwrap_or(&[]);
        Ok((
            Self {
                grid,
                runs,
                run_count,
                free_count,
            },
            rest,
        ))
    }

    /// The grid.
    pub fn grid(&self) -> &FreeSpaceGrid {
        &self.grid
    }

    /// Number of free cells.
    pub fn free_count(&self) -> u32 {
        self.free_count
    }

    /// Number of runs.
    pub fn run_count(&self) -> u32 {
        self.run_count
    }

    /// True when this section describes the grid of `view` (same size, cell and origin, bit
    /// for bit).
    pub fn matches(&self, view: &FieldView<'_>) -> bool {
        let g = FreeSpaceGrid::of_view(view);
        g.width == self.grid.width
            && g.height == self.grid.height
            && g.cell_size_m.to_bits() == self.grid.cell_size_m.to_bits()
            && g.origin_x_m.to_bits() == self.grid.origin_x_m.to_bits()
            && g.origin_y_m.to_bits() == self.grid.origin_y_m.to_bits()
    }

    fn run(&self, i: u32) -> (u32, u32) {
        let at = i as usize * FREE_SPACE_RUN_LEN;
        (u32_at(self.runs, at), u32_at(self.runs, at + 4))
    }

    /// The `k`-th free cell `(ix, iy)` in row-major order (row 0 = lowest y), `k < F`; `k ≥ F`
    /// gives the last free cell.
    pub fn nth_free_cell(&self, k: u32) -> (u32, u32) {
        let k = k.min(self.free_count - 1);
        // Largest run whose "cells before" is ≤ k (run 0 has 0).
        let (mut lo, mut hi) = (0u32, self.run_count);
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if self.run(mid).1 <= k {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (first, before) = self.run(lo);
        let cell = first + (k - before);
        (cell % self.grid.width, cell / self.grid.width)
    }

    /// True when the cell containing map point `(x_m, y_m)` is free (false off the grid or for
    /// NaN).
    pub fn is_free(&self, x_m: f32, y_m: f32) -> bool {
        let inv = 1.0 / self.grid.cell_size_m;
        let gx = (x_m - self.grid.origin_x_m) * inv;
        let gy = (y_m - self.grid.origin_y_m) * inv;
        if !(gx >= 0.0 && gy >= 0.0) {
            return false;
        }
        let (ix, iy) = (gx as u32, gy as u32);
        if ix >= self.grid.width || iy >= self.grid.height {
            return false;
        }
        let cell = iy * self.grid.width + ix;
        // Last run starting at or before `cell`.
        let (mut lo, mut hi) = (0u32, self.run_count);
        if self.run(0).0 > cell {
            return false;
        }
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if self.run(mid).0 <= cell {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (first, before) = self.run(lo);
        let next_before = if lo + 1 < self.run_count {
            self.run(lo + 1).1
        } else {
            self.free_count
        };
        cell - first < next_before - before
    }

    /// A pose uniform over the free cells (each free cell's area equally likely) with a heading
    /// uniform in `[−π, π)`.
    ///
    /// # Random numbers
    /// Exactly four `next_u32`: the cell `k = ⌊u·F / 2³²⌋` (multiply-shift; every cell gets
    /// ⌊2³²/F⌋ or ⌈2³²/F⌉ of the 2³² words, a relative bias below `F/2³²`), then x and y within
    /// the cell and the heading ([`uniform_f32`] each: `x = ox + (ix + u)·s`, `θ = π·(2u − 1)`).
    pub fn sample_pose<R: Rng + ?Sized>(&self, rng: &mut R) -> Pose {
        let u = rng.next_u32();
        let k = ((u64::from(u) * u64::from(self.free_count)) >> 32) as u32;
        let (ix, iy) = self.nth_free_cell(k);
        let fx = uniform_f32(rng);
        let fy = uniform_f32(rng);
        let ft = uniform_f32(rng);
        let s = self.grid.cell_size_m;
        Pose {
            x_m: self.grid.origin_x_m + (ix as f32 + fx) * s,
            y_m: self.grid.origin_y_m + (iy as f32 + fy) * s,
            theta_rad: PI * (2.0 * ft - 1.0),
        }
    }
}

/// Counts the runs of free cells (per row) in `free` (`W·H` flags, row-major, row 0 = lowest y)
/// and returns the section length in bytes.
///
/// # Errors
/// Grid errors as [`FreeSpaceGrid::validate`], [`FreeSpaceError::CellCountMismatch`],
/// [`FreeSpaceError::NoFreeCell`], [`FreeSpaceError::TooLarge`] when the section would exceed
/// `u32` lengths.
pub fn free_space_len(grid: &FreeSpaceGrid, free: &[bool]) -> Result<usize, FreeSpaceError> {
    let (runs, _) = count_runs(grid, free)?;
    let payload = (runs as usize)
        .checked_mul(FREE_SPACE_RUN_LEN)
        .ok_or(FreeSpaceError::TooLarge)?;
    u32::try_from(payload).map_err(|_| FreeSpaceError::TooLarge)?;
    payload
        .checked_add(FREE_SPACE_HEADER_LEN)
        .ok_or(FreeSpaceError::TooLarge)
}

fn count_runs(grid: &FreeSpaceGrid, free: &[bool]) -> Result<(u32, u32), FreeSpaceError> {
    let cells = grid.validate()?;
    if free.len() != cells as usize {
        return Err(FreeSpaceError::CellCountMismatch);
    }
    let (mut runs, mut count) = (0u32, 0u32);
    for row in free.chunks(grid.width as usize) {
        let mut prev = false;
        for &f in row {
            if f {
                count += 1;
                if !prev {
                    runs += 1;
                }
            }
            prev = f;
        }
    }
    if count == 0 {
        return Err(FreeSpaceError::NoFreeCell);
    }
    Ok((runs, count))
}

/// Writes the free-space section of `free` (`W·H` flags, row-major, row 0 = lowest y, `true` =
/// known free) into `out`; returns the bytes written ([`free_space_len`]).
///
/// # Errors
/// As [`free_space_len`], and [`FreeSpaceError::BufferTooSmall`]. Nothing is written on error.
pub fn emit_free_space(
    grid: &FreeSpaceGrid,
    free: &[bool],
    out: &mut [u8],
) -> Result<usize, FreeSpaceError> {
    let total = free_space_len(grid, free)?;
    let (runs, count) = count_runs(grid, free)?;
    let dst = out.get_mut(..total).ok_or(FreeSpaceError::BufferTooSmall)?;
    let (head, payload) = dst.split_at_mut(FREE_SPACE_HEADER_LEN);
    let mut slots = payload.chunks_exact_mut(FREE_SPACE_RUN_LEN);
    let mut before = 0u32;
    for (iy, row) in free.chunks(grid.width as usize).enumerate() {
        let mut prev = false;
        for (ix, &f) in row.iter().enumerate() {
            if f && !prev {
                if let Some(slot) = slots.next() {
                    let first = iy as u32 * grid.width + ix as u32;
                    let mut run = [0u8; FREE_SPACE_RUN_LEN];
                    run[..4].copy_from_slice(&first.to_le_bytes());
                    run[4..].copy_from_slice(&before.to_le_bytes());
                    slot.copy_from_slice(&run);
                }
            }
            before += u32::from(f);
            prev = f;
        }
    }
    let fields: [(usize, [u8; 4]); 11] = [
        (0, FREE_SPACE_MAGIC),
        (
            4,
            (u32::from(FREE_SPACE_VERSION) | ((FREE_SPACE_HEADER_LEN as u32) << 16)).to_le_bytes(),
        ),
        (8, grid.width.to_le_bytes()),
        (12, grid.height.to_le_bytes()),
        (16, grid.cell_size_m.to_le_bytes()),
        (20, grid.origin_x_m.to_le_bytes()),
        (24, grid.origin_y_m.to_le_bytes()),
        (28, runs.to_le_bytes()),
        (32, count.to_le_bytes()),
        (36, (runs * FREE_SPACE_RUN_LEN as u32).to_le_bytes()),
        (40, CRC32.checksum(payload).to_le_bytes()),
    ];
    for (at, b) in fields {
        if let Some(d) = head.get_mut(at..at + 4) {
            d.copy_from_slice(&b);
        }
    }
    let crc = CRC32.checksum(head.get(..44).unwrap_or(&[]));
    if let Some(d) = head.get_mut(44..48) {
        d.copy_from_slice(&crc.to_le_bytes());
    }
    Ok(total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mcl::SplitMix64;

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
}
