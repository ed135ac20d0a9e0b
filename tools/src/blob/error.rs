//! The one error type of blob building and of the `field` commands: every way loading a map,
//! transforming, encoding, reading or writing a field can fail, each with the file concerned.

use super::encode::MAX_DECODED_CELLS;
use crate::input::map::MapError;
use beamfield::field::{BlobError, EdtError, FreeSpaceError};
use std::path::PathBuf;

/// Anything that can go wrong in a `field` command.
#[derive(Debug)]
pub enum FieldError {
    /// Loading the map.
    Map(MapError),
    /// A file could not be read or written.
    Io(PathBuf, std::io::Error),
    /// A field file that is not a regular file, or larger than
    /// [`crate::input::limits::MAX_FIELD_FILE_BYTES`].
    Read(crate::input::limits::ReadError),
    /// A `field query` input line longer than [`crate::input::limits::MAX_QUERY_LINE_BYTES`] (its
    /// 1-based number); reading stops there.
    QueryLineTooLong(usize),
    /// `field encode` of a blob with more cells than [`MAX_DECODED_CELLS`] (the file, width,
    /// height).
    TooManyCells(PathBuf, u32, u32),
    /// The blob is invalid, or could not be written.
    Blob(PathBuf, BlobError),
    /// The distance transform refused the grid.
    Edt(EdtError),
    /// `--max-dist` not finite or ≤ 0.
    BadMaxDist(f32),
    /// The map cannot be represented in a blob (size or f32 origin).
    Header(BlobError),
    /// Writing the PNG failed.
    Png(PathBuf, String),
    /// Some query lines were malformed (count).
    BadLines(usize),
    /// The free-space section could not be built (e.g. the map has no free cell).
    FreeSpace(FreeSpaceError),
    /// A `--variant` map's size, resolution or origin differs from the map's.
    VariantMismatch(PathBuf),
    /// `--clamp-m` not finite, or not between half a code step and `d_max` (the value and
    /// `d_max`).
    BadClamp(f32, f32),
    /// A clamp (`--clamp-m`, or a clamped input blob) with the raw encoding, which cannot
    /// record it.
    ClampNeedsTiled,
    /// `field score-variants` failed.
    ScoreVariants(Box<crate::blob::variants::ScoreVariantsError>),
}

impl std::fmt::Display for FieldError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Map(e) => write!(f, "{e}"),
            Self::Io(p, e) => write!(f, "{}: {e}", p.display()),
            Self::Read(e) => write!(f, "{e}"),
            Self::TooManyCells(p, w, h) => write!(
                f,
                "{}: a field of {w} x {h} = {} cells, more than {MAX_DECODED_CELLS}, the most a \
                 field is decoded to",
                p.display(),
                u64::from(*w) * u64::from(*h)
            ),
            Self::QueryLineTooLong(n) => write!(
                f,
                "standard input line {n}: longer than {} bytes (stopped reading)",
                crate::input::limits::MAX_QUERY_LINE_BYTES
            ),
            Self::Blob(p, e) => write!(
                f,
                "{}: {e}{}",
                p.display(),
                crate::input::field_file::blob_hint(e)
            ),
            Self::Edt(e) => write!(f, "distance transform: {e}"),
            Self::BadMaxDist(d) => write!(f, "--max-dist {d}: must be finite and > 0"),
            Self::Header(e) => write!(f, "map cannot be stored as a blob: {e}"),
            Self::Png(p, e) => write!(f, "{}: {e}", p.display()),
            Self::BadLines(n) => write!(f, "{n} malformed input line(s)"),
            Self::FreeSpace(e) => write!(f, "free-space section: {e}"),
            Self::BadClamp(d, max) => write!(
                f,
                "--clamp-m {d}: must be finite, at least half a code step ({} m) and below \
                 d_max ({max} m)",
                max / 510.0
            ),
            Self::ScoreVariants(e) => write!(f, "score-variants: {e}"),
            Self::ClampNeedsTiled => f.write_str(
                "a clamped field can only be stored tiled (--encoding tiled): the raw encoding \
                 cannot record the clamp",
            ),
            Self::VariantMismatch(p) => write!(
                f,
                "{}: a variant must have the map's size, resolution and origin",
                p.display()
            ),
        }
    }
}

impl std::error::Error for FieldError {}
