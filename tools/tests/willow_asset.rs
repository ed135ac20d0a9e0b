//! The Willow Garage field the firmware links (`firmware/assets/willow-tiled.bin`, run by
//! `cargo xtask willow`) is exactly what the CLI builds today from the map in `data/`.

use std::path::Path;
use std::process::Command;

#[test]
fn checked_in_willow_field_is_what_field_build_writes() {
    let map = host_tests::data_dir().join("map_willow_garage/willow-full-0.05.yaml");
    let out = std::env::temp_dir().join(format!("beamfield-willow-{}.bin", std::process::id()));
    let run = Command::new(env!("CARGO_BIN_EXE_beamfield"))
        .args(["field", "build"])
        .arg(&map)
        .args(["--encoding", "tiled", "-o"])
        .arg(&out)
        .output()
        .expect("run beamfield");
    assert!(
        run.status.success(),
        "field build failed: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let fresh = std::fs::read(&out).expect("the built field");
    let _ = std::fs::remove_file(&out);
    let asset = Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware/assets/willow-tiled.bin");
    let checked_in = std::fs::read(&asset).expect("firmware/assets/willow-tiled.bin");
    assert!(
        fresh == checked_in,
        "firmware/assets/willow-tiled.bin is stale ({} bytes built, {} checked in): rebuild it \
         with `beamfield field build data/map_willow_garage/willow-full-0.05.yaml --encoding \
         tiled -o firmware/assets/willow-tiled.bin`",
        fresh.len(),
        checked_in.len()
    );
}
