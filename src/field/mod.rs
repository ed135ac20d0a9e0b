//! The distance field: from an occupancy grid to a flash blob to the likelihood field
//! (Thrun Table 6.3; docs/models.md#field, docs/blob-format.md).
//!
//! - [`edt`]: the exact squared Euclidean distance transform (Felzenszwalb–Huttenlocher), on
//!   caller-provided buffers.
//! - [`blob`]: the versioned blob format; the writer ([`emit_blob`]) and the parser live
//!   together and round-trip. Specified in `docs/blob-format.md`.
//! - [`tiled`]: distance encoding 2, the same codes in deduplicated 4 × 4 tiles (a blob a
//!   quarter to a half the size, read in O(1)); [`emit_blob_tiled`] writes it.
//! - [`view`]: [`FieldView`], a validated zero-copy view of a blob, with infallible lookups.
//! - [`likelihood`]: [`LikelihoodField`], the likelihood field model scored over a view.
//! - [`free_space`]: [`FreeSpace`], the known-free cells packed for uniform sampling (a section
//!   beside the blob, `docs/free-space-format.md`).
//! - [`prepared`]: [`PreparedScan`], a scan made ready to be scored at many poses (the fast
//!   per-beam path).
//!
//! The host tool (`beamfield field build`) runs the transform on a map and writes the blob; the
//! device links the blob and parses it once at boot.
//!
//! Layering, bottom up (a module imports only those before it): `layout` (the format's
//! constants, the header's and the tiled preamble's field tables, the CRC), `grid` (the grid
//! check), [`blob`], [`tiled`], [`view`], then [`likelihood`] → [`prepared`] and [`free_space`];
//! [`edt`] stands alone.

pub mod blob;
pub mod edt;
pub mod free_space;
mod grid;
mod layout;
pub mod likelihood;
pub mod prepared;
pub mod tiled;
pub mod view;

pub use blob::{
    emit_blob, emit_blob_from_squared_cells, BlobError, FieldHeader, BLOB_HEADER_LEN, BLOB_MAGIC,
    BLOB_MAX_SIDE, BLOB_VERSION, CODE_MAX, DEFAULT_MAX_DIST_M, ENCODING_U8_LINEAR,
};
pub use edt::{edt_scratch_len, squared_edt, EdtError, EdtScratch, EDT_INFINITY, EDT_MAX_SIDE};
pub use free_space::{
    emit_free_space, free_space_len, FreeSpace, FreeSpaceError, FreeSpaceGrid,
    FREE_SPACE_HEADER_LEN, FREE_SPACE_MAGIC, FREE_SPACE_RUN_LEN, FREE_SPACE_VERSION,
};
pub use likelihood::{
    LikelihoodError, LikelihoodField, LikelihoodParam, LikelihoodParams, LIKELIHOOD_TABLE_LEN,
};
pub use prepared::PreparedScan;
pub use tiled::{
    emit_blob_tiled, emit_blob_tiled_clamped, tiled_max_len, tiled_scratch_len, ENCODING_TILED,
    TILED_MAX_POOL_TILES, TILE_SIDE,
};
pub use view::FieldView;
