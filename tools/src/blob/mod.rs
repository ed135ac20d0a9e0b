//! Distance-field blobs on the host: built from a map ([`build`]), re-encoded ([`encode`]),
//! described ([`info`]), and the map variants a scan is scored against ([`variants`]). The
//! format itself (header, codes, tiles) is the library's (`beamfield::field`,
//! docs/blob-format.md); this module feeds it maps and files.

pub mod build;
pub mod encode;
pub mod error;
pub mod info;
pub mod variants;

pub use build::{
    build_blob, build_blob_clamped, build_blob_encoded, build_free_space, edt_seeds, header_for,
    same_geometry, squared_distances, union_map, FieldCodes,
};
pub use encode::{clamp_code_for, tile_blob, tile_blob_clamped, untile_blob, MAX_DECODED_CELLS};
pub use error::FieldError;
pub use info::BlobInfo;

/// How a blob stores its codes (both give the same codes, so the same scores).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Encoding {
    /// Encoding 1: one byte per cell (every reader of the format reads it).
    Raw,
    /// Encoding 2: deduplicated 4 × 4 tiles, 0.28–0.48 bytes per cell on the shared maps;
    /// needs a reader that knows encoding 2.
    Tiled,
}

impl Encoding {
    /// The encoding's name as `--encoding` spells it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Raw => "raw",
            Self::Tiled => "tiled",
        }
    }
}
