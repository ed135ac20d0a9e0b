//! Why a map_server map could not be loaded ([`MapError`]): the file, and what was wrong.

use std::fmt;
use std::path::PathBuf;

/// Why a map could not be loaded.
#[derive(Debug)]
pub enum MapError {
    /// A file could not be read.
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file given as the map's YAML is of another kind (its image, a blob).
    NotYaml {
        /// The file.
        path: PathBuf,
        /// What it is.
        kind: crate::input::kind::FileKind,
    },
    /// The YAML is malformed or lacks a required key.
    Yaml {
        /// The YAML file.
        path: PathBuf,
        /// What the YAML parser said.
        message: String,
    },
    /// The image could not be decoded.
    Image {
        /// The image file.
        path: PathBuf,
        /// What the decoder said.
        message: String,
    },
    /// Thresholds outside `0 ≤ free_thresh < occupied_thresh ≤ 1` (or not finite).
    BadThresholds {
        /// `occupied_thresh`.
        occupied: f64,
        /// `free_thresh`.
        free: f64,
    },
    /// Resolution not finite or ≤ 0.
    BadResolution(f64),
    /// Origin not finite, or with a non-zero yaw.
    BadOrigin(String),
    /// A `mode` other than `trinary` or `scale`.
    UnsupportedMode(String),
    /// The image is empty.
    EmptyImage(PathBuf),
    /// The image path is not a regular file (a device, a FIFO, a directory).
    NotAFile(PathBuf),
    /// The image header announces more cells than the limit (checked before decoding).
    TooLarge {
        /// The image file.
        path: PathBuf,
        /// Width from the image header, pixels.
        width: u32,
        /// Height from the image header, pixels.
        height: u32,
        /// The limit, cells.
        max_cells: u64,
    },
}

/// Default limit on a map's cells, `--max-cells` on the command line: 4096 × 4096 (16.8 M
/// cells). `field build` needs about 10 bytes per cell at its peak (measured, see
/// docs/resource-limits.md), so the default keeps it under ~170 MB; the Willow Garage map is
/// 1.1 M cells.
pub const DEFAULT_MAX_CELLS: u64 = 1 << 24;

impl fmt::Display for MapError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Io { path, source } => write!(f, "cannot read {}: {source}", path.display()),
            Self::NotYaml { path, kind } => write!(
                f,
                "{} is {kind}; pass the map's YAML (the file that names {})",
                path.display(),
                match kind {
                    crate::input::kind::FileKind::Image => "it",
                    _ => "the map's image",
                }
            ),
            Self::Yaml { path, message } => {
                write!(f, "malformed map yaml {}: {message}", path.display())
            }
            Self::Image { path, message } => {
                write!(f, "cannot decode image {}: {message}", path.display())
            }
            Self::BadThresholds { occupied, free } => write!(
                f,
                "bad thresholds: need 0 <= free_thresh ({free}) < occupied_thresh ({occupied}) <= 1"
            ),
            Self::BadResolution(r) => write!(f, "bad resolution {r}: must be finite and > 0"),
            Self::BadOrigin(m) => write!(f, "bad origin: {m}"),
            Self::UnsupportedMode(m) => {
                write!(
                    f,
                    "unsupported mode {m:?} (trinary and scale are supported)"
                )
            }
            Self::EmptyImage(p) => write!(f, "image {} has no pixels", p.display()),
            Self::NotAFile(p) => write!(f, "image {} is not a regular file", p.display()),
            Self::TooLarge {
                path,
                width,
                height,
                max_cells,
            } => write!(
                f,
                "image {} is {width} x {height} = {} cells, over the limit of {max_cells} \
                 (raise it with --max-cells)",
                path.display(),
                u64::from(*width) * u64::from(*height)
            ),
        }
    }
}

impl std::error::Error for MapError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}
