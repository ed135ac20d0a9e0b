//! `beamfield field …` end to end: build, query (with a bad line), render, and a missing file.

use std::io::Write;
use std::path::PathBuf;
use std::process::Stdio;

fn data_dir() -> PathBuf {
    host_tests::data_dir()
}

mod common;
use common::{bin, run_json};

#[test]
fn build_query_render() {
    let out = std::env::temp_dir().join(format!("beamfield-cli-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let blob = out.join("tb3.bin");
    let map = data_dir().join("map_turtlebot3_world/map.yaml");
    let report = run_json(
        bin()
            .args(["--json", "field", "build"])
            .arg(&map)
            .arg("-o")
            .arg(&blob),
    );
    assert_eq!(report["width"], 384);
    assert_eq!(report["occupied_cells"], 795);
    assert_eq!(report["bytes"], 48 + 384 * 384);

    let mut child = bin()
        .args(["field", "query"])
        .arg(&blob)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Cell (0, 0) is unknown, far from the arena: clamped at d_max; (-20, -10) is 10 m off
    // the map's left edge: d_max + 10 m.
    child
        .stdin
        .take()
        .unwrap()
        .write_all(b"-9.975,-9.975\nbad line\n-20,-10\n")
        .unwrap();
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(1), "a bad line must fail the run");
    let stdout = String::from_utf8(o.stdout).unwrap();
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines, ["-9.975,-9.975,2", "-20,-10,12"]);
    assert!(String::from_utf8(o.stderr).unwrap().contains("line 2:"));

    let png = out.join("tb3.png");
    let fig = run_json(
        bin()
            .args(["--json", "field", "render"])
            .arg(&blob)
            .arg("-o")
            .arg(&png),
    );
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!(
        (u64::from(img.width()), u64::from(img.height())),
        (
            fig["width_px"].as_u64().unwrap(),
            fig["height_px"].as_u64().unwrap()
        )
    );
    // 384 cells of 5 cm at 2 px per cell, with room around it for the title, axes and key.
    assert_eq!(fig["px_per_cell"], 2);
    assert!(img.width() > 768 && img.height() > 768);
    // The scale bar: 2 m is the largest 1-2-5 length within a quarter of the 19.2 m wide map.
    assert_eq!(fig["scale_bar_m"].as_f64(), Some(2.0));
    // Occupied cells are drawn in red somewhere in the picture.
    assert!(img.pixels().any(|p| p.0 == [170, 0, 0]));
    // Nothing (title, tick labels, key) runs into the picture's edges.
    let (w, h) = img.dimensions();
    for y in 0..h {
        for x in [0, w - 1] {
            assert_eq!(img.get_pixel(x, y).0, [255; 3], "({x}, {y})");
        }
    }
    for x in 0..w {
        for y in [0, h - 1] {
            assert_eq!(img.get_pixel(x, y).0, [255; 3], "({x}, {y})");
        }
    }
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn missing_map_is_a_clear_error() {
    let st = bin()
        .args([
            "field",
            "build",
            "/nonexistent/map.yaml",
            "-o",
            "/tmp/x.bin",
        ])
        .output()
        .unwrap();
    assert!(!st.status.success());
    let err = String::from_utf8(st.stderr).unwrap();
    assert!(err.contains("cannot read /nonexistent/map.yaml"), "{err}");
}

/// A file of another kind where the map's YAML, a field file or a CARMEN log goes: said as such.
/// The map's image given as its YAML used to be "stream did not contain valid UTF-8"; as a log,
/// "line 5: longer than 65536 bytes (skipped)" or, in `log info`, a log of 0 scans.
#[test]
fn a_file_of_another_kind_is_named() {
    let dir = std::env::temp_dir().join(format!("beamfield-cli-kind-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let pgm = data_dir().join("map_turtlebot3_world/map.pgm");
    let blob = dir.join("tb3.bin");
    let yaml = data_dir().join("map_turtlebot3_world/map.yaml");
    run_json(
        bin()
            .args(["--json", "field", "build"])
            .arg(&yaml)
            .arg("-o")
            .arg(&blob),
    );
    for (input, what) in [(&pgm, "an image"), (&blob, "a distance-field blob")] {
        let st = bin()
            .args(["field", "build"])
            .arg(input)
            .arg("-o")
            .arg(dir.join("x.bin"))
            .output()
            .unwrap();
        assert!(!st.status.success());
        let err = String::from_utf8(st.stderr).unwrap();
        assert!(
            err.contains(&format!(
                "{} is {what}; pass the map's YAML (the file that names ",
                input.display()
            )),
            "{err}"
        );
    }
    let fails = |args: &[&std::ffi::OsStr]| {
        let st = bin().args(args).output().unwrap();
        assert!(!st.status.success(), "{args:?}");
        String::from_utf8(st.stderr).unwrap()
    };
    let err = fails(&["field".as_ref(), "info".as_ref(), yaml.as_os_str()]);
    assert!(
        err.contains(
            "not a distance-field blob (bad magic); a field file is what `beamfield \
             field build MAP.yaml -o FIELD.bin` writes"
        ),
        "{err}"
    );
    for (input, what) in [(&pgm, "an image"), (&blob, "a distance-field blob")] {
        let err = fails(&["log".as_ref(), "info".as_ref(), input.as_os_str()]);
        assert!(
            err.contains(&format!(
                "{} is {what}, not a CARMEN log (a text file of FLASER lines)",
                input.display()
            )),
            "{err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--encoding tiled`, `field info` and `field encode`: the tiled TurtleBot3 blob has the size
/// the format gives for its 1,452 distinct tiles (48 + 8 + 2·96·96 + 16·1,452 bytes), answers
/// queries as the raw one does, and encodes back to the raw blob byte for byte.
#[test]
fn tiled_build_info_encode() {
    let out = std::env::temp_dir().join(format!("beamfield-cli-tiled-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let map = data_dir().join("map_turtlebot3_world/map.yaml");
    let (raw, tiled, back) = (
        out.join("raw.bin"),
        out.join("tiled.bin"),
        out.join("back.bin"),
    );
    for (path, enc) in [(&raw, "raw"), (&tiled, "tiled")] {
        let r = run_json(
            bin()
                .args(["--json", "field", "build", "--encoding", enc])
                .arg(&map)
                .arg("-o")
                .arg(path),
        );
        assert_eq!(r["encoding"], enc);
    }
    let info = run_json(bin().args(["--json", "field", "info"]).arg(&tiled));
    assert_eq!(info["encoding"], "tiled");
    assert_eq!(info["pool_tiles"], 1452);
    assert_eq!(info["bytes"], 48 + 8 + 2 * 96 * 96 + 16 * 1452);
    let raw_info = run_json(bin().args(["--json", "field", "info"]).arg(&raw));
    assert_eq!(raw_info["encoding"], "raw");
    assert_eq!(
        raw_info["bytes_per_cell"],
        (48.0 + 384.0 * 384.0) / (384.0 * 384.0)
    );
    let r = run_json(
        bin()
            .args(["--json", "field", "encode", "--encoding", "raw"])
            .arg(&tiled)
            .arg("-o")
            .arg(&back),
    );
    assert_eq!(r["encoding"], "raw");
    assert_eq!(std::fs::read(&back).unwrap(), std::fs::read(&raw).unwrap());
    let st = bin()
        .args([
            "field",
            "encode",
            "--encoding",
            "tiled",
            "/nonexistent.bin",
            "-o",
        ])
        .arg(out.join("x.bin"))
        .output()
        .unwrap();
    assert!(!st.status.success());
    std::fs::remove_dir_all(&out).ok();
}

/// `--variant` with a map of another size is refused with the variant's path named.
#[test]
fn variant_of_another_geometry_is_refused() {
    let st = bin()
        .args(["field", "build"])
        .arg(data_dir().join("map_turtlebot3_world/map.yaml"))
        .arg("--variant")
        .arg(data_dir().join("map_willow_garage/willow-full-0.05.yaml"))
        .args(["-o", "/tmp/beamfield-variant-refused.bin"])
        .output()
        .unwrap();
    assert!(!st.status.success());
    let err = String::from_utf8(st.stderr).unwrap();
    assert!(
        err.contains("willow-full-0.05.yaml: a variant must have the map's size"),
        "{err}"
    );
}

/// `--clamp-m` (clamped tiled blobs): recorded in the blob (code round(0.5·255/2) = 64, so
/// 64·2/255 m), smaller than the lossless tiled blob, sized as the format says for its pool;
/// `field encode --clamp-m` of the raw blob gives the same bytes; a raw clamped blob is refused
/// both ways; and `field score-variants` on two copies of one map names no variant.
#[test]
fn clamped_build_encode_and_score_variants() {
    let out = std::env::temp_dir().join(format!("beamfield-cli-clamp-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let map = data_dir().join("map_turtlebot3_world/map.yaml");
    let (raw, tiled, clamped, encoded) = (
        out.join("raw.bin"),
        out.join("tiled.bin"),
        out.join("clamped.bin"),
        out.join("encoded.bin"),
    );
    for (path, extra) in [
        (&raw, &["--encoding", "raw"][..]),
        (&tiled, &["--encoding", "tiled"][..]),
        (&clamped, &["--encoding", "tiled", "--clamp-m", "0.5"][..]),
    ] {
        run_json(
            bin()
                .args(["--json", "field", "build"])
                .args(extra)
                .arg(&map)
                .arg("-o")
                .arg(path),
        );
    }
    let info = run_json(bin().args(["--json", "field", "info"]).arg(&clamped));
    let want = 64.0 * 2.0 / 255.0;
    assert!(
        (info["clamp_m"].as_f64().unwrap() - want).abs() < 1e-6,
        "{info}"
    );
    let pool = info["pool_tiles"].as_u64().unwrap();
    assert_eq!(
        info["bytes"].as_u64().unwrap(),
        48 + 8 + 2 * 96 * 96 + 16 * pool
    );
    let lossless = run_json(bin().args(["--json", "field", "info"]).arg(&tiled));
    assert!(lossless["clamp_m"].is_null());
    assert!(info["bytes"].as_u64() < lossless["bytes"].as_u64());
    run_json(
        bin()
            .args([
                "--json",
                "field",
                "encode",
                "--encoding",
                "tiled",
                "--clamp-m",
                "0.5",
            ])
            .arg(&raw)
            .arg("-o")
            .arg(&encoded),
    );
    assert_eq!(
        std::fs::read(&encoded).unwrap(),
        std::fs::read(&clamped).unwrap()
    );
    let refused = [
        bin()
            .args(["field", "build", "--clamp-m", "0.5"])
            .arg(&map)
            .arg("-o")
            .arg(out.join("x.bin"))
            .output()
            .unwrap(),
        bin()
            .args(["field", "encode", "--encoding", "raw"])
            .arg(&clamped)
            .arg("-o")
            .arg(out.join("y.bin"))
            .output()
            .unwrap(),
    ];
    for st in refused {
        assert!(!st.status.success());
        let err = String::from_utf8(st.stderr).unwrap();
        assert!(err.contains("can only be stored tiled"), "{err}");
    }

    let log = data_dir().join("laser_intel_lab/intel-corrected.log");
    let intel = out.join("intel.yaml");
    let st = bin()
        .args(["map", "from-log"])
        .arg(&log)
        .arg("-o")
        .arg(&intel)
        .args(["--resolution", "0.05"])
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let r = run_json(
        bin()
            .args(["--json", "field", "score-variants", "--variant"])
            .arg(&intel)
            .arg("--variant")
            .arg(&intel)
            .arg("--log")
            .arg(&log)
            .args(["--scan", "50", "--sigma-hit", "0.0588"]),
    );
    let v = r["variants"].as_array().unwrap();
    assert_eq!(v.len(), 2);
    assert_eq!(v[0]["log_likelihood_nats"], v[1]["log_likelihood_nats"]);
    assert!(r["preferred"].is_null(), "{r}");
    assert_eq!(r["lead_nats"], 0.0);
    std::fs::remove_dir_all(&out).ok();
}
