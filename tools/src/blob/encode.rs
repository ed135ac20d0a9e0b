//! Re-encoding blobs: raw (encoding 1) to tiled (encoding 2) and back, with the optional clamp of
//! the tiled encoding. The codes are read from the blob and written unchanged, so a re-encoded
//! blob scores exactly as its input.

use super::FieldError;
use crate::input::field_file::parse_field_file;
use beamfield::field::{
    emit_blob, emit_blob_tiled_clamped, tiled_max_len, tiled_scratch_len, BlobError, FieldHeader,
    FieldView,
};

/// Re-encodes a blob (either encoding) as a raw blob (encoding 1) with the same header and
/// codes.
///
/// # Errors
/// Any [`BlobError`] of the input; [`BlobError::BadClamp`] for a clamped tiled blob (the raw
/// encoding cannot record the clamp).
pub fn untile_blob(blob: &[u8]) -> Result<Vec<u8>, BlobError> {
    let view = parse_field_file(blob)?;
    if !decodable(&view) {
        return Err(BlobError::TooLarge);
    }
    if view.clamp_code().is_some() {
        return Err(BlobError::BadClamp);
    }
    raw_from_codes(view.header(), &codes_of(&view))
}

/// A raw blob (encoding 1) of `codes` under `header`.
///
/// # Errors
/// Any [`BlobError`] of [`emit_blob`].
pub fn raw_from_codes(header: &FieldHeader, codes: &[u8]) -> Result<Vec<u8>, BlobError> {
    let mut out = vec![0u8; header.required_len()?];
    emit_blob(header, codes, &mut out)?;
    Ok(out)
}

/// A tiled blob (encoding 2) of `codes` under `header`, codes at or above `clamp_code` stored as
/// it (0: no clamp). Refuses more than [`MAX_DECODED_CELLS`] cells.
///
/// # Errors
/// [`BlobError::TooLarge`], [`BlobError::TooManyTiles`], any [`BlobError`] of
/// [`emit_blob_tiled_clamped`].
pub fn tiled_from_codes(
    header: &FieldHeader,
    codes: &[u8],
    clamp_code: u8,
) -> Result<Vec<u8>, BlobError> {
    if u64::from(header.width) * u64::from(header.height) > MAX_DECODED_CELLS {
        return Err(BlobError::TooLarge);
    }
    let mut scratch = vec![0u32; tiled_scratch_len(header)?];
    let mut out = vec![0u8; tiled_max_len(header)?];
    let n = emit_blob_tiled_clamped(header, codes, clamp_code, &mut scratch, &mut out)?;
    out.truncate(n);
    Ok(out)
}

/// Most cells `field encode` decodes a blob to: as many as a raw blob within
/// [`crate::input::limits::MAX_FIELD_FILE_BYTES`] holds (134,217,728). A tiled blob stores 16 cells in
/// 2 bytes of tile index, so a tiled file within the limit could announce 8 times more; decoding
/// and re-encoding costs about 3 bytes per cell.
pub const MAX_DECODED_CELLS: u64 = crate::input::limits::MAX_FIELD_FILE_BYTES;

/// `view` has at most [`MAX_DECODED_CELLS`] cells.
pub fn decodable(view: &FieldView<'_>) -> bool {
    u64::from(view.width()) * u64::from(view.height()) <= MAX_DECODED_CELLS
}

/// Every code of a view, row-major from the lowest y.
fn codes_of(view: &FieldView<'_>) -> Vec<u8> {
    if let Some(raw) = view.raw_codes() {
        return raw.to_vec();
    }
    let (w, h) = (view.width(), view.height());
    (0..h)
        .flat_map(|iy| (0..w).map(move |ix| (ix, iy)))
        .map(|(ix, iy)| view.code(ix, iy).unwrap_or(255))
        .collect()
}

/// Re-encodes a blob (either encoding) as a tiled blob (encoding 2) with the same header and
/// codes.
///
/// # Errors
/// Any [`BlobError`] of the input, [`BlobError::TooManyTiles`].
pub fn tile_blob(blob: &[u8]) -> Result<Vec<u8>, BlobError> {
    tile_blob_clamped(blob, None)
}

/// As [`tile_blob`], clamping distances beyond `clamp_m` metres (if given) to it; a clamp the
/// input already has is kept (the smaller of the two wins).
///
/// # Errors
/// As [`tile_blob`]; [`BlobError::BadClamp`] for a clamp distance that is not finite, below
/// half a code step, or at or above `d_max` (see [`clamp_code_for`]).
pub fn tile_blob_clamped(blob: &[u8], clamp_m: Option<f32>) -> Result<Vec<u8>, BlobError> {
    let view = parse_field_file(blob)?;
    if !decodable(&view) {
        return Err(BlobError::TooLarge);
    }
    let header = *view.header();
    let codes = codes_of(&view);
    let asked = match clamp_m {
        Some(d) => Some(clamp_code_for(&header, d).map_err(|_| BlobError::BadClamp)?),
        None => None,
    };
    let clamp = match (asked, view.clamp_code()) {
        (Some(a), Some(b)) => a.min(b),
        (Some(c), None) | (None, Some(c)) => c,
        (None, None) => 0,
    };
    tiled_from_codes(&header, &codes, clamp)
}

/// The clamp code of clamp distance `clamp_m` for a blob with `header`.
///
/// # Errors
/// [`FieldError::BadClamp`] unless the code is between 1 and 254 (`clamp_m` finite, at least
/// half a code step, below `d_max`).
pub fn clamp_code_for(header: &FieldHeader, clamp_m: f32) -> Result<u8, FieldError> {
    let code = header.encode_distance_m(f64::from(clamp_m));
    if clamp_m.is_finite() && (1..255).contains(&code) {
        Ok(code)
    } else {
        Err(FieldError::BadClamp(clamp_m, header.max_dist_m))
    }
}
