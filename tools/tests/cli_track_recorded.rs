//! `beamfield track` on recordings: a ROS 2 bag written by PyPI rosbags
//! (`tools/tests/data/intel-bag`, made by `tools/scripts/carmen_to_bag.py` from the Intel log's
//! first 120 scans; its /odom has a 2 % distance scale error and a heading drift), its typed
//! refusals, and an `--odometry` file for a log.

mod common;

use common::{bin, run_json};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn bag() -> PathBuf {
    repo().join("tools/tests/data/intel-bag")
}

fn field() -> PathBuf {
    repo().join("firmware/assets/intel.bin")
}

#[test]
fn a_bag_is_tracked_with_its_own_odometry() {
    let v = run_json(bin().args([
        "--json",
        "track",
        "--field",
        field().to_str().unwrap(),
        "--bag",
        bag().to_str().unwrap(),
        "--reference-topic",
        "/ground_truth",
        "--seeds",
        "3",
    ]));
    assert_eq!(v["bag"]["scans_used"], 120);
    assert_eq!(v["bag"]["beams"], 180);
    assert_eq!(v["bag"]["mount_from_tf"], true);
    assert_eq!(v["odometry"], "recorded (/odom)");
    assert_eq!(v["lost_runs"], 0);
    // The odometry drifts by 2 % of the distance and 0.5° per metre; tracked against the
    // logged poses, the estimate stays within centimetres.
    let rmse = v["trans_rmse_cm_min_med_max"][1].as_f64().unwrap();
    assert!(rmse < 6.0, "median RMSE {rmse} cm");
    assert!(v["max_trans_m_min_med_max"][2].as_f64().unwrap() < 0.2);
}

fn fails_with(args: &[&str], want: &str) {
    let out = bin().args(args).output().unwrap();
    assert!(!out.status.success(), "{args:?} succeeded");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(want), "{args:?}: {err}");
}

#[test]
fn bag_refusals_name_what_is_there() {
    let (f, b) = (field(), bag());
    let (f, b) = (f.to_str().unwrap(), b.to_str().unwrap());
    fails_with(
        &["track", "--field", f, "--bag", b, "--reference-topic", "/ground_truth", "--scan-topic", "/laser"],
        "the bag has no topic /laser; it has /ground_truth (geometry_msgs/msg/PoseWithCovarianceStamped), /odom (nav_msgs/msg/Odometry), /scan (sensor_msgs/msg/LaserScan)",
    );
    fails_with(
        &[
            "track",
            "--field",
            f,
            "--bag",
            b,
            "--reference-topic",
            "/ground_truth",
            "--scan-topic",
            "/odom",
        ],
        "topic /odom is nav_msgs/msg/Odometry, not sensor_msgs/msg/LaserScan",
    );
    fails_with(
        &["track", "--field", f, "--bag", b],
        "needs --reference-topic",
    );
    fails_with(
        &[
            "track",
            "--field",
            f,
            "--bag",
            "/nonexistent.mcap",
            "--reference-topic",
            "/x",
        ],
        "cannot read /nonexistent.mcap",
    );
    let dir = std::env::temp_dir().join(format!("bf-bag-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let junk = dir.join("junk.mcap");
    std::fs::write(&junk, b"not an mcap file at all").unwrap();
    fails_with(
        &[
            "track",
            "--field",
            f,
            "--bag",
            junk.to_str().unwrap(),
            "--reference-topic",
            "/x",
        ],
        "is not a readable MCAP file",
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn odometry_file_for_a_log() {
    let dir = std::env::temp_dir().join(format!("bf-odom-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = repo().join("data/laser_intel_lab/intel-corrected.log");
    // The log's own poses (its odometry fields repeat them) for the first 30 scans.
    let text = std::fs::read_to_string(&log).unwrap();
    let mut lines = vec!["# index x y theta".to_string()];
    for (k, l) in text
        .lines()
        .filter(|l| l.starts_with("FLASER"))
        .take(30)
        .enumerate()
    {
        let f: Vec<&str> = l.split_whitespace().collect();
        let n: usize = f[1].parse().unwrap();
        lines.push(format!("{k} {} {} {}", f[2 + n], f[3 + n], f[4 + n]));
    }
    let good = dir.join("odom.txt");
    std::fs::write(&good, lines.join("\n")).unwrap();
    let (f, l) = (field(), log);
    let args = |o: &Path, scans: &str| {
        vec![
            "--json".to_string(),
            "track".into(),
            "--field".into(),
            f.display().to_string(),
            "--log".into(),
            l.display().to_string(),
            "--scans".into(),
            scans.into(),
            "--odometry".into(),
            o.display().to_string(),
        ]
    };
    // The log's poses as odometry: tracked, and the report says where the odometry came from.
    let v = run_json(bin().args(args(&good, "30")));
    assert!(v["odometry"].as_str().unwrap().starts_with("recorded ("));
    assert_eq!(v["lost_runs"], 0);
    // 30 poses for 31 scans: the first missing one is named.
    let out = bin().args(args(&good, "31")).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no pose for scan 30"));
    let bad = dir.join("bad.txt");
    std::fs::write(&bad, "0 1 2 3\n0 1 2 3\n").unwrap();
    let out = bin().args(args(&bad, "30")).output().unwrap();
    assert!(String::from_utf8_lossy(&out.stderr).contains("line 2: scan 0 has a pose already"));
    std::fs::write(&bad, "0 1 nan 3\n").unwrap();
    let out = bin().args(args(&bad, "30")).output().unwrap();
    assert!(String::from_utf8_lossy(&out.stderr).contains("line 1: x, y and θ must be finite"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_nav2_map_yaml_is_a_field() {
    // The Intel map as map_server YAML + PGM, made from the log as firmware/assets/intel.bin
    // was; the run on it equals the run on the blob.
    let dir = std::env::temp_dir().join(format!("bf-yaml-field-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let yaml = dir.join("intel.yaml");
    let log = repo().join("data/laser_intel_lab/intel-corrected.log");
    let out = bin()
        .args(["map", "from-log"])
        .arg(&log)
        .arg("-o")
        .arg(&yaml)
        .args(["--resolution", "0.05"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let run = |field: &Path| {
        run_json(bin().args([
            "--json",
            "track",
            "--field",
            field.to_str().unwrap(),
            "--bag",
            bag().to_str().unwrap(),
            "--reference-topic",
            "/ground_truth",
        ]))
    };
    let (from_yaml, from_blob) = (run(&yaml), run(&field()));
    assert_eq!(from_yaml["runs"], from_blob["runs"]);
    // A YAML that is not a map is refused with its name.
    let bad = dir.join("bad.yaml");
    std::fs::write(&bad, "image: nowhere.pgm\n").unwrap();
    fails_with(
        &[
            "track",
            "--field",
            bad.to_str().unwrap(),
            "--bag",
            bag().to_str().unwrap(),
            "--reference-topic",
            "/ground_truth",
        ],
        "--field",
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
