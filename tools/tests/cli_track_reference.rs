//! `beamfield track` on a log whose poses are the robot's odometry
//! (`data/laser_intel_lab_raw_odometry/`: the Intel lab's raw wheel odometry) with reference
//! poses at some scans (`anchors.tsv`): the run starts at the first anchor, is scored at the
//! anchors only, and reports every update in `--json`.

mod common;

use common::{bin, run_json};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn data() -> PathBuf {
    repo().join("data/laser_intel_lab_raw_odometry")
}

fn field() -> PathBuf {
    repo().join("firmware/assets/intel.bin")
}

/// The anchors as the file has them, read here independently: (scan, x, y, θ).
fn anchors() -> Vec<(usize, f64, f64, f64)> {
    let text = std::fs::read_to_string(data().join("anchors.tsv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split('\t').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (i, x, y, t) = (col("index"), col("ref_x"), col("ref_y"), col("ref_theta"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            (
                f[i].parse().unwrap(),
                f[x].parse().unwrap(),
                f[y].parse().unwrap(),
                f[t].parse().unwrap(),
            )
        })
        .collect()
}

fn args(scans: &str) -> Vec<String> {
    [
        "--json",
        "track",
        "--field",
        field().to_str().unwrap(),
        "--log",
        data().join("intel-real-odom.clf").to_str().unwrap(),
        "--log-poses",
        "odometry",
        "--reference",
        data().join("anchors.tsv").to_str().unwrap(),
        "--scans",
        scans,
        "--seeds",
        "2",
    ]
    .map(String::from)
    .to_vec()
}

#[test]
fn real_odometry_is_scored_at_the_anchors_only() {
    const SCANS: usize = 160;
    let v = run_json(bin().args(args(&SCANS.to_string())));
    let want: Vec<_> = anchors().into_iter().filter(|a| a.0 < SCANS).collect();
    assert!(want.len() >= 5, "{} anchors in the slice", want.len());
    assert_eq!(v["scored"], "reference");
    assert_eq!(v["odometry_model"], "recorded");
    for run in v["runs"].as_array().unwrap() {
        assert_eq!(run["metrics"]["scored_scans"], want.len());
        let per = run["per_scan"].as_array().unwrap();
        // From the first anchor to the last scan asked for, one record per update.
        assert_eq!(per.len(), SCANS - want[0].0);
        assert_eq!(per[0]["scan"], want[0].0);
        let mut next = want.iter().peekable();
        let mut sq = 0.0;
        for rec in per {
            let k = rec["scan"].as_u64().unwrap() as usize;
            assert!(["tracking", "uncertain", "lost"].contains(&rec["quality"].as_str().unwrap()));
            match next.peek() {
                Some(&&(a, x, y, t)) if a == k => {
                    next.next();
                    // The error is against the anchor's pose, not the log's (odometry) pose.
                    let p = rec["pose"].as_array().unwrap();
                    let (px, py, pt) = (
                        p[0].as_f64().unwrap(),
                        p[1].as_f64().unwrap(),
                        p[2].as_f64().unwrap(),
                    );
                    let e = (px - x).hypot(py - y);
                    let got = rec["error_m"].as_f64().unwrap();
                    assert!((got - e).abs() < 1e-4, "scan {k}: {got} vs {e}");
                    let dh = (pt - t + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                        - std::f64::consts::PI;
                    let head = rec["heading_error_deg"].as_f64().unwrap();
                    assert!((head - dh.abs().to_degrees()).abs() < 1e-2, "scan {k}");
                    sq += e * e;
                }
                _ => {
                    assert!(rec["error_m"].is_null(), "scan {k} has no anchor");
                    assert!(rec["heading_error_deg"].is_null());
                }
            }
        }
        assert!(next.next().is_none(), "every anchor scored");
        let rmse = (sq / want.len() as f64).sqrt();
        let reported = run["metrics"]["trans_rmse_m"].as_f64().unwrap();
        assert!((rmse - reported).abs() < 1e-6, "{rmse} vs {reported}");
        // The quality table covers the scored scans.
        let q = &run["metrics"]["quality"];
        let total: u64 = [
            "tracking_within",
            "tracking_off",
            "uncertain_within",
            "uncertain_off",
            "lost_within",
            "lost_off",
        ]
        .iter()
        .map(|k| q[k].as_u64().unwrap())
        .sum();
        assert_eq!(total as usize, want.len());
        // Real odometry drifts by about 12 % of the distance; the filter keeps the robot.
        assert!(reported < 0.3, "RMSE {reported} m at the anchors");
    }
}

#[test]
fn odometry_poses_need_a_reference_and_no_other_odometry() {
    // Without --reference (the flag and its value dropped).
    let mut a = args("100");
    a.drain(8..10);
    let out = bin().args(&a).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("give --reference"), "{err}");
    let mut a = args("100");
    a.extend(["--wheel-odometry".into(), "mild".into()]);
    let out = bin().args(&a).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("need a log of true poses"), "{err}");
}

#[test]
fn reference_file_errors_name_the_line() {
    let dir = std::env::temp_dir().join(format!("bf-reference-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("ref.tsv");
    let run = |text: &str| {
        std::fs::write(&bad, text).unwrap();
        let mut a = args("100");
        a[9] = bad.display().to_string();
        let out = bin().args(&a).output().unwrap();
        assert!(!out.status.success(), "{text:?} accepted");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    assert!(run("40 1 2 3\n40 1 2 3\n").contains("line 2: scan 40 has a pose already"));
    assert!(run("index a b c\n").contains("line 1: a header needs the columns"));
    assert!(run("# nothing\n").contains("no reference pose in it"));
    assert!(run("99999 1 2 3\n").contains("line 1: scan 99999 is past the log's 2726 scans"));
    assert!(run("40 1 inf 3\n").contains("line 1: x, y and θ must be finite"));
    // Only anchors past the scans run: nothing to start from.
    assert!(run("500 1 2 3\n").contains("no reference pose within the 100 scans run"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--update-min D,A` (AMCL's update gate): with a gate no step of the slice reaches, the filter
/// weighs the first scan only and every later estimate is that one carried by the odometry, so
/// the particles' weights (their ESS) never change and the pose follows the odometry; without
/// it, every scan is weighed. Malformed gates are usage errors.
#[test]
fn the_update_gate_carries_the_estimate_between_updates() {
    const SCANS: usize = 120;
    let mut gated = args(&SCANS.to_string());
    gated.extend(["--update-min", "1000,1000"].map(String::from));
    let v = run_json(bin().args(&gated));
    assert_eq!(v["update_min"][0], 1000.0);
    let every = run_json(bin().args(args(&SCANS.to_string())));
    let first = anchors()[0].0;
    for (run, all) in v["runs"]
        .as_array()
        .unwrap()
        .iter()
        .zip(every["runs"].as_array().unwrap())
    {
        let per = run["per_scan"].as_array().unwrap();
        assert_eq!(per.len(), SCANS - first);
        // One weighing (the first scan), so at most one resampling; every scan without the gate.
        assert!(
            run["resamplings"].as_u64().unwrap() <= 1,
            "{}",
            run["resamplings"]
        );
        assert!(
            all["resamplings"].as_u64().unwrap() > 10,
            "{}",
            all["resamplings"]
        );
        let ess0 = per[0]["ess"].as_f64().unwrap();
        let (mut moved, mut prev) = (0.0f64, per[0]["pose"].clone());
        for rec in &per[1..] {
            assert_eq!(rec["ess"].as_f64().unwrap(), ess0, "scan {}", rec["scan"]);
            let d = |i: usize| rec["pose"][i].as_f64().unwrap() - prev[i].as_f64().unwrap();
            moved += d(0).hypot(d(1));
            prev = rec["pose"].clone();
        }
        // The robot drives through the slice: the carried estimate moves with it.
        assert!(moved > 1.0, "carried {moved} m");
    }
    for bad in ["nan,0", "-1,0", "0.25", "0.25,inf"] {
        let mut a = args("50");
        a.extend(["--update-min".to_string(), bad.to_string()]);
        let out = bin().args(&a).output().unwrap();
        assert!(!out.status.success(), "--update-min {bad}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--update-min"), "{bad}: {err}");
    }
}

/// The defaults (κ 64, the default quality thresholds) on the whole real-odometry log at nav2's
/// odometry noise α 0.2, with the recovery on: the robot is never lost (largest error at an
/// anchor under 0.35 m, the robustness target), no update reports `Lost` (nothing is wrong:
/// the clutter near the laser at scans 415 and 834 is not a loss) and no free-space reset fires.
#[test]
fn the_defaults_keep_the_robot_on_real_odometry_at_nav2s_noise() {
    // The field with its free space, as `field build --free-space` writes it.
    let dir = std::env::temp_dir().join(format!("beamfield-real-odometry-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let with_free = dir.join("intel-fs.bin");
    let mut blob = std::fs::read(field()).unwrap();
    blob.extend(std::fs::read(repo().join("firmware/assets/intel-free-space.bin")).unwrap());
    std::fs::write(&with_free, blob).unwrap();
    let mut a = args("0");
    let scans = a.iter().position(|s| s == "--scans").unwrap();
    a.drain(scans..scans + 2);
    let f = a.iter().position(|s| s == "--field").unwrap();
    a[f + 1] = with_free.to_str().unwrap().to_string();
    a.extend(["--odom-noise", "0.2", "--resetting"].map(String::from));
    let v = run_json(bin().args(&a));
    std::fs::remove_dir_all(&dir).unwrap();
    let runs = v["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2);
    for run in runs {
        let m = &run["metrics"];
        let max = m["max_trans_m"].as_f64().unwrap();
        println!(
            "seed {}: RMSE {:.4} m, largest {max:.3} m, resets {}",
            run["seed"],
            m["trans_rmse_m"].as_f64().unwrap(),
            run["resets"]
        );
        assert_eq!(m["scored_scans"], anchors().len());
        assert!(max < 0.35, "seed {}: largest error {max} m", run["seed"]);
        let lost: Vec<u64> = run["per_scan"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|r| r["quality"] == "lost")
            .map(|r| r["scan"].as_u64().unwrap())
            .collect();
        assert!(lost.is_empty(), "seed {}: Lost at {lost:?}", run["seed"]);
        assert_eq!(run["resets"], 0, "seed {}", run["seed"]);
    }
}
