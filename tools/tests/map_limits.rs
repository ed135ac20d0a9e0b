//! Hostile map inputs: an image header announcing more cells than the limit is refused before
//! decoding (and before reading the file's body), `--max-cells` raises the limit, the image must
//! be a regular file, and it is found relative to the YAML, not the working directory.

mod common;

use beamfield_tools::map::{load_map, load_map_limited, MapError, DEFAULT_MAX_CELLS};
use common::bin;
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beamfield-maplimits-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

const YAML: &str = "image: map.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n\
                    occupied_thresh: 0.65\nfree_thresh: 0.196\n";

/// A binary PGM whose header says `w × h` but which holds only `body` bytes after it, padded
/// (sparsely) to `file_len` bytes.
fn write_pgm(path: &PathBuf, w: u32, h: u32, body: &[u8], file_len: u64) {
    let mut bytes = format!("P5\n{w} {h}\n255\n").into_bytes();
    bytes.extend_from_slice(body);
    std::fs::write(path, &bytes).unwrap();
    let f = std::fs::OpenOptions::new().write(true).open(path).unwrap();
    if file_len > bytes.len() as u64 {
        f.set_len(file_len).unwrap();
    }
}

#[test]
fn oversized_header_is_refused_before_decoding() {
    let d = scratch("big");
    std::fs::write(d.join("map.yaml"), YAML).unwrap();
    // 16384 × 16384 = 268 M cells announced; the file is 1 GiB (sparse) of zeros. Reading it
    // whole or decoding it would take GiBs; the header alone decides.
    write_pgm(&d.join("map.pgm"), 16384, 16384, &[], 1 << 30);
    match load_map(&d.join("map.yaml")) {
        Err(MapError::TooLarge {
            width,
            height,
            max_cells,
            ..
        }) => {
            assert_eq!((width, height), (16384, 16384));
            assert_eq!(max_cells, DEFAULT_MAX_CELLS);
        }
        other => panic!("expected TooLarge, got {other:?}"),
    }
    // On the command line: a clear error that states the size and the flag, exit status 1.
    let out = bin()
        .args(["field", "build"])
        .arg(d.join("map.yaml"))
        .arg("-o")
        .arg(d.join("out.bin"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("16384 x 16384 = 268435456 cells") && err.contains("--max-cells"),
        "{err}"
    );
    assert!(!d.join("out.bin").exists());
}

#[test]
fn max_cells_flag_raises_the_limit() {
    let d = scratch("flag");
    std::fs::write(d.join("map.yaml"), YAML).unwrap();
    // 300 × 200 = 60,000 cells, all free (254).
    write_pgm(&d.join("map.pgm"), 300, 200, &[254u8; 60_000], 0);
    assert!(matches!(
        load_map_limited(&d.join("map.yaml"), 59_999),
        Err(MapError::TooLarge { .. })
    ));
    let m = load_map_limited(&d.join("map.yaml"), 60_000).unwrap();
    assert_eq!((m.width, m.height), (300, 200));
    let build = |limit: &str| {
        bin()
            .args(["field", "build", "--max-cells", limit])
            .arg(d.join("map.yaml"))
            .arg("-o")
            .arg(d.join("out.bin"))
            .output()
            .unwrap()
    };
    let refused = build("1000");
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("300 x 200 = 60000 cells"));
    let ok = build("60000");
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    assert!(d.join("out.bin").is_file());
}

#[test]
fn image_must_be_a_regular_file() {
    let d = scratch("dev");
    std::fs::write(d.join("map.yaml"), YAML.replace("map.pgm", "/dev/zero")).unwrap();
    match load_map(&d.join("map.yaml")) {
        Err(MapError::NotAFile(p)) => assert_eq!(p, PathBuf::from("/dev/zero")),
        other => panic!("expected NotAFile, got {other:?}"),
    }
    std::fs::create_dir_all(d.join("sub")).unwrap();
    std::fs::write(d.join("map2.yaml"), YAML.replace("map.pgm", "sub")).unwrap();
    assert!(matches!(
        load_map(&d.join("map2.yaml")),
        Err(MapError::NotAFile(_))
    ));
}

#[test]
fn image_is_found_relative_to_the_yaml() {
    let d = scratch("rel");
    std::fs::create_dir_all(d.join("maps")).unwrap();
    std::fs::write(d.join("maps/map.yaml"), YAML).unwrap();
    write_pgm(&d.join("maps/map.pgm"), 4, 3, &[0u8; 12], 0);
    // A decoy of another size where a working-directory-relative lookup would find it.
    write_pgm(&d.join("map.pgm"), 9, 9, &[0u8; 81], 0);
    let out = bin()
        .current_dir(&d)
        .args(["field", "build", "maps/map.yaml", "-o", "out.bin"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let m = load_map(&d.join("maps/map.yaml")).unwrap();
    assert_eq!((m.width, m.height), (4, 3));
}
