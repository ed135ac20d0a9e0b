//! The demo firmware's checked-in assets are exactly what `cargo xtask demo-assets` makes from
//! the real log today: regenerated and compared byte for byte.

use beamfield_tools::demo_assets::generate;
use std::path::Path;

#[test]
fn checked_in_demo_assets_are_current() {
    let log = host_tests::data_dir().join("laser_intel_lab/intel-corrected.log");
    let work = std::env::temp_dir().join(format!("beamfield-demo-test-{}", std::process::id()));
    let fresh = generate(&log, &work).expect("generate");
    let _ = std::fs::remove_dir_all(&work);
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let assets = repo.join(beamfield_tools::demo_assets::BLOB_DIR);
    let sources = repo.join(beamfield_tools::demo_assets::SOURCE_DIR);
    let blob = std::fs::read(assets.join("intel.bin")).expect("firmware/assets/intel.bin");
    let scans =
        std::fs::read_to_string(sources.join("scans.rs")).expect("fixtures/assets/scans.rs");
    assert!(
        blob == fresh.blob,
        "firmware/assets/intel.bin is stale: run `cargo xtask demo-assets`"
    );
    assert!(
        scans == fresh.scans_rs,
        "fixtures/assets/scans.rs is stale: run `cargo xtask demo-assets`"
    );
    let segment = std::fs::read_to_string(sources.join("lidar_segment.rs"))
        .expect("fixtures/assets/lidar_segment.rs");
    assert!(
        segment == fresh.lidar_segment_rs,
        "fixtures/assets/lidar_segment.rs is stale: run `cargo xtask demo-assets`"
    );
    let tiled =
        std::fs::read(assets.join("intel-tiled.bin")).expect("firmware/assets/intel-tiled.bin");
    assert!(
        tiled == beamfield_tools::blob::tile_blob(&fresh.blob).expect("tile"),
        "firmware/assets/intel-tiled.bin is stale: run `cargo xtask demo-assets`"
    );
    // And the blob is one the device accepts.
    let view = beamfield::FieldView::parse(&blob).expect("valid blob");
    assert!(view.width() > 100 && view.height() > 100);
}
