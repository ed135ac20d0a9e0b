//! `beamfield field encode`: a blob rewritten in the other encoding (the same header and codes,
//! so the same scores); a free-space section after it is carried over unchanged.

use crate::blob::encode::decodable;
use crate::blob::{clamp_code_for, tile_blob_clamped, untile_blob, BlobInfo, Encoding, FieldError};
use crate::input::field_file::{parse_field_file, read_field_file};
use beamfield::field::FieldView;
use clap::Args;
use serde::Serialize;
use std::fmt;
use std::path::PathBuf;

/// Arguments of `beamfield field encode`.
#[derive(Args, Debug)]
pub struct EncodeArgs {
    /// The blob to read (either encoding).
    pub blob: PathBuf,
    /// Where to write the re-encoded blob.
    #[arg(short, long)]
    pub output: PathBuf,
    /// The encoding to write. A clamped blob (--clamp-m) can only be written tiled.
    #[arg(long, value_enum)]
    pub encoding: Encoding,
    /// Clamp distances beyond D metres to D (tiled only; see `field build --clamp-m`).
    /// A blob that already has a clamp keeps the smaller of the two.
    #[arg(long = "clamp-m", value_name = "D")]
    pub clamp_m: Option<f32>,
}

/// What `field encode` wrote.
#[derive(Debug, Serialize)]
pub struct EncodeReport {
    /// The blob read.
    pub input: String,
    /// The blob written.
    pub output: String,
    /// Length of the input file, bytes.
    pub input_bytes: usize,
    /// `raw` or `tiled`.
    pub encoding: &'static str,
    /// Length of the blob written (without a free-space section), bytes.
    pub bytes: usize,
    /// Bytes per cell of the blob written.
    pub bytes_per_cell: f64,
}

/// Runs `field encode`.
///
/// # Errors
/// [`FieldError`].
pub fn run(a: &EncodeArgs) -> Result<EncodeReport, FieldError> {
    let (blob, output) = (&a.blob, &a.output);
    let bytes = read_field_file(blob)?;
    let view = parse_field_file(&bytes).map_err(|e| FieldError::Blob(blob.clone(), e))?;
    if !decodable(&view) {
        return Err(FieldError::TooManyCells(
            blob.clone(),
            view.width(),
            view.height(),
        ));
    }
    if a.encoding == Encoding::Raw && (a.clamp_m.is_some() || view.clamp_code().is_some()) {
        return Err(FieldError::ClampNeedsTiled);
    }
    if let Some(d) = a.clamp_m {
        clamp_code_for(view.header(), d)?;
    }
    let mut out = match a.encoding {
        Encoding::Raw => untile_blob(&bytes),
        Encoding::Tiled => tile_blob_clamped(&bytes, a.clamp_m),
    }
    .map_err(|e| FieldError::Blob(blob.clone(), e))?;
    // A free-space section after the blob is carried over unchanged.
    let (_, rest) =
        FieldView::parse_prefix(&bytes).map_err(|e| FieldError::Blob(blob.clone(), e))?;
    out.extend_from_slice(rest);
    std::fs::write(output, &out).map_err(|e| FieldError::Io(output.clone(), e))?;
    let info = BlobInfo::of(&out).map_err(|e| FieldError::Blob(output.clone(), e))?;
    Ok(EncodeReport {
        input: blob.display().to_string(),
        output: output.display().to_string(),
        input_bytes: bytes.len(),
        encoding: info.encoding_name(),
        bytes: info.bytes,
        bytes_per_cell: info.bytes_per_cell(),
    })
}

impl fmt::Display for EncodeReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} encoding, {} bytes ({:.4} bytes/cell; {} was {} bytes)",
            self.output,
            self.encoding,
            self.bytes,
            self.bytes_per_cell,
            self.input,
            self.input_bytes
        )
    }
}
