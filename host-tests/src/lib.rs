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

/// The whole Intel lab log as a tracking input, the way the whole-log tests use it: the map
/// built from all 910 scans at their corrected poses (`beamfield map from-log`'s defaults), its
/// distance field capped at 2 m with the free-space section, the mixture z_hit 0.95, z_short
/// 0.05, z_rand 0.05 at the log's max range, the laser centred, no recorded odometry.
///
/// # Panics
/// When the log cannot be read or the map built: the tests that need it must not pass without.
pub fn intel_input() -> beamfield_tools::track::TrackInput {
    use beamfield_tools::blob::{build_blob, build_free_space};
    use beamfield_tools::input::carmen::{CarmenLog, ReadOptions};
    use beamfield_tools::input::map::OccupancyMap;
    use beamfield_tools::mapping::{build_from_log, MappingOptions, FREE_THRESH, OCCUPIED_THRESH};
    let path = data_dir().join("laser_intel_lab/intel-corrected.log");
    let log = CarmenLog::read_path(&path, ReadOptions::default()).unwrap();
    let max_range = log.max_range.value_m().unwrap();
    let (grid, _) = build_from_log(&log, &MappingOptions::new(max_range), |_, _| {}).unwrap();
    let map = OccupancyMap::from_grid(&grid.to_occupancy(OCCUPIED_THRESH, FREE_THRESH));
    let mut bytes = build_blob(&map, 2.0).unwrap();
    bytes.extend(build_free_space(&map).unwrap());
    beamfield_tools::track::TrackInput {
        bytes,
        params: beamfield::field::LikelihoodParams::new(0.95, 0.05, 0.05, max_range).unwrap(),
        layout: log
            .layout_with_mount(beamfield::SensorMount::CENTERED)
            .unwrap(),
        scans: log.scans.iter().map(|s| s.ranges_m.clone()).collect(),
        logged: log.scans.iter().map(|s| s.pose).collect(),
        odometry: None,
        reference: None,
    }
}
