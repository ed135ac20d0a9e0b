//! The bottom layer of `src/field/`: the constants of the distance-field blob format, the byte
//! layout of its header and of the tiled payload's preamble, the CRC, and the tiled payload's
//! length arithmetic.
//!
//! Contract: this module imports nothing from `src/field/`; everything else there builds on it
//! (`grid` → `blob` → `tiled` → `view` → `likelihood`, `prepared`, `free_space`; nothing imports
//! upward). The tables `header` and `preamble` are the one statement of where each field lies:
//! the writers (`FieldHeader::write_fields`, the tiled writer) and the parsers (`parse_blob`,
//! `TiledCells::parse`) read them and no offset literal of their own. `docs/blob-format.md`
//! states the same layout for other builders.

use crc::{Crc, CRC_32_ISO_HDLC};

/// The four magic bytes at offset 0.
pub const BLOB_MAGIC: [u8; 4] = *b"BFDF";
/// The format version this crate writes and reads.
pub const BLOB_VERSION: u16 = 1;
/// Header length, bytes; the payload starts here.
pub const BLOB_HEADER_LEN: usize = 48;
/// Distance encoding 1: u8 code `c` stands for `c · d_max / 255` metres.
pub const ENCODING_U8_LINEAR: u8 = 1;
/// Distance encoding 2: u8 codes as encoding 1, in deduplicated 4 × 4 tiles.
pub const ENCODING_TILED: u8 = 2;
/// The largest code; it also stands for every distance `≥ d_max`.
pub const CODE_MAX: u8 = 255;
/// Largest accepted width or height, cells (2²⁴: every index is exact in an f32).
pub const BLOB_MAX_SIDE: u32 = 1 << 24;
/// Side of a tile, cells.
pub const TILE_SIDE: u32 = 4;
/// Cells (and bytes) per tile.
pub const TILE_CELLS: usize = 16;
/// Bytes of the tiled payload before the tile index.
pub const TILED_PREAMBLE_LEN: usize = 8;
/// Most tiles a pool can hold (the index entries are u16).
pub const TILED_MAX_POOL_TILES: u32 = 1 << 16;

/// CRC-32/ISO-HDLC, of the blob's header and payload (and of the free-space section's).
pub(crate) const CRC32: Crc<u32> = Crc::<u32>::new(&CRC_32_ISO_HDLC);

/// Where each field of the blob header lies (offsets in bytes), all little-endian.
pub(crate) mod header {
    use crate::wire::Field;

    /// Magic, [`BLOB_MAGIC`](super::BLOB_MAGIC).
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
    /// `d_max`, metres, `f32`.
    pub const MAX_DIST: Field = 28..32;
    /// Distance encoding.
    pub const ENCODING: usize = 32;
    /// Encoding 2's clamp code (reserved, zero, for encoding 1).
    pub const CLAMP_CODE: usize = 33;
    /// Reserved, zero.
    pub const RESERVED: Field = 34..36;
    /// Payload length, bytes, `u32`.
    pub const PAYLOAD_LEN: Field = 36..40;
    /// CRC-32 of the payload.
    pub const PAYLOAD_CRC: Field = 40..44;
    /// The bytes the header CRC covers.
    pub const CHECKED: Field = 0..44;
    /// CRC-32 of [`CHECKED`].
    pub const HEADER_CRC: Field = 44..48;
}

/// Where each field of the tiled payload's preamble lies (offsets in bytes from the start of
/// the payload), little-endian.
pub(crate) mod preamble {
    use crate::wire::Field;

    /// Tile side, `u16`, [`TILE_SIDE`](super::TILE_SIDE).
    pub const TILE_SIDE: Field = 0..2;
    /// Reserved, zero.
    pub const RESERVED: Field = 2..4;
    /// Tiles in the pool, `u32`.
    pub const POOL_TILES: Field = 4..8;
}

// The tables cover the header and the preamble exactly, field after field.
const _: () = {
    use header::*;
    assert!(MAGIC.start == 0 && MAGIC.end == VERSION.start && VERSION.end == HEADER_LEN.start);
    assert!(HEADER_LEN.end == WIDTH.start && WIDTH.end == HEIGHT.start);
    assert!(HEIGHT.end == CELL_SIZE.start && CELL_SIZE.end == ORIGIN_X.start);
    assert!(ORIGIN_X.end == ORIGIN_Y.start && ORIGIN_Y.end == MAX_DIST.start);
    assert!(MAX_DIST.end == ENCODING && ENCODING + 1 == CLAMP_CODE);
    assert!(CLAMP_CODE + 1 == RESERVED.start && RESERVED.end == PAYLOAD_LEN.start);
    assert!(PAYLOAD_LEN.end == PAYLOAD_CRC.start && PAYLOAD_CRC.end == HEADER_CRC.start);
    assert!(CHECKED.start == 0 && CHECKED.end == HEADER_CRC.start);
    assert!(HEADER_CRC.end == BLOB_HEADER_LEN);
    assert!(preamble::TILE_SIDE.start == 0 && preamble::TILE_SIDE.end == preamble::RESERVED.start);
    assert!(preamble::RESERVED.end == preamble::POOL_TILES.start);
    assert!(preamble::POOL_TILES.end == TILED_PREAMBLE_LEN);
};

/// The tile grid of a `width` × `height` map: tiles per row, rows of tiles, and the tile count
/// (`None` when it overflows `usize`).
pub(crate) fn tile_grid(width: u32, height: u32) -> (u32, u32, Option<usize>) {
    let tw = width.div_ceil(TILE_SIDE);
    let th = height.div_ceil(TILE_SIDE);
    (tw, th, (tw as usize).checked_mul(th as usize))
}

/// Payload length of a tiled blob of `tiles` map tiles with `pool_tiles` tiles in its pool, or
/// `None` on overflow.
pub(crate) fn tiled_payload_len(tiles: usize, pool_tiles: usize) -> Option<usize> {
    tiles
        .checked_mul(2)?
        .checked_add(TILED_PREAMBLE_LEN)?
        .checked_add(pool_tiles.checked_mul(TILE_CELLS)?)
}

/// Whether `len` is a payload length a tiled blob of a `width` × `height` map can have (checked
/// before the payload is read, like encoding 1's `W·H` rule).
#[cfg(feature = "tiled-field")]
pub(crate) fn tiled_payload_len_possible(width: u32, height: u32, len: usize) -> bool {
    let (_, _, Some(tiles)) = tile_grid(width, height) else {
        return false;
    };
    match (
        tiled_payload_len(tiles, 1),
        tiled_payload_len(tiles, TILED_MAX_POOL_TILES as usize),
    ) {
        (Some(lo), Some(hi)) => len >= lo && len <= hi && (len - lo) % TILE_CELLS == 0,
        _ => false,
    }
}
