//! `beamfield field render`: the field drawn as a PNG a person can read.

use crate::blob::FieldError;
use crate::input::field_file::{parse_field_file, read_field_file};
use clap::Args;
use serde::Serialize;
use std::fmt;
use std::path::PathBuf;

/// Arguments of `beamfield field render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// The blob.
    pub blob: PathBuf,
    /// Where to write the PNG.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// What `field render` drew.
#[derive(Debug, Serialize)]
pub struct RenderReport {
    /// The PNG file.
    pub output: String,
    /// Picture width, pixels.
    pub width_px: u32,
    /// Picture height, pixels.
    pub height_px: u32,
    /// Pixels per cell side.
    pub px_per_cell: u32,
    /// Length of the scale bar, metres.
    pub scale_bar_m: f64,
    /// Grid width, cells.
    pub width_cells: u32,
    /// Grid height, cells.
    pub height_cells: u32,
}

/// Runs `field render`.
///
/// # Errors
/// [`FieldError::Read`], [`FieldError::Blob`], [`FieldError::Png`].
pub fn run(a: &RenderArgs) -> Result<RenderReport, FieldError> {
    let (blob, output) = (&a.blob, &a.output);
    let bytes = read_field_file(blob)?;
    let view = parse_field_file(&bytes).map_err(|e| FieldError::Blob(blob.clone(), e))?;
    let name = blob.file_name().map_or_else(
        || blob.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let title = format!("distance field of {name}");
    let fig = crate::draw::field_figure::draw_field(output, &view, &title)
        .map_err(|e| FieldError::Png(output.clone(), e.to_string()))?;
    Ok(RenderReport {
        output: output.display().to_string(),
        width_px: fig.width_px,
        height_px: fig.height_px,
        px_per_cell: fig.px_per_cell,
        scale_bar_m: fig.scale_bar_m,
        width_cells: view.width(),
        height_cells: view.height(),
    })
}

impl fmt::Display for RenderReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} × {} px, {} px per cell, scale bar {} m",
            self.output, self.width_px, self.height_px, self.px_per_cell, self.scale_bar_m
        )
    }
}
