//! What a blob holds: its header, encoding, sizes and (tiled) pool, as `field info` reports it.

use crate::input::field_file::parse_field_file;
use beamfield::field::{BlobError, FieldHeader, FieldView, ENCODING_TILED};

/// What `field info` reports about a blob.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlobInfo {
    /// The header.
    pub header: FieldHeader,
    /// Distance encoding (1 raw, 2 tiled).
    pub encoding: u8,
    /// Blob length, bytes (without a free-space section that follows it).
    pub bytes: usize,
    /// Length of the free-space section after the blob, bytes (0 without one).
    pub free_space_bytes: usize,
    /// Tiles in the pool (tiled blobs only).
    pub pool_tiles: Option<usize>,
    /// The clamp distance, metres (clamped tiled blobs only): distances at or beyond it are
    /// stored as it.
    pub clamp_m: Option<f32>,
}

impl BlobInfo {
    /// Parses `blob` and summarizes it.
    ///
    /// # Errors
    /// Any [`BlobError`].
    pub fn of(blob: &[u8]) -> Result<Self, BlobError> {
        let view = parse_field_file(blob)?;
        let (_, rest) = FieldView::parse_prefix(blob)?;
        Ok(Self {
            header: *view.header(),
            encoding: view.encoding(),
            bytes: blob.len() - rest.len(),
            free_space_bytes: rest.len(),
            pool_tiles: view.pool_tiles(),
            clamp_m: view.clamp_m(),
        })
    }

    /// Cells of the grid.
    pub fn cells(&self) -> u64 {
        u64::from(self.header.width) * u64::from(self.header.height)
    }

    /// Bytes per cell, header included.
    pub fn bytes_per_cell(&self) -> f64 {
        self.bytes as f64 / self.cells() as f64
    }

    /// The encoding's name as `--encoding` spells it.
    pub fn encoding_name(&self) -> &'static str {
        if self.encoding == ENCODING_TILED {
            "tiled"
        } else {
            "raw"
        }
    }
}
