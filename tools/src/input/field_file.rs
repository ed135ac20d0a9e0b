//! Reading field files: a blob, optionally followed by its free-space section, read as a
//! regular file within [`crate::input::limits::MAX_FIELD_FILE_BYTES`] and parsed as the tool
//! writes it.

use crate::blob::FieldError;
use beamfield::field::{BlobError, FieldView};
use std::path::Path;

/// Parses a field file as the tool writes it: a blob, optionally followed by its free-space
/// section (`field build --free-space`, docs/free-space-format.md). Any other trailing bytes are
/// rejected as [`FieldView::parse`] rejects them.
///
/// # Errors
/// The [`BlobError`] of the blob, or [`BlobError::TrailingBytes`] when what follows the blob is
/// not a free-space section.
pub fn parse_field_file(bytes: &[u8]) -> Result<FieldView<'_>, BlobError> {
    let (view, rest) = FieldView::parse_prefix(bytes)?;
    if rest.is_empty() || beamfield::field::FreeSpace::parse(rest).is_ok() {
        Ok(view)
    } else {
        FieldView::parse(bytes)
    }
}

/// What follows a [`BlobError`] in a message for a user: for a file that is no blob at all (a
/// map's YAML or image, a log), how a field file is made; nothing for the other errors.
pub fn blob_hint(e: &BlobError) -> &'static str {
    if *e == BlobError::BadMagic {
        "; a field file is what `beamfield field build MAP.yaml -o FIELD.bin` writes from a \
         map_server map"
    } else {
        ""
    }
}

/// Reads a field file (blob and optional free-space section): a regular file of at most
/// [`crate::input::limits::MAX_FIELD_FILE_BYTES`].
///
/// # Errors
/// [`FieldError::Read`].
pub fn read_field_file(path: &Path) -> Result<Vec<u8>, FieldError> {
    crate::input::limits::read_regular_file(
        path,
        crate::input::limits::MAX_FIELD_FILE_BYTES,
        "field file",
    )
    .map_err(FieldError::Read)
}
