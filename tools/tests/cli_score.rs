//! `beamfield score --overlay` end to end on the demo's blob and a real Intel scan: the best
//! grid pose it prints is the one a plain loop over the same poses finds, the picture is
//! written, and a malformed option is a clear error.

use beamfield::field::{FieldView, LikelihoodField, LikelihoodParams};
use beamfield::{Pose, SensorMount};
use beamfield_tools::input::carmen::{CarmenLog, ReadOptions};
use std::path::PathBuf;
use std::process::Command;

mod common;
use common::{bin, run_json};

fn data_dir() -> PathBuf {
    host_tests::data_dir()
}

fn blob_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../firmware/assets/intel.bin")
}

fn log_path() -> PathBuf {
    data_dir().join("laser_intel_lab/intel-corrected.log")
}

/// A fresh scratch directory for one test.
fn scratch(name: &str) -> PathBuf {
    let out = std::env::temp_dir().join(format!("beamfield-score-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    out
}

/// `beamfield [--json] score --field <the demo's blob> --log <the Intel log>`, to which each
/// test adds its options.
fn score(json: bool) -> Command {
    let mut c = bin();
    if json {
        c.arg("--json");
    }
    c.args(["score", "--field"])
        .arg(blob_path())
        .arg("--log")
        .arg(log_path());
    c
}

#[test]
fn overlay_reports_the_grid_best_and_draws_it() {
    let out = scratch("overlay");
    let png = out.join("overlay.png");
    let scan_index = 728usize;
    let v = run_json(
        score(true)
            .args(["--scan", &scan_index.to_string(), "--sigma-hit", "0.0588"])
            .args([
                "--grid-half",
                "0.06",
                "--grid-step",
                "0.01",
                "--grid-half-deg",
                "1",
            ])
            .arg("--overlay")
            .arg(&png),
    );
    let best = &v["best_grid_pose"];
    // 13 × 13 positions, 9 headings (±1° in 0.25° steps).
    assert_eq!(best["grid_poses"], 13 * 13 * 9);
    let got: Vec<f64> = best["pose_m_m_rad"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();

    // The same search, written out: every pose of the grid scored with the per-pose path,
    // keeping the first of the highest.
    let blob = std::fs::read(blob_path()).unwrap();
    let log = CarmenLog::read_path(&log_path(), ReadOptions::default()).unwrap();
    let max_range = log.max_range.value_m().unwrap();
    let lf = LikelihoodField::new(
        FieldView::parse(&blob).unwrap(),
        LikelihoodParams::new(0.95, 0.05, 0.0588, max_range).unwrap(),
    );
    let layout = log.layout_with_mount::<180>(SensorMount::CENTERED).unwrap();
    let s = &log.scans[scan_index];
    let scan = s.to_scan::<180>().unwrap();
    let c = s.pose;
    let mut want = (f32::NEG_INFINITY, Pose::new(0.0, 0.0, 0.0));
    for it in -4i32..=4 {
        for iy in -6i32..=6 {
            for ix in -6i32..=6 {
                let p = Pose::new(
                    (f64::from(c.x_m) + f64::from(ix) * 0.01) as f32,
                    (f64::from(c.y_m) + f64::from(iy) * 0.01) as f32,
                    (f64::from(c.theta_rad) + (f64::from(it) * 0.25).to_radians()) as f32,
                );
                let ll = lf.score(&layout, &scan, &p).log_likelihood;
                if ll > want.0 {
                    want = (ll, p);
                }
            }
        }
    }
    let w = want.1;
    assert_eq!(
        got,
        vec![f64::from(w.x_m), f64::from(w.y_m), f64::from(w.theta_rad)],
        "best pose"
    );
    assert_eq!(
        best["log_likelihood_nats"].as_f64().unwrap(),
        f64::from(want.0)
    );
    // The grid holds the given pose, so its best is at least as good.
    assert!(
        best["log_likelihood_nats"].as_f64().unwrap() >= v["log_likelihood_nats"].as_f64().unwrap()
    );
    assert!(v["files"]
        .as_array()
        .unwrap()
        .iter()
        .any(|f| f.as_str() == Some(png.to_str().unwrap())));
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), (900, 900));
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn malformed_overlay_centre_is_a_clear_error() {
    let out = scratch("bad");
    let png = out.join("never.png");
    let st = score(false)
        .args(["--scan", "50", "--grid-half", "0.02", "--grid-step", "0.01"])
        .args([
            "--grid-half-deg",
            "0.5",
            "--overlay-center=1,x",
            "--overlay",
        ])
        .arg(&png)
        .output()
        .unwrap();
    assert!(!st.status.success());
    let err = String::from_utf8_lossy(&st.stderr);
    assert!(err.contains("--overlay-center"), "{err}");
    assert!(!png.exists());
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn a_log_without_scans_is_named_and_max_range_can_be_given() {
    let out = scratch("log");
    let empty = out.join("empty.log");
    std::fs::write(&empty, "# a comment\nODOM 0 0 0 0 0 0 1 h 1\n").unwrap();
    let st = bin()
        .args(["score", "--field"])
        .arg(blob_path())
        .arg("--log")
        .arg(&empty)
        .args(["--scan", "0"])
        .output()
        .unwrap();
    assert!(!st.status.success());
    let err = String::from_utf8_lossy(&st.stderr);
    assert!(err.contains("no FLASER scans"), "{err}");

    // --max-range overrides the detected 81.83 m: at 10 m, readings of 10 m or more become
    // max-range readings, so fewer beams are scored than with the detected value.
    let run = |extra: &[&str]| -> serde_json::Value {
        run_json(score(true).args(["--scan", "50"]).args(extra))
    };
    let detected = run(&[]);
    let given = run(&["--max-range", "10"]);
    let n = |v: &serde_json::Value, k: &str| v[k].as_u64().unwrap();
    assert!(n(&given, "beams_skipped_max_range") > n(&detected, "beams_skipped_max_range"));
    for v in [&detected, &given] {
        assert_eq!(
            n(v, "beams_scored") + n(v, "beams_skipped_max_range") + n(v, "beams_skipped_invalid"),
            180
        );
    }
    // The skipped count is the number of the scan's readings at or above the max range.
    let log = CarmenLog::read_path(&log_path(), ReadOptions::default()).unwrap();
    let ranges = log.scans[50].to_scan::<180>().unwrap();
    let at_or_above = |m: f32| ranges.ranges_m().iter().filter(|&&r| r >= m).count() as u64;
    assert_eq!(n(&given, "beams_skipped_max_range"), at_or_above(10.0));
    assert_eq!(
        n(&detected, "beams_skipped_max_range"),
        at_or_above(log.max_range.value_m().unwrap())
    );
    std::fs::remove_dir_all(&out).ok();
}

/// `beamfield calibrate` on three Intel scans and a coarse grid: κ is bracketed to the stated
/// relative precision, the coverage is reached at κ, the scans used are reported, the plot is
/// written, and with stderr not a terminal (a pipe here) no progress is written to it.
#[test]
fn calibrate_brackets_kappa_and_keeps_stderr_quiet() {
    let out = scratch("calibrate");
    let png = out.join("calib.png");
    let mut cmd = bin();
    cmd.args(["--json", "calibrate", "--field"])
        .arg(blob_path())
        .arg("--log")
        .arg(log_path())
        .args(["--scans", "3", "--half-xy", "0.04", "--step-xy", "0.01"])
        .args(["--half-deg", "1", "--step-deg", "0.5", "-o"])
        .arg(&png);
    let o = cmd.output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        o.stderr.is_empty(),
        "stderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let cal = &v["calibration"];
    assert_eq!(cal["scans"], 3);
    let level = cal["level"].as_f64().unwrap();
    assert_eq!(level, 0.95);
    let precision = cal["relative_precision"].as_f64().unwrap();
    assert!(precision > 0.0 && precision <= 0.01, "{precision}");
    let k = cal["kappa"].as_f64().unwrap();
    assert!(cal["coverage_at_kappa"].as_f64().unwrap() >= level);
    if cal["coverage_at_1"].as_f64().unwrap() < level {
        let below = cal["kappa_below"].as_f64().unwrap();
        assert!(below < k && k / below <= 1.0 + precision, "{below} .. {k}");
    } else {
        assert_eq!(k, 1.0);
    }
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), (900, 560));
    std::fs::remove_dir_all(&out).ok();
}
