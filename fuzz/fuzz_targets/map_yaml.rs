//! Fuzzes the host tool's map reader (map_server YAML + PGM/PNG): the input is split into a
//! YAML text and an image file (the first two bytes give the YAML's length), written to a
//! scratch folder (in `/dev/shm` when it exists), and loaded with a 2^20-cell limit. Any input
//! must give a map or a typed error, never a panic, and an accepted map must have
//! `width·height` cells within the limit.
//!
//! The scratch folder is the harness's speed: three small files are written per input, and on
//! the machine of the runs in docs/fuzzing.md (ext4 mounted with `discard`) rewriting them on disk held the
//! target at about 600 inputs a second; on tmpfs it runs at about 33,000 (docs/fuzzing.md has
//! the measurements; capping images at 4,096 cells instead gave only 1,950).
//!
//! Run: `cargo +nightly fuzz run map_yaml` from the repository root.

#![no_main]

use beamfield_tools::input::map::load_map_limited;
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

/// A scratch folder per fuzzing process.
fn dir() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let shm = std::path::Path::new("/dev/shm");
        let base = if shm.is_dir() {
            shm.to_path_buf()
        } else {
            std::env::temp_dir()
        };
        let d = base.join(format!("beamfield-fuzz-map-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("scratch folder");
        d
    })
}

const MAX_CELLS: u64 = 1 << 20;

fuzz_target!(|data: &[u8]| {
    let Some((len, rest)) = data.split_first_chunk::<2>() else {
        return;
    };
    let n = usize::from(u16::from_le_bytes(*len)).min(rest.len());
    let (yaml, image) = rest.split_at(n);
    let d = dir();
    // The image is written under the names a YAML most likely uses; the YAML decides.
    std::fs::write(d.join("map.yaml"), yaml).expect("write yaml");
    std::fs::write(d.join("map.pgm"), image).expect("write image");
    std::fs::write(d.join("map.png"), image).expect("write image");
    if let Ok(m) = load_map_limited(&d.join("map.yaml"), MAX_CELLS) {
        assert!(u64::from(m.width) * u64::from(m.height) <= MAX_CELLS);
        assert_eq!(m.cells.len(), m.width as usize * m.height as usize);
    }
});
