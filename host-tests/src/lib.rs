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
pub mod xorshift;

use std::path::PathBuf;

/// The shared real-data folder (`shared/data`: maps, the Intel laser log, the sonar ring data).
///
/// Looked up as `$BEAMFIELD_DATA` if set, else as `shared/data` beside the repository (the
/// layout of a developer machine and of CI), walking up from this crate's directory.
///
/// # Panics
/// When the folder cannot be found: the tests that need real data must not pass silently
/// without it.
pub fn data_dir() -> PathBuf {
    if let Some(p) = std::env::var_os("BEAMFIELD_DATA") {
        return PathBuf::from(p);
    }
    let mut dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    loop {
        let candidate = dir.join("shared").join("data");
        if candidate.join("README.md").is_file() {
            return candidate;
        }
        if !dir.pop() {
            panic!(
                "shared/data not found above {}; set BEAMFIELD_DATA",
                env!("CARGO_MANIFEST_DIR")
            );
        }
    }
}
pub mod corridor;
