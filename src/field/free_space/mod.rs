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
//!
//! Files and layering: this module holds the format's field table (`field`, read by both
//! [`FreeSpace::parse_prefix`] and [`emit_free_space`]), the parser and the queries;
//! `emit.rs` the writer. It builds on `layout` (the CRC), `grid` (the grid check) and `view`
//! (the grid of a [`FieldView`]); nothing below it imports it.

use super::grid::{check_grid, from_grid_fault, GridFault};
use super::layout::CRC32;
use super::FieldView;
use crate::gaussian::uniform_f32;
use crate::pose::Pose;
use crate::wire::{self, Field};
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

mod emit;
#[cfg(test)]
mod tests;

pub use emit::{emit_free_space, free_space_len};

/// Where each field of the section lies (offsets in bytes), all little-endian: the one table the
/// parse and the emit side read.
mod field {
    use crate::wire::Field;

    /// Magic, [`FREE_SPACE_MAGIC`](super::FREE_SPACE_MAGIC).
    pub const MAGIC: Field = 0..4;
    /// Format version, `u16`.
    pub const VERSION: Field = 4..6;
    /// Header length, `u16`.
    pub const HEADER_LEN: Field = 6..8;
    /// Width, cells, `u32`.
    pub const WIDTH: Field = 8..12;
    /// Height, cells, `u32`.
    pub const HEIGHT: Field = 12..16;
    /// Cell size, metres, `f32`.
    pub const CELL_SIZE: Field = 16..20;
    /// Origin x, metres, `f32`.
    pub const ORIGIN_X: Field = 20..24;
    /// Origin y, metres, `f32`.
    pub const ORIGIN_Y: Field = 24..28;
    /// Run count, `u32`.
    pub const RUN_COUNT: Field = 28..32;
    /// Free cell count, `u32`.
    pub const FREE_COUNT: Field = 32..36;
    /// Payload length, bytes, `u32`.
    pub const PAYLOAD_LEN: Field = 36..40;
    /// CRC-32 of the payload.
    pub const PAYLOAD_CRC: Field = 40..44;
    /// The bytes the header CRC covers.
    pub const CHECKED: Field = 0..44;
    /// CRC-32 of [`CHECKED`].
    pub const HEADER_CRC: Field = 44..48;

    /// One run, within the payload.
    pub mod run {
        use crate::wire::Field;

        /// First cell, `iy·W + ix`, `u32`.
        pub const FIRST: Field = 0..4;
        /// Free cells in all earlier runs, `u32`.
        pub const BEFORE: Field = 4..8;
    }
}

// The table covers the header and a run exactly, field after field.
const _: () = {
    use field::*;
    assert!(MAGIC.start == 0 && MAGIC.end == VERSION.start && VERSION.end == HEADER_LEN.start);
    assert!(HEADER_LEN.end == WIDTH.start && WIDTH.end == HEIGHT.start);
    assert!(HEIGHT.end == CELL_SIZE.start && CELL_SIZE.end == ORIGIN_X.start);
    assert!(ORIGIN_X.end == ORIGIN_Y.start && ORIGIN_Y.end == RUN_COUNT.start);
    assert!(RUN_COUNT.end == FREE_COUNT.start && FREE_COUNT.end == PAYLOAD_LEN.start);
    assert!(PAYLOAD_LEN.end == PAYLOAD_CRC.start && PAYLOAD_CRC.end == HEADER_CRC.start);
    assert!(CHECKED.start == 0 && CHECKED.end == HEADER_CRC.start);
    assert!(HEADER_CRC.end == FREE_SPACE_HEADER_LEN);
    assert!(run::FIRST.start == 0 && run::FIRST.end == run::BEFORE.start);
    assert!(run::BEFORE.end == FREE_SPACE_RUN_LEN);
};

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

from_grid_fault!(FreeSpaceError);

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

/// Field `f` of run `i` of `runs` (0 past the end).
#[inline]
fn run_field(runs: &[u8], i: u32, f: Field) -> u32 {
    let at = i as usize * FREE_SPACE_RUN_LEN;
    wire::get_u32(runs, at + f.start..at + f.end)
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
        if head.get(field::MAGIC) != Some(&FREE_SPACE_MAGIC[..]) {
            return Err(FreeSpaceError::BadMagic);
        }
        let version = wire::get_u16(head, field::VERSION);
        if version != FREE_SPACE_VERSION {
            return Err(FreeSpaceError::UnsupportedVersion(version));
        }
        if usize::from(wire::get_u16(head, field::HEADER_LEN)) != FREE_SPACE_HEADER_LEN {
            return Err(FreeSpaceError::BadHeaderLength);
        }
        let header_crc = wire::get_u32(head, field::HEADER_CRC);
        if CRC32.checksum(head.get(field::CHECKED).unwrap_or(&[])) != header_crc {
            return Err(FreeSpaceError::HeaderChecksum);
        }
        let grid = FreeSpaceGrid {
            width: wire::get_u32(head, field::WIDTH),
            height: wire::get_u32(head, field::HEIGHT),
            cell_size_m: wire::get_f32(head, field::CELL_SIZE),
            origin_x_m: wire::get_f32(head, field::ORIGIN_X),
            origin_y_m: wire::get_f32(head, field::ORIGIN_Y),
        };
        let cells = grid.validate()?;
        let run_count = wire::get_u32(head, field::RUN_COUNT);
        let free_count = wire::get_u32(head, field::FREE_COUNT);
        if run_count == 0 || free_count == 0 {
            return Err(FreeSpaceError::NoFreeCell);
        }
        let payload_len = wire::get_u32(head, field::PAYLOAD_LEN) as usize;
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
        if CRC32.checksum(runs) != wire::get_u32(head, field::PAYLOAD_CRC) {
            return Err(FreeSpaceError::PayloadChecksum);
        }
        // Every run: non-empty, after the previous one, inside its row.
        let mut prev_end = 0u64;
        for i in 0..run_count {
            let first = run_field(runs, i, field::run::FIRST);
            let before = run_field(runs, i, field::run::BEFORE);
            let next_before = if i + 1 < run_count {
                run_field(runs, i + 1, field::run::BEFORE)
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
        (
            run_field(self.runs, i, field::run::FIRST),
            run_field(self.runs, i, field::run::BEFORE),
        )
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
