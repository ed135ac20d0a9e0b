//! `beamfield field info`: a blob's grid, encoding, sizes and (tiled) pool.

use crate::blob::{BlobInfo, FieldError};
use crate::input::field_file::read_field_file;
use clap::Args;
use serde::Serialize;
use std::fmt;
use std::path::PathBuf;

/// Arguments of `beamfield field info`.
#[derive(Args, Debug)]
pub struct InfoArgs {
    /// The blob.
    pub blob: PathBuf,
}

/// What `field info` reports.
#[derive(Debug, Serialize)]
pub struct InfoReport {
    /// The blob file.
    pub blob: String,
    /// Grid width, cells.
    pub width: u32,
    /// Grid height, cells.
    pub height: u32,
    /// Cell side, metres.
    pub cell_size_m: f32,
    /// Grid origin (x, y), metres.
    pub origin_m: [f32; 2],
    /// Clamp distance d_max, metres.
    pub max_dist_m: f32,
    /// The tiled encoding's clamp, metres.
    pub clamp_m: Option<f32>,
    /// `raw` or `tiled`.
    pub encoding: &'static str,
    /// Blob length, bytes (without the free-space section).
    pub bytes: usize,
    /// Length of the free-space section after the blob, bytes (0 without one).
    pub free_space_bytes: usize,
    /// Cells of the grid.
    pub cells: u64,
    /// Bytes per cell, header included.
    pub bytes_per_cell: f64,
    /// Tiles in the pool (tiled blobs only).
    pub pool_tiles: Option<usize>,
}

/// Runs `field info`.
///
/// # Errors
/// [`FieldError::Read`], [`FieldError::Blob`].
pub fn run(a: &InfoArgs) -> Result<InfoReport, FieldError> {
    let bytes = read_field_file(&a.blob)?;
    let info = BlobInfo::of(&bytes).map_err(|e| FieldError::Blob(a.blob.clone(), e))?;
    let h = info.header;
    Ok(InfoReport {
        blob: a.blob.display().to_string(),
        width: h.width,
        height: h.height,
        cell_size_m: h.cell_size_m,
        origin_m: [h.origin_x_m, h.origin_y_m],
        max_dist_m: h.max_dist_m,
        clamp_m: info.clamp_m,
        encoding: info.encoding_name(),
        bytes: info.bytes,
        free_space_bytes: info.free_space_bytes,
        cells: info.cells(),
        bytes_per_cell: info.bytes_per_cell(),
        pool_tiles: info.pool_tiles,
    })
}

impl fmt::Display for InfoReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let tiles = self
            .pool_tiles
            .map(|p| format!(", {p} distinct tiles"))
            .unwrap_or_default()
            + &self
                .clamp_m
                .map(|d| format!(", distances clamped at {d} m (stored as {d} m when farther)"))
                .unwrap_or_default();
        let free = if self.free_space_bytes > 0 {
            format!(
                "; then a free-space section of {} bytes",
                self.free_space_bytes
            )
        } else {
            String::new()
        };
        write!(
            f,
            "{}: {} × {} cells of {} m, origin ({}, {}), d_max {} m; {} encoding{}; \
             {} bytes, {:.4} bytes/cell{}",
            self.blob,
            self.width,
            self.height,
            self.cell_size_m,
            self.origin_m[0],
            self.origin_m[1],
            self.max_dist_m,
            self.encoding,
            tiles,
            self.bytes,
            self.bytes_per_cell,
            free,
        )
    }
}
