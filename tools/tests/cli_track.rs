//! `beamfield track`: help text, typed errors, and a short run on a synthetic room.

mod common;

use beamfield::field::{emit_blob, emit_free_space, free_space_len, FieldHeader, FreeSpaceGrid};
use common::bin;

#[test]
fn help_explains_the_command() {
    let out = bin().args(["track", "--help"]).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for word in [
        "--particles",
        "--kappa",
        "--odom-noise",
        "--init",
        "--kidnap",
        "--seed",
        "--unexplained",
    ] {
        assert!(text.contains(word), "help lacks {word}");
    }
}

#[test]
fn global_init_needs_the_free_space_section() {
    let dir = std::env::temp_dir().join(format!("bf-track-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A 40 × 40 room of 10 cm cells (walls on the border) with no free-space section, and a
    // two-scan CARMEN log whose ranges include the max-range value 20 m.
    let h = FieldHeader::new(40, 40, 0.1, 0.0, 0.0);
    let codes: Vec<u8> = (0..1600u32)
        .map(|i| {
            let (x, y) = (i % 40, i / 40);
            let d = x.min(y).min(39 - x).min(39 - y);
            h.encode_distance_m(f64::from(d) * 0.1)
        })
        .collect();
    let mut blob = vec![0u8; h.required_len().unwrap()];
    emit_blob(&h, &codes, &mut blob).unwrap();
    let field = dir.join("room.bin");
    std::fs::write(&field, &blob).unwrap();
    let ranges: Vec<String> = (0..180)
        .map(|i| {
            if i % 9 == 0 {
                "20.0".to_string()
            } else {
                format!("{:.2}", 1.0 + (i % 7) as f32 * 0.1)
            }
        })
        .collect();
    let ranges = ranges.join(" ");
    let log = dir.join("room.log");
    std::fs::write(
        &log,
        format!(
            "FLASER 180 {ranges} 2.0 2.0 0.0 2.0 2.0 0.0 1.0 host 1.0\n\
             FLASER 180 {ranges} 2.1 2.0 0.0 2.1 2.0 0.0 2.0 host 2.0\n"
        ),
    )
    .unwrap();
    let run = |extra: &[&str]| {
        bin()
            .args(["track", "--field"])
            .arg(&field)
            .arg("--log")
            .arg(&log)
            .args(["--particles", "50"])
            .args(extra)
            .output()
            .unwrap()
    };
    let out = run(&["--init", "global"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--free-space"), "{err}");
    // Recovery would inject nothing without the free space: refused, not silently off.
    let out = run(&["--recovery", "0.001,0.1"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--recovery") && err.contains("--free-space"),
        "{err}"
    );
    // A guard on recovery that is off cannot take effect.
    let out = run(&["--recovery-while-unsettled"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--recovery-while-unsettled"), "{err}");
    // Tracking from the logged pose needs no free space.
    let out = run(&["--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["scans"], 2);
    // The removal of unexplained beams runs; a distance of 0 is refused as a usage error.
    let out = run(&["--unexplained", "0.25,0.5"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = run(&["--unexplained", "0,0.5"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--unexplained"), "{err}");
    // The defaults the docs name: κ 64, odometry noise α 0.02.
    assert_eq!(v["kappa"], 64.0);
    assert!(v["odom_alphas"]
        .as_array()
        .unwrap()
        .iter()
        .all(|a| (a.as_f64().unwrap() - 0.02).abs() < 1e-7));
    // The study options run, are echoed in the report, and bad values are refused by name.
    let out = run(&[
        "--json",
        "--kappa-uncertain",
        "8.25",
        "--adaptive-sigma",
        "1,0.3",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let study: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(study["kappa_uncertain"], 8.25);
    assert_eq!(study["adaptive_sigma"][0], 1.0);
    assert!((study["adaptive_sigma"][1].as_f64().unwrap() - 0.3).abs() < 1e-7);
    for (flag, value) in [
        ("--kappa-uncertain", "0"),
        ("--kappa-uncertain", "nan"),
        ("--adaptive-sigma", "-1,0.3"),
        ("--adaptive-sigma", "1,0"),
        ("--adaptive-sigma", "1"),
    ] {
        let out = run(&[flag, value]);
        assert!(!out.status.success(), "{flag} {value} accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(flag), "{flag} {value}: {err}");
    }
    // With the section appended, global initialization runs.
    let grid = FreeSpaceGrid::of_view(&beamfield::field::FieldView::parse(&blob).unwrap());
    let flags: Vec<bool> = (0..1600u32)
        .map(|i| {
            let (x, y) = (i % 40, i / 40);
            x > 0 && y > 0 && x < 39 && y < 39
        })
        .collect();
    let mut fs = vec![0u8; free_space_len(&grid, &flags).unwrap()];
    emit_free_space(&grid, &flags, &mut fs).unwrap();
    blob.extend(fs);
    std::fs::write(&field, &blob).unwrap();
    let out = run(&["--init", "global"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
