//! Host-side reference and helpers for testing `beamfield`.
//!
//! [`reference`] is an f64 implementation written from the textbook (`docs/models.md`),
//! independent of the crate's f32 code: it shares no function with it (std's f64 math, not the
//! crate's math façade), so an error in one is not silently copied into the other.

pub mod field_reference;
pub mod firmware_cases;
pub mod firmware_models;
pub mod landmark_correlation_cases;
pub mod reference;
pub mod reference_backend;
pub mod sonar_sim;
pub mod sonar_uci;
pub mod splitmix;
/// The wheel odometry that is not the filter's motion model (moved to the tools, which feed it
/// to `beamfield track --wheel-odometry`).
pub use beamfield_tools::track::wheels as wheel_odometry;

use std::path::PathBuf;

/// The real-data folder: the maps, the Intel laser log and the sonar ring data that the tests
/// use, kept in the repository's `data/` (each folder with its provenance and licence).
///
/// `$BEAMFIELD_DATA`, when set, overrides it (a folder with the same layout).
///
/// # Panics
/// When the folder cannot be found: the tests that need real data must not pass silently
/// without it.
pub fn data_dir() -> PathBuf {
    if let Some(p) = std::env::var_os("BEAMFIELD_DATA") {
        return PathBuf::from(p);
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("data");
    assert!(
        dir.join("README.md").is_file(),
        "the repository's data folder {} is missing (set BEAMFIELD_DATA to use another)",
        dir.display()
    );
    dir
}
pub mod corridor;
