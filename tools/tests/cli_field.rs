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
