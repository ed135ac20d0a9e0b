//! Distance encoding 2, *tiled*: the same u8 codes as encoding 1 (lossless, so every score is
//! unchanged bit for bit), stored as 4 × 4-cell tiles with identical tiles kept once. The
//! writer ([`emit_blob_tiled`]) and the parser (`TiledCells::parse`, used by
//! [`FieldView::parse`](super::FieldView::parse)) live here side by side;
//! the layout is specified for other builders in `docs/blob-format.md`.
//!
//! ```text
//! payload offset  size           field
//!              0     2 u16        tile side = 4
//!              2     2 u16        reserved, zero
//!              4     4 u32        P, tiles in the pool, 1 ≤ P ≤ 65,536
//!              8  2·TW·TH u16[]   tile index: pool tile of each map tile, TW = ⌈W/4⌉ per row,
//!                                 TH = ⌈H/4⌉ rows, row 0 = lowest y; every entry < P
//!  8 + 2·TW·TH   16·P [u8; 16][]  pool: 16 codes per tile, row-major inside the tile
//! ```
//!
//! A cell `(ix, iy)` is code `lx + 4·ly` of pool tile `index[(iy/4)·TW + ix/4]`, with
//! `lx = ix mod 4`, `ly = iy mod 4`: two loads, whatever the map. Cells of the last column or
//! row of tiles that lie beyond the map repeat the nearest cell on the map (readers never see
//! them; the rule makes the output canonical and helps tiles repeat). The pool holds tiles in
//! the order of their first appearance in the index, so a builder's output is unique.
//!
//! Why 4 × 4 and raw codes: measured on the TurtleBot3, Willow Garage and Intel maps at 5 cm,
//! `docs/blob-format.md` lists the alternatives (larger tiles, per-tile base and narrow
//! residuals, per-tile planes); this is the one whose lookup stays within a few instructions of
//! a raw byte read.
//!
//! Layering: the preamble's offsets, the constants and the payload-length arithmetic are in
//! `src/field/layout.rs` (which `blob` reads too, to check a tiled payload's length without
//! importing this module); this module builds on `blob` and `layout` only.

use super::blob::{BlobError, FieldHeader};
use super::layout::{self, preamble as field, tiled_payload_len as payload_len, CRC32};
use super::layout::{BLOB_HEADER_LEN, CODE_MAX};
pub use super::layout::{
    ENCODING_TILED, TILED_MAX_POOL_TILES, TILED_PREAMBLE_LEN, TILE_CELLS, TILE_SIDE,
};
use crate::wire;

/// The tile grid of a map: tiles per row, rows of tiles, tiles.
fn tile_grid(header: &FieldHeader) -> Result<(u32, u32, usize), BlobError> {
    header.validate()?;
    match layout::tile_grid(header.width, header.height) {
        (tw, th, Some(tiles)) => Ok((tw, th, tiles)),
        _ => Err(BlobError::TooLarge),
    }
}

/// Length of the `scratch` [`emit_blob_tiled`] needs for `header`, in `u32`s: a hash table of
/// twice the tile count (rounded up to a power of two) plus one entry per tile.
///
/// # Errors
/// As [`FieldHeader::validate`].
pub fn tiled_scratch_len(header: &FieldHeader) -> Result<usize, BlobError> {
    let (_, _, tiles) = tile_grid(header)?;
    let table = tiles
        .checked_mul(2)
        .and_then(usize::checked_next_power_of_two)
        .ok_or(BlobError::TooLarge)?;
    table.checked_add(tiles).ok_or(BlobError::TooLarge)
}

/// The longest tiled blob `header` can give (no two tiles alike), bytes: a safe size for the
/// output buffer of [`emit_blob_tiled`], which returns the length it used.
///
/// # Errors
/// As [`FieldHeader::validate`].
pub fn tiled_max_len(header: &FieldHeader) -> Result<usize, BlobError> {
    let (_, _, tiles) = tile_grid(header)?;
    let pool = tiles.min(TILED_MAX_POOL_TILES as usize);
    payload_len(tiles, pool)
        .and_then(|p| p.checked_add(BLOB_HEADER_LEN))
        .ok_or(BlobError::TooLarge)
}

/// The 16 codes of map tile `(tx, ty)`, row-major, cells beyond the map repeating the nearest
/// cell on it. `codes` has `w · h` entries (checked by the callers).
fn gather(codes: &[u8], w: u32, h: u32, tx: u32, ty: u32) -> [u8; TILE_CELLS] {
    let mut tile = [CODE_MAX; TILE_CELLS];
    for (k, c) in tile.iter_mut().enumerate() {
        let x = (tx * TILE_SIDE + (k as u32 % TILE_SIDE)).min(w - 1) as usize;
        let y = (ty * TILE_SIDE + (k as u32 / TILE_SIDE)).min(h - 1) as usize;
        *c = codes.get(y * w as usize + x).copied().unwrap_or(CODE_MAX);
    }
    tile
}

/// FNV-1a over a tile's 16 bytes.
fn tile_hash(tile: &[u8; TILE_CELLS]) -> u32 {
    tile.iter().fold(0x811c_9dc5u32, |h, &b| {
        (h ^ u32::from(b)).wrapping_mul(0x0100_0193)
    })
}

/// Writes a tiled blob (encoding 2) of `codes` (`width · height` of them, row 0 = lowest y,
/// as [`emit_blob`](super::emit_blob) takes them) into `out`; returns the bytes written.
///
/// `scratch` holds at least [`tiled_scratch_len`] entries (its contents are overwritten);
/// `out` needs the returned length, at most [`tiled_max_len`]. Time linear in the cells
/// (one hash-table probe per tile).
///
/// # Errors
/// Header errors as [`FieldHeader::validate`], [`BlobError::CellCountMismatch`],
/// [`BlobError::ScratchTooSmall`], [`BlobError::TooManyTiles`] (more than 65,536 distinct
/// tiles: write encoding 1), [`BlobError::BufferTooSmall`].
pub fn emit_blob_tiled(
    header: &FieldHeader,
    codes: &[u8],
    scratch: &mut [u32],
    out: &mut [u8],
) -> Result<usize, BlobError> {
    emit_blob_tiled_clamped(header, codes, 0, scratch, out)
}

/// As [`emit_blob_tiled`], with every code above `clamp_code` stored as `clamp_code` and the
/// clamp code recorded in the header (byte 33), so that readers know that code means "at least
/// this far" ([`FieldView::clamp_m`](super::FieldView::clamp_m)). `clamp_code` 0 writes no
/// clamp (exactly [`emit_blob_tiled`]). Distances up to `clamp_code · step` keep their codes;
/// far from walls the tiles become uniform and are stored once. The clamp code is
/// [`FieldHeader::encode_distance_m`] of the clamp distance.
///
/// # Errors
/// As [`emit_blob_tiled`]; [`BlobError::BadClamp`] for a clamp code of 255 (use 0: no clamp).
pub fn emit_blob_tiled_clamped(
    header: &FieldHeader,
    codes: &[u8],
    clamp_code: u8,
    scratch: &mut [u32],
    out: &mut [u8],
) -> Result<usize, BlobError> {
    if clamp_code == CODE_MAX {
        return Err(BlobError::BadClamp);
    }
    let top = if clamp_code == 0 {
        CODE_MAX
    } else {
        clamp_code
    };
    let cells = header.validate()?;
    if codes.len() != cells {
        return Err(BlobError::CellCountMismatch);
    }
    let (tw, _, tiles) = tile_grid(header)?;
    let need = tiled_scratch_len(header)?;
    let scratch = scratch.get_mut(..need).ok_or(BlobError::ScratchTooSmall)?;
    let cap = need - tiles;
    let (table, ids) = scratch.split_at_mut(cap);
    table.fill(0);
    let (w, h) = (header.width, header.height);
    let at = |t: usize| gather(codes, w, h, t as u32 % tw, t as u32 / tw).map(|c| c.min(top));
    // Pass 1: the pool tile of each map tile, pool tiles numbered by first appearance.
    let mut pool_tiles = 0u32;
    for t in 0..tiles {
        let tile = at(t);
        let mut slot = tile_hash(&tile) as usize & (cap - 1);
        let id = loop {
            let Some(entry) = table.get_mut(slot) else {
                return Err(BlobError::ScratchTooSmall);
            };
            if *entry == 0 {
                // Table entries are `t + 1` (0 is empty); t < tiles ≤ u32::MAX by validate.
                *entry = t as u32 + 1;
                pool_tiles += 1;
                break pool_tiles - 1;
            }
            let seen = (*entry - 1) as usize;
            if at(seen) == tile {
                break ids.get(seen).copied().unwrap_or(0);
            }
            slot = (slot + 1) & (cap - 1);
        };
        if let Some(d) = ids.get_mut(t) {
            *d = id;
        }
    }
    if pool_tiles > TILED_MAX_POOL_TILES {
        return Err(BlobError::TooManyTiles);
    }
    let len = payload_len(tiles, pool_tiles as usize).ok_or(BlobError::TooLarge)?;
    let total = len
        .checked_add(BLOB_HEADER_LEN)
        .ok_or(BlobError::TooLarge)?;
    let payload_len32 = u32::try_from(len).map_err(|_| BlobError::TooLarge)?;
    let blob = out.get_mut(..total).ok_or(BlobError::BufferTooSmall)?;
    let (head, payload) = blob.split_at_mut(BLOB_HEADER_LEN);
    // Pass 2: preamble, index, pool.
    let (pre, rest) = payload.split_at_mut(TILED_PREAMBLE_LEN);
    pre.copy_from_slice(&preamble(pool_tiles));
    let (index, pool) = rest.split_at_mut(tiles * 2);
    let mut next = 0u32;
    let pairs = index.chunks_exact_mut(2);
    for (t, (pair, &id)) in pairs.zip(ids.iter()).enumerate() {
        pair.copy_from_slice(&(id as u16).to_le_bytes());
        if id == next {
            let start = id as usize * TILE_CELLS;
            if let Some(dst) = pool.get_mut(start..start + TILE_CELLS) {
                dst.copy_from_slice(&at(t));
            }
            next += 1;
        }
    }
    let payload_crc = CRC32.checksum(payload);
    let mut hd = [0u8; BLOB_HEADER_LEN];
    header.write_fields(
        &mut hd,
        ENCODING_TILED,
        clamp_code,
        payload_len32,
        payload_crc,
    );
    head.copy_from_slice(&hd);
    Ok(total)
}

/// The preamble of a payload with `pool_tiles` tiles.
fn preamble(pool_tiles: u32) -> [u8; TILED_PREAMBLE_LEN] {
    let mut p = [0u8; TILED_PREAMBLE_LEN];
    wire::put_u16(&mut p, field::TILE_SIDE, TILE_SIDE as u16);
    wire::put_u16(&mut p, field::RESERVED, 0);
    wire::put_u32(&mut p, field::POOL_TILES, pool_tiles);
    p
}

/// A validated tiled payload: every index entry names a pool tile, so a lookup of a cell on
/// the map never misses (the accessors still return `Option`: no panic path whatever).
#[cfg(feature = "tiled-field")]
#[derive(Clone, Copy, Debug)]
pub(crate) struct TiledCells<'a> {
    /// The tile index (`2·TW·TH` bytes: u16 little-endian pool tile numbers) followed by the
    /// pool (`16·P` bytes): one slice, so the per-beam loop keeps one pointer and one length.
    tables: &'a [u8],
    /// Offset of the pool in `tables`, bytes (`2·TW·TH`).
    pool_at: usize,
    /// `TW`, tiles per row.
    tiles_w: u32,
}

#[cfg(feature = "tiled-field")]
impl<'a> TiledCells<'a> {
    /// Checks a tiled payload (its length and CRC already checked against the header) and
    /// the header's clamp code (`0`: none).
    ///
    /// # Errors
    /// [`BlobError::BadTileTable`] (tile side not 4, reserved bytes not zero, pool size 0,
    /// above 65,536 or not the one the payload length implies), [`BlobError::TileIndexOutOfRange`]
    /// (an index entry names no pool tile), [`BlobError::BadClamp`] (clamp code 255, or a pool
    /// code above a non-zero clamp code), [`BlobError::Truncated`].
    pub(crate) fn parse(
        header: &FieldHeader,
        payload: &'a [u8],
        clamp_code: u8,
    ) -> Result<Self, BlobError> {
        let (tw, _, tiles) = tile_grid(header)?;
        let pre = payload
            .get(..TILED_PREAMBLE_LEN)
            .ok_or(BlobError::Truncated)?;
        let side = wire::get_u16(pre, field::TILE_SIDE);
        let reserved = wire::get_u16(pre, field::RESERVED);
        let pool_tiles = wire::get_u32(pre, field::POOL_TILES);
        if u32::from(side) != TILE_SIDE
            || reserved != 0
            || pool_tiles == 0
            || pool_tiles > TILED_MAX_POOL_TILES
            || payload_len(tiles, pool_tiles as usize) != Some(payload.len())
        {
            return Err(BlobError::BadTileTable);
        }
        let rest = payload.get(TILED_PREAMBLE_LEN..).unwrap_or(&[]);
        let index = rest.get(..tiles * 2).ok_or(BlobError::Truncated)?;
        if index.chunks_exact(2).any(|p| match p {
            [lo, hi] => u32::from(u16::from_le_bytes([*lo, *hi])) >= pool_tiles,
            _ => true,
        }) {
            return Err(BlobError::TileIndexOutOfRange);
        }
        let pool = rest.get(tiles * 2..).unwrap_or(&[]);
        if clamp_code == CODE_MAX || (clamp_code != 0 && pool.iter().any(|&c| c > clamp_code)) {
            return Err(BlobError::BadClamp);
        }
        Ok(Self {
            tables: rest,
            pool_at: tiles * 2,
            tiles_w: tw,
        })
    }

    /// The code of cell `(ix, iy)`, for `ix < W`, `iy < H` (the caller's check); `None` only
    /// if that precondition is broken and the cell falls outside the tables.
    #[inline(always)]
    pub(crate) fn code(&self, ix: u32, iy: u32) -> Option<u8> {
        let t = (iy >> 2) as usize * self.tiles_w as usize + (ix >> 2) as usize;
        let pair: [u8; 2] = self.tables.get(t * 2..t * 2 + 2)?.try_into().ok()?;
        let local = ((iy & 3) << 2 | (ix & 3)) as usize;
        let tile = usize::from(u16::from_le_bytes(pair)) * TILE_CELLS;
        self.tables.get(self.pool_at + (tile | local)).copied()
    }

    /// Tiles in the pool.
    pub(crate) fn pool_tiles(&self) -> usize {
        (self.tables.len() - self.pool_at) / TILE_CELLS
    }

    /// The per-beam loop's reader for a map of `height` cells: only the rows of tiles that
    /// lie wholly on the map (`⌊H/4⌋` of them), so that one bounds check on the index stands
    /// for the row test; cells of a last, partial row of tiles are left to the caller's slow
    /// path ([`TiledCells::code`]).
    pub(crate) fn full_rows(&self, height: u32) -> FullTileRows<'a> {
        let full = (height / TILE_SIDE) as usize * self.tiles_w as usize * 2;
        let (index, pool) = self.tables.split_at(self.pool_at.min(self.tables.len()));
        FullTileRows {
            index: index.get(..full).unwrap_or(&[]),
            pool,
            tiles_w: self.tiles_w,
        }
    }
}

/// The rows of tiles wholly on the map, for the fixed-point per-beam loop
/// ([`TiledCells::full_rows`]).
#[cfg(feature = "tiled-field")]
#[derive(Clone, Copy, Debug)]
pub(crate) struct FullTileRows<'a> {
    /// Index entries of the full rows of tiles only (`2·TW·⌊H/4⌋` bytes).
    index: &'a [u8],
    /// The pool.
    pool: &'a [u8],
    /// `TW`.
    tiles_w: u32,
}

#[cfg(feature = "tiled-field")]
impl FullTileRows<'_> {
    /// The code of cell `(ix, iy)` when `ix < W` (the caller's check) and `iy` is in a full row
    /// of tiles; `None` for any other row (below the map, wrapped negative, in the partial
    /// last row of tiles or above the map): rows past the index fall past its end.
    #[inline(always)]
    pub(crate) fn code(&self, ix: u32, iy: u32) -> Option<u8> {
        let t = (iy >> 2) as usize * self.tiles_w as usize + (ix >> 2) as usize;
        let pair: [u8; 2] = self.index.get(t * 2..t * 2 + 2)?.try_into().ok()?;
        let local = ((iy & 3) << 2 | (ix & 3)) as usize;
        let tile = usize::from(u16::from_le_bytes(pair)) * TILE_CELLS;
        self.pool.get(tile | local).copied()
    }
}

#[cfg(test)]
#[cfg(feature = "tiled-field")]
mod tests {
    use super::super::blob::parse_blob;
    use super::super::layout::CRC32;
    use super::super::view::FieldView;
    use super::*;

    fn tiled(h: &FieldHeader, codes: &[u8]) -> Vec<u8> {
        let mut scratch = vec![0u32; tiled_scratch_len(h).unwrap()];
        let mut out = vec![0u8; tiled_max_len(h).unwrap()];
        let n = emit_blob_tiled(h, codes, &mut scratch, &mut out).unwrap();
        out.truncate(n);
        out
    }

    /// Recomputes both CRCs after an edit of the payload (so the edit reaches its own check).
    fn reseal(b: &mut [u8]) {
        let crc = CRC32.checksum(&b[48..]);
        b[40..44].copy_from_slice(&crc.to_le_bytes());
        let crc = CRC32.checksum(&b[..44]);
        b[44..48].copy_from_slice(&crc.to_le_bytes());
    }

    /// A 5 × 3 map laid out by hand from the format's rules: two tiles per row of tiles, one
    /// row; the right tile repeats column 4, the top row of both repeats row 2.
    #[test]
    fn hand_laid_out_payload() {
        let h = FieldHeader::new(5, 3, 0.05, 0.0, 0.0);
        let codes: Vec<u8> = (1..=15).collect();
        let b = tiled(&h, &codes);
        let mut want = vec![4, 0, 0, 0, 2, 0, 0, 0, 0, 0, 1, 0];
        want.extend([1, 2, 3, 4, 6, 7, 8, 9, 11, 12, 13, 14, 11, 12, 13, 14]);
        want.extend([5, 5, 5, 5, 10, 10, 10, 10, 15, 15, 15, 15, 15, 15, 15, 15]);
        assert_eq!(&b[48..], &want[..]);
        assert_eq!(b[32], ENCODING_TILED);
        assert_eq!(u32::from_le_bytes(b[36..40].try_into().unwrap()), 44);
        let v = FieldView::parse(&b).unwrap();
        for iy in 0..3 {
            for ix in 0..5 {
                assert_eq!(v.code(ix, iy), Some(codes[(iy * 5 + ix) as usize]));
            }
        }
        assert_eq!(v.code(5, 0), None);
        assert_eq!(v.code(0, 3), None);
        assert_eq!(v.codes(), &[] as &[u8]);
        assert_eq!(v.pool_tiles(), Some(2));
    }

    /// Identical tiles are stored once: an 8 × 8 map of one value has a one-tile pool and an
    /// all-zero index.
    #[test]
    fn identical_tiles_stored_once() {
        let h = FieldHeader::new(8, 8, 0.05, 0.0, 0.0);
        let b = tiled(&h, &[255; 64]);
        let mut want = vec![4, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];
        want.extend([255; 16]);
        assert_eq!(&b[48..], &want[..]);
    }

    /// The 5 × 3 map of `hand_laid_out_payload` clamped at code 10: codes above 10 become 10,
    /// byte 33 records it, and the view reports it.
    #[test]
    fn clamped_payload_by_hand() {
        let h = FieldHeader::new(5, 3, 0.05, 0.0, 0.0);
        let codes: Vec<u8> = (1..=15).collect();
        let mut scratch = vec![0u32; tiled_scratch_len(&h).unwrap()];
        let mut b = vec![0u8; tiled_max_len(&h).unwrap()];
        let n = emit_blob_tiled_clamped(&h, &codes, 10, &mut scratch, &mut b).unwrap();
        b.truncate(n);
        let mut want = vec![4, 0, 0, 0, 2, 0, 0, 0, 0, 0, 1, 0];
        want.extend([1, 2, 3, 4, 6, 7, 8, 9, 10, 10, 10, 10, 10, 10, 10, 10]);
        want.extend([5, 5, 5, 5, 10, 10, 10, 10, 10, 10, 10, 10, 10, 10, 10, 10]);
        assert_eq!(&b[48..], &want[..]);
        assert_eq!(b[33], 10);
        let v = FieldView::parse(&b).unwrap();
        assert_eq!(v.clamp_code(), Some(10));
        assert_eq!(v.clamp_m(), Some(10.0 * (2.0f32 / 255.0)));
        assert_eq!(v.code(4, 2), Some(10));
        assert_eq!(v.code(3, 0), Some(4));
        // No clamp: byte 33 zero, no clamp reported.
        assert_eq!(
            FieldView::parse(&tiled(&h, &codes)).unwrap().clamp_code(),
            None
        );
        // A pool code above the clamp, and a clamp code of 255, are typed errors.
        let mut above = b.clone();
        above[60] = 11;
        reseal(&mut above);
        assert_eq!(FieldView::parse(&above).err(), Some(BlobError::BadClamp));
        let mut top = b.clone();
        top[33] = 255;
        reseal(&mut top);
        assert_eq!(FieldView::parse(&top).err(), Some(BlobError::BadClamp));
        assert_eq!(
            emit_blob_tiled_clamped(&h, &codes, 255, &mut scratch, &mut b),
            Err(BlobError::BadClamp)
        );
    }

    #[test]
    fn inconsistent_tables_are_typed_errors() {
        let h = FieldHeader::new(5, 3, 0.05, 0.0, 0.0);
        let codes: Vec<u8> = (1..=15).collect();
        let good = tiled(&h, &codes);
        type Edit = fn(&mut Vec<u8>);
        let cases: [(Edit, BlobError); 6] = [
            (|b| b[48] = 8, BlobError::BadTileTable),
            (|b| b[50] = 1, BlobError::BadTileTable),
            // Pool size 1 while the payload holds two tiles.
            (|b| b[52] = 1, BlobError::BadTileTable),
            (|b| b[52..56].fill(0), BlobError::BadTileTable),
            (|b| b[58] = 2, BlobError::TileIndexOutOfRange),
            (|b| b[59] = 0x80, BlobError::TileIndexOutOfRange),
        ];
        for (i, (edit, want)) in cases.into_iter().enumerate() {
            let mut b = good.clone();
            edit(&mut b);
            reseal(&mut b);
            assert_eq!(FieldView::parse(&b).err(), Some(want), "case {i}");
        }
        // A payload length no tiled payload of this grid can have (not 8 + 4 + 16·P).
        let mut b = good.clone();
        b.push(0);
        b[36] = 45;
        reseal(&mut b);
        assert_eq!(parse_blob(&b).err(), Some(BlobError::PayloadLengthMismatch));
    }

    #[test]
    fn writer_errors() {
        let h = FieldHeader::new(5, 3, 0.05, 0.0, 0.0);
        let codes = [0u8; 15];
        let mut out = [0u8; 200];
        let mut small = [0u32; 4];
        assert_eq!(
            emit_blob_tiled(&h, &codes, &mut small, &mut out),
            Err(BlobError::ScratchTooSmall)
        );
        let mut scratch = vec![0u32; tiled_scratch_len(&h).unwrap()];
        assert_eq!(
            emit_blob_tiled(&h, &codes[..14], &mut scratch, &mut out),
            Err(BlobError::CellCountMismatch)
        );
        // 48 + 8 + 4 + 16 (one tile) = 76 bytes needed.
        assert_eq!(
            emit_blob_tiled(&h, &codes, &mut scratch, &mut out[..75]),
            Err(BlobError::BufferTooSmall)
        );
        assert_eq!(emit_blob_tiled(&h, &codes, &mut scratch, &mut out), Ok(76));
    }

    /// More than 65,536 distinct tiles cannot be indexed by u16: a typed error.
    #[test]
    fn too_many_tiles() {
        // 1024 × 1028 cells: 256 · 257 = 65,792 tiles, each distinct (its number in its first
        // three cells).
        let (w, hgt) = (1024u32, 1028u32);
        let h = FieldHeader::new(w, hgt, 0.05, 0.0, 0.0);
        let mut codes = vec![0u8; (w * hgt) as usize];
        let tw = w / 4;
        for ty in 0..hgt / 4 {
            for tx in 0..tw {
                let t = ty * tw + tx;
                let i = (ty * 4 * w + tx * 4) as usize;
                codes[i] = t as u8;
                codes[i + 1] = (t >> 8) as u8;
                codes[i + 2] = (t >> 16) as u8;
            }
        }
        let mut scratch = vec![0u32; tiled_scratch_len(&h).unwrap()];
        let mut out = vec![0u8; tiled_max_len(&h).unwrap()];
        assert_eq!(
            emit_blob_tiled(&h, &codes, &mut scratch, &mut out),
            Err(BlobError::TooManyTiles)
        );
    }
}
