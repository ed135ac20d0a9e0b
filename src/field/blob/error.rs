//! [`BlobError`]: one variant per check of the blob format (docs/blob-format.md, "Reader
//! rules"), for the parser, the writers and the tiled encoding alike.
//!
//! Contract: every failure of a parse or a write is one of these variants, never a panic; the
//! grid check's faults map onto the variants of the same name.

use crate::field::grid::{from_grid_fault, GridFault};

/// Why a blob could not be parsed or written. Each variant names one check of the format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum BlobError {
    /// Fewer bytes than the header, or than header plus payload.
    Truncated,
    /// The first four bytes are not [`BLOB_MAGIC`](super::BLOB_MAGIC).
    BadMagic,
    /// A format version this crate does not read (the version found).
    UnsupportedVersion(u16),
    /// The header-length field is not [`BLOB_HEADER_LEN`](super::BLOB_HEADER_LEN).
    BadHeaderLength,
    /// The header CRC does not match header bytes 0..44.
    HeaderChecksum,
    /// A distance encoding this crate does not read (the code found).
    UnsupportedEncoding(u8),
    /// A reserved byte is not zero.
    ReservedNonZero,
    /// Width or height is 0.
    ZeroSize,
    /// Width or height above [`BLOB_MAX_SIDE`](super::BLOB_MAX_SIDE), or `width · height` overflows `usize`.
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
    /// Bytes after the payload ([`FieldView::parse`](crate::field::FieldView::parse) only).
    TrailingBytes,
    /// Writer: the output buffer is shorter than [`FieldHeader::required_len`](super::FieldHeader::required_len).
    BufferTooSmall,
    /// Writer: the number of cells given is not `width · height`.
    CellCountMismatch,
    /// Tiled writer: the scratch is shorter than
    /// [`tiled_scratch_len`](crate::field::tiled_scratch_len).
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

from_grid_fault!(BlobError);
