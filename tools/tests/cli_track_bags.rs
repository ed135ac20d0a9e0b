//! `beamfield track --bag` on bags as ROS 2 users record them, each compared with the run on
//! the MCAP bag `tools/tests/data/intel-bag` (the Intel log's first 120 scans, written by PyPI
//! rosbags): the same recording stored as sqlite3 (`.db3`, Humble's default), the laser's mount
//! as a chain of `/tf_static` transforms, the odometry only on `/tf`, scans whose beam count and
//! angles change every revolution (`tools/tests/data/make_db3.py` wrote them with rosbags); a
//! scan frame not connected to the base frame is refused, and a lost run ends with its own exit
//! code.

mod common;

use common::bin;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

fn field() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../firmware/assets/intel.bin")
        .display()
        .to_string()
}

/// `beamfield --json track` on `bag` with `extra` arguments: the exit code, the report
/// (`Null` when stdout is not JSON) and stderr.
fn track(bag: &Path, extra: &[&str]) -> (i32, Value, String) {
    let out = bin()
        .args(["--json", "track", "--field", &field(), "--bag"])
        .arg(bag)
        .args(["--reference-topic", "/ground_truth", "--seeds", "2"])
        .args(extra)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        serde_json::from_slice(&out.stdout).unwrap_or(Value::Null),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The MCAP bag's run: the reference every other storage and layout is compared with.
fn mcap_run() -> Value {
    let (code, v, err) = track(&data().join("intel-bag"), &[]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(v["bag"]["scans_used"], 120);
    assert_eq!(v["lost_runs"], 0);
    v
}

/// The per-scan estimates and every error figure of two reports are the same, value for
/// value.
fn assert_same_runs(a: &Value, b: &Value) {
    assert!(!a["runs"][0]["per_scan"].as_array().unwrap().is_empty());
    assert_eq!(a["runs"], b["runs"]);
    for k in [
        "trans_rmse_cm_min_med_max",
        "heading_rmse_deg_min_med_max",
        "max_trans_m_min_med_max",
        "within_10cm_2deg_pct_min_med_max",
        "lost_runs",
    ] {
        assert_eq!(a[k], b[k], "{k}");
    }
}

#[test]
fn a_db3_bag_tracks_as_the_mcap_bag() {
    let mcap = mcap_run();
    for bag in [
        data().join("intel-bag-db3"),
        data().join("intel-bag-db3/intel-bag-db3.db3"),
    ] {
        let (code, v, err) = track(&bag, &[]);
        assert_eq!(code, 0, "{}: {err}", bag.display());
        // The whole report: estimates, errors, what the bag gave.
        assert_eq!(v, mcap, "{}", bag.display());
    }
}

#[test]
fn a_damaged_db3_is_refused_with_its_line() {
    let dir = std::env::temp_dir().join(format!("bf-track-db3-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = std::fs::read(data().join("intel-bag-db3/intel-bag-db3.db3")).unwrap();
    let cases: [(&str, Vec<u8>, &str); 2] = [
        ("junk.db3", b"hello".to_vec(), "is not an SQLite database"),
        (
            "half.db3",
            good[..good.len() / 2].to_vec(),
            "is damaged: database disk image is malformed",
        ),
    ];
    for (name, bytes, want) in cases {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let (code, _, err) = track(&path, &[]);
        assert_eq!(code, 1, "{name}: {err}");
        assert!(err.contains(want), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_mount_through_a_chain_tracks_as_the_single_transform() {
    let mcap = mcap_run();
    let chain = data().join("intel-bag-chain");
    let (code, v, err) = track(&chain, &["--base-frame", "base_footprint"]);
    assert_eq!(code, 0, "{err}");
    assert_same_runs(&v, &mcap);
    assert_eq!(v["bag"]["mount"], mcap["bag"]["mount"]);
    assert_eq!(v["bag"]["mount_from_tf"], true);
    assert_eq!(v["odometry"], "recorded (/odom)");
    // From base_link, the laser is make_db3.py's base_link → laser: (−0.25, 0.10 m, 0).
    let (code, v, err) = track(&chain, &["--base-frame", "base_link", "--scans", "3"]);
    assert_eq!(code, 0, "{err}");
    let m: Vec<f64> = v["bag"]["mount"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!(
        (m[0] + 0.25).abs() < 1e-6 && (m[1] - 0.10).abs() < 1e-6 && m[2] == 0.0,
        "{m:?}"
    );
}

#[test]
fn a_scan_frame_not_connected_to_the_base_frame_is_refused() {
    let (code, v, err) = track(&data().join("intel-bag-chain"), &["--base-frame", "map"]);
    assert_eq!(code, 1, "{err}");
    assert_eq!(v, Value::Null);
    assert!(
        err.contains(
            r#"the scans' frame "laser" is not connected to the base frame "map" by /tf_static"#
        ),
        "{err}"
    );
    assert!(err.contains("base_footprint → base_link"), "{err}");
}

#[test]
fn odometry_from_tf_tracks_as_the_odometry_topic() {
    let mcap = mcap_run();
    // The bag has /odom and /tf; naming an odometry topic it does not have leaves /tf.
    let (code, v, err) = track(
        &data().join("intel-bag-chain"),
        &[
            "--base-frame",
            "base_footprint",
            "--odom-topic",
            "/wheel_odom",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert_same_runs(&v, &mcap);
    assert_eq!(
        v["odometry"],
        "recorded (/tf: odom → base_footprint; the bag has no /wheel_odom)"
    );
    // Said on stderr too (a mistyped topic name lands here).
    assert!(
        err.contains("the bag has no /wheel_odom topic: odometry from /tf (odom → base_footprint)"),
        "{err}"
    );
    // No odometry anywhere: the line names what /tf has.
    let (code, _, err) = track(
        &data().join("intel-bag-chain"),
        &["--odom-topic", "/wheel_odom", "--odom-frame", "world"],
    );
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("no topic /wheel_odom, and no transform world → base_link on /tf (there: odom → base_footprint)"),
        "{err}"
    );
}

#[test]
fn a_lost_run_ends_with_its_exit_code_and_a_line() {
    // The wrong base frame: imu_link, turned 34° from base_link (make_db3.py), so the scans
    // are taken 34° off and the odometry is read in the wrong frame; every seed ends metres
    // away from the reference.
    let (code, v, err) = track(
        &data().join("intel-bag-chain"),
        &["--base-frame", "imu_link"],
    );
    assert_eq!(code, 3, "{err}");
    assert_eq!(v["lost_runs"], 2, "the report is printed in full");
    // The mount is the laser's pose in imu_link, composed backwards through base_link. By
    // hand from make_db3.py's transforms: the laser is (−0.30, 0.10) from the imu in
    // base_link's axes, seen from the imu turned 0.6 rad.
    let (s, c) = 0.6f64.sin_cos();
    let want = [c * -0.30 + s * 0.10, -s * -0.30 + c * 0.10, -0.6];
    for (k, w) in want.iter().enumerate() {
        let got = v["bag"]["mount"][k].as_f64().unwrap();
        assert!((got - w).abs() < 1e-6, "mount[{k}] {got}, want {w}");
    }
    assert!(v["max_trans_m_min_med_max"][0].as_f64().unwrap() > 0.5);
    assert!(
        err.contains("LOST: 2 of 2 runs lost the robot (largest error over 0.5 m against the reference topic; seeds 1, 2)"),
        "{err}"
    );
    // The help says so.
    let help = bin().args(["track", "--help"]).output().unwrap();
    assert!(String::from_utf8_lossy(&help.stdout)
        .contains("3 with --bag, the report is printed but at least one run was lost"));
    // Not lost: exit code 0 and no such line.
    let (code, _, err) = track(&data().join("intel-bag"), &["--scans", "20"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("LOST"), "{err}");
}

#[test]
fn scans_whose_angles_change_are_binned_onto_one_layout() {
    let mcap = mcap_run();
    let ld06 = data().join("intel-bag-ld06");
    // Binned back onto the original layout, every beam gets its original range
    // (make_db3.py), so the run is the MCAP bag's.
    let (code, v, err) = track(&ld06, &["--scan-layout", "-90,1,180"]);
    assert_eq!(code, 0, "{err}");
    assert_same_runs(&v, &mcap);
    assert_eq!(v["bag"]["rebinned"], 120);
    assert_eq!(v["bag"]["beams"], 180);
    assert_eq!(v["bag"]["angle_min_rad"], mcap["bag"]["angle_min_rad"]);
    assert_eq!(
        v["bag"]["angle_increment_rad"],
        mcap["bag"]["angle_increment_rad"]
    );
    // Without a layout: none is skipped, each is binned onto the layout covering them
    // (make_db3.py's steps are 0.69° to 0.90°: the largest sets it), and the robot is tracked.
    let (code, v, err) = track(&ld06, &[]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(v["bag"]["scans_used"], 120);
    assert_eq!(v["bag"]["rebinned"], 120);
    assert_eq!(v["bag"]["skipped"], serde_json::json!({}));
    let step = v["bag"]["angle_increment_rad"]
        .as_f64()
        .unwrap()
        .to_degrees();
    assert!((0.85..=0.91).contains(&step), "{step}");
    assert_eq!(v["lost_runs"], 0);
    let rmse = v["trans_rmse_cm_min_med_max"][2].as_f64().unwrap();
    assert!(rmse < 6.0, "{rmse} cm");
    // A layout that is not one is refused.
    let (code, _, err) = track(&ld06, &["--scan-layout", "0,2,200"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("spanning at most 360°"), "{err}");
}
