//! The `beamfield log info` and `beamfield map from-log` commands, run as a user would.

use std::path::PathBuf;
use std::process::Output;

mod common;

fn beamfield(args: &[&str]) -> Output {
    common::bin().args(args).output().unwrap()
}

fn intel() -> String {
    host_tests::data_dir()
        .join("laser_intel_lab/intel-corrected.log")
        .display()
        .to_string()
}

fn tmp(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_carmen");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// A small log: a robot at the origin facing +x in a 4 m × 4 m box (walls at x = ±2, y = ±2),
/// 5 beams at −90°, −54°, −18°, 18°, 54°; the −90° beam has no return (sentinel 40.0).
fn box_log() -> String {
    let mut text = String::from("# a box\nPARAM robot_frontlaser_offset 0.0 nohost 0\n");
    for k in 0..4 {
        let ranges: Vec<String> = (0..5)
            .map(|i| {
                if i == 0 {
                    "40.0".to_string()
                } else {
                    let a = (-90.0f64 + 36.0 * i as f64).to_radians();
                    format!("{:.4}", (2.0 / a.cos().abs()).min(2.0 / a.sin().abs()))
                }
            })
            .collect();
        text += &format!(
            "FLASER 5 {} 0 0 0 0 0 0 {k}.0 host {k}.0\nODOM 0 0 0 0 0 0 {k}.0 host {k}.0\n",
            ranges.join(" ")
        );
    }
    text
}

#[test]
fn log_info_json_on_the_intel_log() {
    let out = beamfield(&["--json", "log", "info", &intel()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["stats"]["scans"], 910);
    assert_eq!(v["stats"]["beams"], 180);
    assert_eq!(v["max_range"]["value_m"], 81.83);
    assert_eq!(v["max_range"]["source"], "detected");
    assert_eq!(v["stats"]["max_range_readings"], 4172);
    assert_eq!(v["bad_lines"].as_array().map(Vec::len), Some(0));
    let text = beamfield(&["log", "info", &intel()]);
    let text = String::from_utf8(text.stdout).unwrap();
    assert!(
        text.contains("81.83 m (detected): 4172 readings (2.55 %)"),
        "{text}"
    );
}

#[test]
fn map_from_log_writes_a_map_server_pair() {
    let log = tmp("box.log");
    std::fs::write(&log, box_log()).unwrap();
    let yaml = tmp("box.yaml");
    let out = beamfield(&[
        "--json",
        "map",
        "from-log",
        log.to_str().unwrap(),
        "-o",
        yaml.to_str().unwrap(),
        "--resolution",
        "0.1",
        "--max-range",
        "40",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["resolution_m"], 0.1);
    assert_eq!(v["readings"]["hits"], 16);
    assert_eq!(v["readings"]["max_range"], 4);
    let text = std::fs::read_to_string(&yaml).unwrap();
    assert!(
        text.contains("image: box.pgm\n") && text.contains("resolution: 0.1\n"),
        "{text}"
    );
    let pgm = std::fs::read(tmp("box.pgm")).unwrap();
    assert!(pgm.starts_with(b"P5\n"));
    assert!(v["cells"]["occupied"].as_u64().unwrap() >= 4);
}

#[test]
fn errors_are_clear() {
    let yaml = tmp("never.yaml");
    let y = yaml.to_str().unwrap();
    // A missing file.
    let out = beamfield(&["map", "from-log", "/nonexistent/x.log", "-o", y]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cannot read /nonexistent/x.log"), "{err}");
    // A malformed line, with its number.
    let bad = tmp("bad.log");
    std::fs::write(&bad, format!("{}FLASER 5 1 2 3\n", box_log())).unwrap();
    let out = beamfield(&["map", "from-log", bad.to_str().unwrap(), "-o", y]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("line 11:") && err.contains("found 3"), "{err}");
    // …which `log info` lists instead of failing on.
    let out = beamfield(&["log", "info", bad.to_str().unwrap()]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("bad lines: 1"));
    // No detectable max range: the user is told to give it.
    let log = tmp("nosentinel.log");
    std::fs::write(&log, box_log().replace("40.0 ", "1.9 ")).unwrap();
    let out = beamfield(&["map", "from-log", log.to_str().unwrap(), "-o", y]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--max-range"));
    // A bad resolution.
    let out = beamfield(&[
        "map",
        "from-log",
        log.to_str().unwrap(),
        "-o",
        y,
        "--resolution",
        "0",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--resolution"));
    assert!(!yaml.exists());
}

#[test]
fn help_explains_the_commands() {
    let out = beamfield(&["map", "from-log", "--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(
        help.contains("map_server") && help.contains("--max-range-free"),
        "{help}"
    );
    let out = beamfield(&["log", "info", "--help"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("max-range"));
}
