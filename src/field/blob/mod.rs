//! The distance-field blob, format version 1: one definition for the host writer and the device
//! parser (docs/models.md#blob). The full specification, for third-party builders, is
//! `docs/blob-format.md`; this module is its reference implementation.
//!
//! ```text
//! offset size type    field
//!      0    4 [u8; 4] magic "BFDF"
//!      4    2 u16     format version = 1
//!      6    2 u16     header length = 48
//!      8    4 u32     width, cells (x direction), ≥ 1
//!     12    4 u32     height, cells (y direction), ≥ 1
//!     16    4 f32     cell size, metres, finite, > 0
//!     20    4 f32     origin x, metres: lower-left corner of cell (0, 0)
//!     24    4 f32     origin y, metres
//!     28    4 f32     d_max, metres, finite, > 0: distances are clamped here
//!     32    1 u8      distance encoding = 1 (u8 code c means c · d_max / 255 metres)
//!     33    3 [u8; 3] reserved, zero
//!     36    4 u32     payload length, bytes = width · height
//!     40    4 u32     CRC-32 of the payload
//!     44    4 u32     CRC-32 of header bytes 0..44
//!     48    …         payload: width · height codes, row-major, row 0 = lowest y, column 0 = lowest x
//! ```
//!
//! All multi-byte fields are little-endian; floats are IEEE 754 binary32. The CRC is CRC-32/ISO-HDLC
//! (the zlib/PNG/Ethernet CRC: reflected polynomial 0x04C11DB7, init and final XOR 0xFFFFFFFF),
//! computed with the `crc` crate (no_std, a 1 KiB table in flash).
//!
//! Trailing bytes: [`FieldView::parse`](super::FieldView::parse) rejects them (a blob linked
//! with `include_bytes!` has its exact length); [`FieldView::parse_prefix`](super::FieldView::parse_prefix)
//! accepts a blob at the start of a longer region (a flash partition) and returns the rest.
//!
//! Layering: the offsets of the header's fields and the format's constants are in
//! `src/field/layout.rs`, the bottom of `src/field/`, which both `FieldHeader::write_fields`
//! and `parse_blob` read; this module imports only it and `grid` (the grid check), never the
//! encodings built on it (`tiled`) or the views above. [`BlobError`] is in `error.rs`.

use super::grid::check_grid;
use super::layout::{header as field, CRC32};
#[cfg(feature = "tiled-field")]
use super::layout::{tiled_payload_len_possible, ENCODING_TILED};
pub use super::layout::{
    BLOB_HEADER_LEN, BLOB_MAGIC, BLOB_MAX_SIDE, BLOB_VERSION, CODE_MAX, ENCODING_U8_LINEAR,
};
use crate::wire;

mod error;
#[cfg(test)]
mod tests;

pub use error::BlobError;

/// Default `d_max`, metres: AMCL's `laser_likelihood_max_dist`.
pub const DEFAULT_MAX_DIST_M: f32 = 2.0;

/// Everything a blob's header says about its grid.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FieldHeader {
    /// Cells per row (x direction).
    pub width: u32,
    /// Rows (y direction).
    pub height: u32,
    /// Side of a square cell, metres.
    pub cell_size_m: f32,
    /// x of the lower-left corner of cell (0, 0), metres (map_server's `origin[0]`).
    pub origin_x_m: f32,
    /// y of the lower-left corner of cell (0, 0), metres (map_server's `origin[1]`).
    pub origin_y_m: f32,
    /// Clamp distance `d_max`, metres; code 255 means "≥ d_max".
    pub max_dist_m: f32,
}

impl FieldHeader {
    /// A header with the default `d_max` ([`DEFAULT_MAX_DIST_M`]).
    pub const fn new(
        width: u32,
        height: u32,
        cell_size_m: f32,
        origin_x_m: f32,
        origin_y_m: f32,
    ) -> Self {
        Self {
            width,
            height,
            cell_size_m,
            origin_x_m,
            origin_y_m,
            max_dist_m: DEFAULT_MAX_DIST_M,
        }
    }

    /// Checks every field as the parser does and returns the cell count.
    ///
    /// # Errors
    /// [`BlobError::ZeroSize`], [`BlobError::TooLarge`], [`BlobError::BadCellSize`],
    /// [`BlobError::BadOrigin`], [`BlobError::BadMaxDist`].
    pub fn validate(&self) -> Result<usize, BlobError> {
        let cells = check_grid(
            self.width,
            self.height,
            self.cell_size_m,
            self.origin_x_m,
            self.origin_y_m,
            |w, h| {
                let cells = usize::try_from(w)
                    .ok()?
                    .checked_mul(usize::try_from(h).ok()?)?;
                cells.checked_add(BLOB_HEADER_LEN).map(|_| cells)
            },
        )?;
        let d = self.max_dist_m;
        if !(d.is_finite() && d > 0.0) {
            return Err(BlobError::BadMaxDist);
        }
        Ok(cells)
    }

    /// Total blob length in bytes (header plus one byte per cell).
    ///
    /// # Errors
    /// A [`BlobError`], as [`FieldHeader::validate`].
    pub fn required_len(&self) -> Result<usize, BlobError> {
        let cells = self.validate()?;
        cells
            .checked_add(BLOB_HEADER_LEN)
            .ok_or(BlobError::TooLarge)
    }

    /// One code step, metres: `d_max / 255`.
    pub fn step_m(&self) -> f32 {
        self.max_dist_m / f32::from(CODE_MAX)
    }

    /// The code for a distance in metres: `round(d / step)`, clamped to `0..=255`.
    ///
    /// Computed in f64 so the host and the device agree on ties. NaN and negative distances
    /// give 0, `+∞` gives 255.
    pub fn encode_distance_m(&self, distance_m: f64) -> u8 {
        let steps = distance_m * f64::from(CODE_MAX) / f64::from(self.max_dist_m);
        let r = crate::math::floor_f64(steps + 0.5);
        if r >= f64::from(CODE_MAX) {
            CODE_MAX
        } else if r >= 0.0 {
            r as u8
        } else {
            0
        }
    }

    /// The code of a cell from its exact squared distance in **cell units** (as
    /// [`squared_edt`](super::squared_edt) produces; [`EDT_INFINITY`](super::EDT_INFINITY)
    /// gives 255).
    pub fn encode_squared_cells(&self, squared_cells: u32) -> u8 {
        if squared_cells == super::EDT_INFINITY {
            return CODE_MAX;
        }
        let d_m = crate::math::sqrt_f64(f64::from(squared_cells)) * f64::from(self.cell_size_m);
        self.encode_distance_m(d_m)
    }

    /// Writes the whole header: these fields, the given encoding, clamp code and payload
    /// length and CRC, and the header CRC (the writer's half of `parse_blob`, through the same
    /// table).
    pub(crate) fn write_fields(
        &self,
        head: &mut [u8; BLOB_HEADER_LEN],
        encoding: u8,
        clamp_code: u8,
        payload_len: u32,
        payload_crc: u32,
    ) {
        wire::put(head, field::MAGIC, &BLOB_MAGIC);
        wire::put_u16(head, field::VERSION, BLOB_VERSION);
        wire::put_u16(head, field::HEADER_LEN, BLOB_HEADER_LEN as u16);
        wire::put_u32(head, field::WIDTH, self.width);
        wire::put_u32(head, field::HEIGHT, self.height);
        wire::put_f32(head, field::CELL_SIZE, self.cell_size_m);
        wire::put_f32(head, field::ORIGIN_X, self.origin_x_m);
        wire::put_f32(head, field::ORIGIN_Y, self.origin_y_m);
        wire::put_f32(head, field::MAX_DIST, self.max_dist_m);
        head[field::ENCODING] = encoding;
        head[field::CLAMP_CODE] = clamp_code;
        wire::put(head, field::RESERVED, &[0, 0]);
        wire::put_u32(head, field::PAYLOAD_LEN, payload_len);
        wire::put_u32(head, field::PAYLOAD_CRC, payload_crc);
        let crc = CRC32.checksum(head.get(field::CHECKED).unwrap_or(&[]));
        wire::put_u32(head, field::HEADER_CRC, crc);
    }
}

/// Writes a blob from ready-made codes (`width · height` of them, row 0 = lowest y) into `out`.
///
/// Returns the number of bytes written ([`FieldHeader::required_len`]); bytes of `out` past
/// that are left untouched.
///
/// # Errors
/// Header errors as [`FieldHeader::validate`], [`BlobError::CellCountMismatch`],
/// [`BlobError::BufferTooSmall`]. Nothing is written on error.
pub fn emit_blob(header: &FieldHeader, codes: &[u8], out: &mut [u8]) -> Result<usize, BlobError> {
    emit_with(header, codes.len(), out, |payload| {
        payload.copy_from_slice(codes);
    })
}

/// Writes a blob from exact squared distances in cell units (the output of
/// [`squared_edt`](super::squared_edt)), encoding each with [`FieldHeader::encode_squared_cells`].
///
/// # Errors
/// A [`BlobError`], as [`emit_blob`].
pub fn emit_blob_from_squared_cells(
    header: &FieldHeader,
    squared_cells: &[u32],
    out: &mut [u8],
) -> Result<usize, BlobError> {
    emit_with(header, squared_cells.len(), out, |payload| {
        for (d, &s) in payload.iter_mut().zip(squared_cells) {
            *d = header.encode_squared_cells(s);
        }
    })
}

fn emit_with(
    header: &FieldHeader,
    count: usize,
    out: &mut [u8],
    fill: impl FnOnce(&mut [u8]),
) -> Result<usize, BlobError> {
    let cells = header.validate()?;
    if count != cells {
        return Err(BlobError::CellCountMismatch);
    }
    let total = header.required_len()?;
    let payload_len = u32::try_from(cells).map_err(|_| BlobError::TooLarge)?;
    let blob = out.get_mut(..total).ok_or(BlobError::BufferTooSmall)?;
    let (head, payload) = blob.split_at_mut(BLOB_HEADER_LEN);
    fill(payload);
    let payload_crc = CRC32.checksum(payload);
    let mut h = [0u8; BLOB_HEADER_LEN];
    header.write_fields(&mut h, ENCODING_U8_LINEAR, 0, payload_len, payload_crc);
    head.copy_from_slice(&h);
    Ok(total)
}

/// A blob whose header and checksums passed: see [`parse_blob`].
pub(crate) struct ParsedBlob<'a> {
    pub(crate) header: FieldHeader,
    pub(crate) encoding: u8,
    /// The header's clamp-code byte: encoding 2's clamp code (0: none); always 0 for encoding 1.
    #[cfg(feature = "tiled-field")]
    pub(crate) clamp_code: u8,
    pub(crate) payload: &'a [u8],
    pub(crate) trailing: &'a [u8],
}

/// Reads and checks a header; returns it with the distance encoding, the payload (exactly
/// `width · height` bytes for encoding 1, the header's payload length for encoding 2) and
/// whatever follows the payload. The structure of a tiled payload is checked by
/// [`TiledCells::parse`](super::tiled::TiledCells::parse).
pub(crate) fn parse_blob(bytes: &[u8]) -> Result<ParsedBlob<'_>, BlobError> {
    let head: &[u8; BLOB_HEADER_LEN] = bytes
        .get(..BLOB_HEADER_LEN)
        .and_then(|h| h.try_into().ok())
        .ok_or(BlobError::Truncated)?;
    if head.get(field::MAGIC) != Some(&BLOB_MAGIC[..]) {
        return Err(BlobError::BadMagic);
    }
    let version = wire::get_u16(head, field::VERSION);
    if version != BLOB_VERSION {
        return Err(BlobError::UnsupportedVersion(version));
    }
    if usize::from(wire::get_u16(head, field::HEADER_LEN)) != BLOB_HEADER_LEN {
        return Err(BlobError::BadHeaderLength);
    }
    if CRC32.checksum(head.get(field::CHECKED).unwrap_or(&[]))
        != wire::get_u32(head, field::HEADER_CRC)
    {
        return Err(BlobError::HeaderChecksum);
    }
    let encoding = head[field::ENCODING];
    // Encoding 2 is read only with the `tiled-field` feature (on by default).
    #[cfg(feature = "tiled-field")]
    let known = encoding == ENCODING_U8_LINEAR || encoding == ENCODING_TILED;
    #[cfg(not(feature = "tiled-field"))]
    let known = encoding == ENCODING_U8_LINEAR;
    if !known {
        return Err(BlobError::UnsupportedEncoding(encoding));
    }
    // The clamp code is encoding 2's (checked against the pool by the tiled parser);
    // reserved, zero, for encoding 1.
    let clamp_code = head[field::CLAMP_CODE];
    #[cfg(feature = "tiled-field")]
    let clamp_ok = clamp_code == 0 || encoding != ENCODING_U8_LINEAR;
    #[cfg(not(feature = "tiled-field"))]
    let clamp_ok = clamp_code == 0;
    if !clamp_ok || head.get(field::RESERVED) != Some(&[0, 0][..]) {
        return Err(BlobError::ReservedNonZero);
    }
    let header = FieldHeader {
        width: wire::get_u32(head, field::WIDTH),
        height: wire::get_u32(head, field::HEIGHT),
        cell_size_m: wire::get_f32(head, field::CELL_SIZE),
        origin_x_m: wire::get_f32(head, field::ORIGIN_X),
        origin_y_m: wire::get_f32(head, field::ORIGIN_Y),
        max_dist_m: wire::get_f32(head, field::MAX_DIST),
    };
    let cells = header.validate()?;
    let stated = usize::try_from(wire::get_u32(head, field::PAYLOAD_LEN))
        .map_err(|_| BlobError::PayloadLengthMismatch)?;
    #[cfg(feature = "tiled-field")]
    let possible = if encoding == ENCODING_U8_LINEAR {
        stated == cells
    } else {
        tiled_payload_len_possible(header.width, header.height, stated)
    };
    #[cfg(not(feature = "tiled-field"))]
    let possible = stated == cells;
    if !possible {
        return Err(BlobError::PayloadLengthMismatch);
    }
    let rest = bytes.get(BLOB_HEADER_LEN..).unwrap_or(&[]);
    if rest.len() < stated {
        return Err(BlobError::Truncated);
    }
    let (payload, trailing) = rest.split_at(stated);
    if CRC32.checksum(payload) != wire::get_u32(head, field::PAYLOAD_CRC) {
        return Err(BlobError::PayloadChecksum);
    }
    Ok(ParsedBlob {
        header,
        encoding,
        #[cfg(feature = "tiled-field")]
        clamp_code,
        payload,
        trailing,
    })
}
