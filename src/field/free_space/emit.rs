//! The writer of the free-space section: counts the runs of a grid's free cells and writes the
//! header and the runs.
//!
//! Contract: every field goes through the table `field` of the module, the one
//! [`FreeSpace::parse`](super::FreeSpace::parse) reads; nothing is written on error.

use super::{
    field, FreeSpaceError, FreeSpaceGrid, FREE_SPACE_HEADER_LEN, FREE_SPACE_MAGIC,
    FREE_SPACE_RUN_LEN, FREE_SPACE_VERSION,
};
use crate::field::layout::CRC32;
use crate::wire;

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
                    wire::put_u32(slot, field::run::FIRST, first);
                    wire::put_u32(slot, field::run::BEFORE, before);
                }
            }
            before += u32::from(f);
            prev = f;
        }
    }
    wire::put(head, field::MAGIC, &FREE_SPACE_MAGIC);
    wire::put_u16(head, field::VERSION, FREE_SPACE_VERSION);
    wire::put_u16(head, field::HEADER_LEN, FREE_SPACE_HEADER_LEN as u16);
    wire::put_u32(head, field::WIDTH, grid.width);
    wire::put_u32(head, field::HEIGHT, grid.height);
    wire::put_f32(head, field::CELL_SIZE, grid.cell_size_m);
    wire::put_f32(head, field::ORIGIN_X, grid.origin_x_m);
    wire::put_f32(head, field::ORIGIN_Y, grid.origin_y_m);
    wire::put_u32(head, field::RUN_COUNT, runs);
    wire::put_u32(head, field::FREE_COUNT, count);
    wire::put_u32(head, field::PAYLOAD_LEN, runs * FREE_SPACE_RUN_LEN as u32);
    wire::put_u32(head, field::PAYLOAD_CRC, CRC32.checksum(payload));
    let crc = CRC32.checksum(head.get(field::CHECKED).unwrap_or(&[]));
    wire::put_u32(head, field::HEADER_CRC, crc);
    Ok(total)
}
