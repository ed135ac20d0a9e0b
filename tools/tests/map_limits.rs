//! Hostile map inputs: an image header announcing more cells than the limit is refused before
//! decoding (and before reading the file's body), `--max-cells` raises the limit, the image must
//! be a regular file, and it is found relative to the YAML, not the working directory.

mod common;

use beamfield_tools::input::map::{load_map, load_map_limited, MapError, DEFAULT_MAX_CELLS};
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

/// The Intel log with every FLASER pose (laser and robot x, y) moved by `shift` metres.
fn shifted_intel(dir: &std::path::Path, shift: f64) -> PathBuf {
    let src = host_tests::data_dir().join("laser_intel_lab/intel-corrected.log");
    let text = std::fs::read_to_string(src).unwrap();
    let mut out = String::new();
    for line in text.lines() {
        let mut t: Vec<String> = line.split_whitespace().map(str::to_string).collect();
        if t.first().map(String::as_str) == Some("FLASER") {
            let n: usize = t[1].parse().unwrap();
            // x, y (laser pose) and odom_x, odom_y after the n ranges.
            for k in [2 + n, 3 + n, 5 + n, 6 + n] {
                let v: f64 = t[k].parse().unwrap();
                t[k] = format!("{:.6}", v + shift);
            }
        }
        out.push_str(&t.join(" "));
        out.push('\n');
    }
    let path = dir.join(format!("intel-shifted-{shift:e}.log"));
    std::fs::write(&path, out).unwrap();
    path
}

/// `map from-log LOG` (default settings) as JSON, or its one-line error.
fn map_from_log(log: &std::path::Path, out: &std::path::Path) -> Result<serde_json::Value, String> {
    let o = common::run_bounded(
        &[
            "--json".as_ref(),
            "map".as_ref(),
            "from-log".as_ref(),
            log.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ],
        None,
    );
    if o.status.success() {
        Ok(serde_json::from_slice(&o.stdout).unwrap())
    } else {
        assert_eq!(o.status.code(), Some(1));
        Err(common::one_line_error(&o))
    }
}

#[test]
fn a_log_far_from_the_origin_builds_the_same_map_or_is_refused() {
    let d = scratch("far");
    let intel = host_tests::data_dir().join("laser_intel_lab/intel-corrected.log");
    let base = map_from_log(&intel, &d.join("base.yaml")).unwrap();
    assert_eq!(base["cells"]["occupied"], 12_710);
    // 1e9 m (a million km): with f32 poses (64 m apart there) the map had 1,101
    // occupied cells. In f64 the coordinates are 1.2e-7 m apart, 1/400,000 of a 5 cm cell: the
    // same map, cell for cell.
    let far = map_from_log(&shifted_intel(&d, 1e9), &d.join("far.yaml")).unwrap();
    for key in ["occupied", "free", "unknown"] {
        assert_eq!(far["cells"][key], base["cells"][key], "{key}");
    }
    assert_eq!(
        (far["width"].clone(), far["height"].clone()),
        (base["width"].clone(), base["height"].clone())
    );
    let pixels = |p: &str| {
        let b = std::fs::read(d.join(p)).unwrap();
        // The PGM's pixels: after its 4-line header (magic, comment, size, maxval).
        let mut at = 0;
        for _ in 0..4 {
            at += b[at..].iter().position(|&c| c == b'\n').unwrap() + 1;
        }
        b[at..].to_vec()
    };
    assert!(pixels("far.pgm") == pixels("base.pgm"), "pixels differ");
    // 1e12 m: f64 coordinates are 1.2e-4 m apart, more than 1/1024 of a cell: refused.
    let err = map_from_log(&shifted_intel(&d, 1e12), &d.join("farther.yaml")).unwrap_err();
    assert!(
        err.starts_with("error: poses and end points reach 1.0000000000")
            && err.contains(
                "f64 coordinates are 1.220703125e-4 m apart: more than 1/1024 of a 0.05 m cell"
            ),
        "{err}"
    );
    assert!(!d.join("farther.yaml").exists());
}

#[test]
fn map_from_log_bounds_its_grid() {
    let d = scratch("grid");
    // Two one-beam scans 300 m apart (a 100-byte log): 6,040 × 6,060 cells at 5 cm, 440 MB of
    // grids to allocate; refused at the default limit, the same as `field build`'s.
    let log = d.join("two.log");
    std::fs::write(
        &log,
        "FLASER 1 1.0 0 0 0 0 0 0 0 h 0\nFLASER 1 1.0 300 300 0 300 300 0 1 h 1\n",
    )
    .unwrap();
    let (log, out) = (log.display().to_string(), d.join("two.yaml"));
    let out = out.display().to_string();
    let base = [
        "map",
        "from-log",
        log.as_str(),
        "--max-range",
        "5",
        "-o",
        out.as_str(),
    ];
    let o = common::run_bounded(&base, None);
    assert_eq!(o.status.code(), Some(1), "{o:?}");
    assert_eq!(
        common::one_line_error(&o),
        "error: map of 6040 × 6060 = 36602400 cells is over the limit of 16777216; use a \
         coarser resolution (or raise the limit with --max-cells)"
    );
    assert!(!d.join("two.yaml").exists());
    // --max-cells raises it, up to the builder's ceiling of 2^28 cells.
    let mut args = base.to_vec();
    args.extend(["--max-cells", "268435457"]);
    let o = common::run_bounded(&args, None);
    assert_eq!(o.status.code(), Some(2), "{o:?}");
    let mut args = base.to_vec();
    args.extend(["--max-cells", "36602400", "--resolution", "0.1"]);
    let o = common::run_bounded(&args, None);
    assert!(o.status.success(), "{o:?}");
}
