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

use crc::{Crc, CRC_32_ISO_HDLC};

/// The four magic bytes at offset 0.
pub const BLOB_MAGIC: [u8; 4] = *b"BFDF";
/// The format version this crate writes and reads.
pub const BLOB_VERSION: u16 = 1;
/// Header length, bytes; the payload starts here.
pub const BLOB_HEADER_LEN: usize = 48;
/// Distance encoding 1: u8 code `c` stands for `c · d_max / 255` metres.
pub const ENCODING_U8_LINEAR: u8 = 1;
/// The largest code; it also stands for every distance `≥ d_max`.
pub const CODE_MAX: u8 = 255;
/// Default `d_max`, metres: AMCL's `laser_likelihood_max_dist`.
pub const DEFAULT_MAX_DIST_M: f32 = 2.0;
/// Largest accepted width or height, cells (2²⁴: every index is exact in an f32).
pub const BLOB_MAX_SIDE: u32 = 1 << 24;

pub(crate) const CRC32: Crc<u32> = Crc::<u32>::new(&CRC_32_ISO_HDLC);

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

/// Why a blob could not be parsed or written. Each variant names one check of the format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum BlobError {
    /// Fewer bytes than the header, or than header plus payload.
    Truncated,
    /// The first four bytes are not [`BLOB_MAGIC`].
    BadMagic,
    /// A format version this crate does not read (the version found).
    UnsupportedVersion(u16),
    /// The header-length field is not [`BLOB_HEADER_LEN`].
    BadHeaderLength,
    /// The header CRC does not match header bytes 0..44.
    HeaderChecksum,
    /// A distance encoding this crate does not read (the code found).
    UnsupportedEncoding(u8),
    /// A reserved byte is not zero.
    ReservedNonZero,
    /// Width or height is 0.
    ZeroSize,
    /// Width or height above [`BLOB_MAX_SIDE`], or `width · height` overflows `usize`.
    TooLarge,
    /// The payload-length field is not `width · height`.
    PayloadLengthMismatch,
    /// Cell size not finite, not > 0, or so small its inverse overflows.
    BadCellSize,
    /// Origin not finite, or the map's far corner not finite.
    BadOrigin,
    /// `d_max` not finite or not > 0.
    BadMaxDist,
    /// The payload CRC does not match.
    PayloadChecksum,
    /// Bytes after the payload ([`FieldView::parse`](super::FieldView::parse) only).
    TrailingBytes,
    /// Writer: the output buffer is shorter than [`FieldHeader::required_len`].
    BufferTooSmall,
    /// Writer: the number of cells given is not `width · height`.
    CellCountMismatch,
    /// Tiled writer: the scratch is shorter than
    /// [`tiled_scratch_len`](super::tiled_scratch_len).
    ScratchTooSmall,
    /// Tiled writer: more than 65,536 distinct tiles (write encoding 1 instead).
    TooManyTiles,
    /// Tiled blob: the tile side is not 4, reserved bytes are not zero, or the pool size is 0,
    /// above 65,536, or not the one the payload length implies.
    BadTileTable,
    /// Tiled blob: a tile-index entry names no tile of the pool.
    TileIndexOutOfRange,
    /// Tiled blob: the clamp code (header byte 33) is 255, or a pool code is above it
    /// (writer: a clamp code of 255).
    BadClamp,
}

impl core::fmt::Display for BlobError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Truncated => f.write_str("blob truncated"),
            Self::BadMagic => f.write_str("not a distance-field blob (bad magic)"),
            Self::UnsupportedVersion(v) => write!(f, "unsupported blob version {v}"),
            Self::BadHeaderLength => f.write_str("bad header length"),
            Self::HeaderChecksum => f.write_str("header checksum mismatch"),
            Self::UnsupportedEncoding(e) => write!(f, "unsupported distance encoding {e}"),
            Self::BadClamp => f.write_str("clamp code 255 or a tile code above the clamp code"),
            Self::ReservedNonZero => f.write_str("reserved header bytes not zero"),
            Self::ZeroSize => f.write_str("width or height is zero"),
            Self::TooLarge => f.write_str("grid too large"),
            Self::PayloadLengthMismatch => f.write_str("payload length is not width times height"),
            Self::BadCellSize => f.write_str("cell size must be finite and > 0"),
            Self::BadOrigin => f.write_str("origin must be finite"),
            Self::BadMaxDist => f.write_str("max distance must be finite and > 0"),
            Self::PayloadChecksum => f.write_str("payload checksum mismatch"),
            Self::TrailingBytes => f.write_str("trailing bytes after the payload"),
            Self::BufferTooSmall => f.write_str("output buffer too small"),
            Self::CellCountMismatch => f.write_str("cell count is not width times height"),
            Self::ScratchTooSmall => f.write_str("scratch buffer too small"),
            Self::TooManyTiles => f.write_str("more than 65536 distinct tiles"),
            Self::BadTileTable => f.write_str("inconsistent tile table"),
            Self::TileIndexOutOfRange => f.write_str("tile index entry outside the tile pool"),
        }
    }
}

impl core::error::Error for BlobError {}

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
        let cells = super::grid::check_grid(
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

    pub(crate) fn write_fields(
        &self,
        head: &mut [u8; BLOB_HEADER_LEN],
        encoding: u8,
        clamp_code: u8,
        payload_len: u32,
        payload_crc: u32,
    ) {
        fn put(head: &mut [u8; BLOB_HEADER_LEN], at: usize, bytes: &[u8]) {
            for (d, s) in head.iter_mut().skip(at).zip(bytes) {
                *d = *s;
            }
        }
        put(head, 0, &BLOB_MAGIC);
        put(head, 4, &BLOB_VERSION.to_le_bytes());
        put(head, 6, &(BLOB_HEADER_LEN as u16).to_le_bytes());
        put(head, 8, &self.width.to_le_bytes());
        put(head, 12, &self.height.to_le_bytes());
        put(head, 16, &self.cell_size_m.to_le_bytes());
        put(head, 20, &self.origin_x_m.to_le_bytes());
        put(head, 24, &self.origin_y_m.to_le_bytes());
        put(head, 28, &self.max_dist_m.to_le_bytes());
        put(head, 32, &[encoding, clamp_code, 0, 0]);
        put(head, 36, &payload_len.to_le_bytes());
        put(head, 40, &payload_crc.to_le_bytes());
        let crc = CRC32.checksum(head.get(..44).unwrap_or(&[]));
        put(head, 44, &crc.to_le_bytes());
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
    /// Header byte 33: encoding 2's clamp code (0: none); always 0 for encoding 1.
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
    let u16_at = |at: usize| u16::from_le_bytes([byte(head, at), byte(head, at + 1)]);
    let u32_at = |at: usize| {
        u32::from_le_bytes([
            byte(head, at),
            byte(head, at + 1),
            byte(head, at + 2),
            byte(head, at + 3),
        ])
    };
    let f32_at = |at: usize| f32::from_bits(u32_at(at));
    if head.get(..4) != Some(&BLOB_MAGIC[..]) {
        return Err(BlobError::BadMagic);
    }
    let version = u16_at(4);
    if version != BLOB_VERSION {
        return Err(BlobError::UnsupportedVersion(version));
    }
    if usize::from(u16_at(6)) != BLOB_HEADER_LEN {
        return Err(BlobError::BadHeaderLength);
    }
    if CRC32.checksum(head.get(..44).unwrap_or(&[])) != u32_at(44) {
        return Err(BlobError::HeaderChecksum);
    }
    let encoding = byte(head, 32);
    // Encoding 2 is read only with the `tiled-field` feature (on by default).
    let known = encoding == ENCODING_U8_LINEAR
        || (cfg!(feature = "tiled-field") && encoding == super::tiled::ENCODING_TILED);
    if !known {
        return Err(BlobError::UnsupportedEncoding(encoding));
    }
    // Byte 33 is encoding 2's clamp code (checked against the pool by the tiled parser);
    // reserved, zero, for encoding 1.
    let clamp_code = byte(head, 33);
    #[cfg(feature = "tiled-field")]
    let clamp_ok = clamp_code == 0 || encoding != ENCODING_U8_LINEAR;
    #[cfg(not(feature = "tiled-field"))]
    let clamp_ok = clamp_code == 0;
    if !clamp_ok || byte(head, 34) != 0 || byte(head, 35) != 0 {
        return Err(BlobError::ReservedNonZero);
    }
    let header = FieldHeader {
        width: u32_at(8),
        height: u32_at(12),
        cell_size_m: f32_at(16),
        origin_x_m: f32_at(20),
        origin_y_m: f32_at(24),
        max_dist_m: f32_at(28),
    };
    let cells = header.validate()?;
    let stated = usize::try_from(u32_at(36)).map_err(|_| BlobError::PayloadLengthMismatch)?;
    #[cfg(feature = "tiled-field")]
    let possible = if encoding == ENCODING_U8_LINEAR {
        stated == cells
    } else {
        super::tiled::payload_len_possible(&header, stated)
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
    if CRC32.checksum(payload) != u32_at(40) {
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

fn byte(head: &[u8; BLOB_HEADER_LEN], at: usize) -> u8 {
    head.get(at).copied().unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (FieldHeader, Vec<u8>) {
        let h = FieldHeader::new(3, 2, 0.05, -1.0, 2.0);
        let codes = vec![0, 1, 2, 253, 254, 255];
        let mut out = vec![0u8; h.required_len().unwrap()];
        assert_eq!(emit_blob(&h, &codes, &mut out), Ok(54));
        (h, out)
    }

    /// Rewrites the header CRC so that a deliberately wrong field reaches its own check.
    fn reseal(b: &mut [u8]) {
        let crc = CRC32.checksum(&b[..44]);
        b[44..48].copy_from_slice(&crc.to_le_bytes());
    }

    #[test]
    fn crc_is_the_zlib_crc() {
        // The standard check value of CRC-32/ISO-HDLC.
        assert_eq!(CRC32.checksum(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn each_field_check_is_reached() {
        let (_, good) = sample();
        type Edit = fn(&mut Vec<u8>);
        let cases: [(Edit, BlobError); 15] = [
            (|b| b[3] = b'X', BlobError::BadMagic),
            (|b| b[4] = 2, BlobError::UnsupportedVersion(2)),
            (|b| b[6] = 47, BlobError::BadHeaderLength),
            (|b| b[9] ^= 1, BlobError::HeaderChecksum),
            (|b| b[32] = 3, BlobError::UnsupportedEncoding(3)),
            (|b| b[34] = 1, BlobError::ReservedNonZero),
            // Byte 33 is a clamp code for encoding 2 only: reserved for encoding 1.
            (|b| b[33] = 1, BlobError::ReservedNonZero),
            (|b| b[8..12].fill(0), BlobError::ZeroSize),
            (
                |b| b[8..12].copy_from_slice(&(1u32 << 25).to_le_bytes()),
                BlobError::TooLarge,
            ),
            (|b| b[36] = 7, BlobError::PayloadLengthMismatch),
            (
                |b| b[16..20].copy_from_slice(&f32::NAN.to_le_bytes()),
                BlobError::BadCellSize,
            ),
            (
                |b| b[16..20].copy_from_slice(&(-0.05f32).to_le_bytes()),
                BlobError::BadCellSize,
            ),
            (
                |b| b[20..24].copy_from_slice(&f32::INFINITY.to_le_bytes()),
                BlobError::BadOrigin,
            ),
            (
                |b| b[28..32].copy_from_slice(&0f32.to_le_bytes()),
                BlobError::BadMaxDist,
            ),
            (|b| b[50] ^= 0x10, BlobError::PayloadChecksum),
        ];
        for (i, (edit, want)) in cases.into_iter().enumerate() {
            let mut b = good.clone();
            edit(&mut b);
            if want != BlobError::HeaderChecksum && i > 3 && want != BlobError::PayloadChecksum {
                reseal(&mut b);
            }
            assert_eq!(parse_blob(&b).err(), Some(want), "case {i}");
        }
        assert_eq!(parse_blob(&good[..53]).err(), Some(BlobError::Truncated));
        assert_eq!(parse_blob(&good[..47]).err(), Some(BlobError::Truncated));
    }

    #[test]
    fn encoding_table() {
        let h = FieldHeader::new(1, 1, 0.05, 0.0, 0.0);
        let step = 2.0 / 255.0;
        let cases: [(f64, u8); 8] = [
            (0.0, 0),
            (0.49 * step, 0),
            (0.51 * step, 1),
            (10.0 * step, 10),
            (2.0, 255),
            (50.0, 255),
            (f64::INFINITY, 255),
            (f64::NAN, 0),
        ];
        for (d, want) in cases {
            assert_eq!(h.encode_distance_m(d), want, "d = {d}");
        }
        // 0.05 m · √(25) = 0.25 m = 31.875 steps → 32.
        assert_eq!(h.encode_squared_cells(25), 32);
        assert_eq!(h.encode_squared_cells(super::super::EDT_INFINITY), 255);
    }

    #[test]
    fn writer_errors() {
        let h = FieldHeader::new(3, 2, 0.05, 0.0, 0.0);
        let mut small = [0u8; 53];
        assert_eq!(
            emit_blob(&h, &[0; 6], &mut small),
            Err(BlobError::BufferTooSmall)
        );
        let mut out = [0u8; 60];
        assert_eq!(
            emit_blob(&h, &[0; 5], &mut out),
            Err(BlobError::CellCountMismatch)
        );
        assert!(out.iter().all(|&b| b == 0));
    }

    /// Without the `tiled-field` feature a tiled blob is a typed error, not a misread.
    #[cfg(not(feature = "tiled-field"))]
    #[test]
    fn tiled_blob_needs_the_feature() {
        use super::super::tiled::{emit_blob_tiled, tiled_max_len, tiled_scratch_len};
        let (h, _) = sample();
        let codes = [0, 1, 2, 253, 254, 255];
        let mut scratch = vec![0u32; tiled_scratch_len(&h).unwrap()];
        let mut out = vec![0u8; tiled_max_len(&h).unwrap()];
        let n = emit_blob_tiled(&h, &codes, &mut scratch, &mut out).unwrap();
        assert_eq!(
            super::super::FieldView::parse(&out[..n]).err(),
            Some(BlobError::UnsupportedEncoding(2))
        );
    }
}
