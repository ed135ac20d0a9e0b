//! The track firmware's checked-in input is exactly what `cargo xtask track-assets` makes from
//! the real log today (scans, logged poses, and `beamfield track`'s synthesized odometry for the
//! same seed): regenerated and compared byte for byte.

use beamfield_tools::track_assets::generate;
use std::path::Path;

#[test]
fn checked_in_track_asset_is_current() {
    let log = host_tests::data_dir().join("laser_intel_lab/intel-corrected.log");
    let fresh = generate(&log).expect("generate");
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(beamfield_tools::track_assets::PATH);
    let checked_in = std::fs::read_to_string(&path).expect("fixtures/assets/track.rs");
    assert!(
        checked_in == fresh,
        "fixtures/assets/track.rs is stale: run `cargo xtask track-assets`"
    );
}
