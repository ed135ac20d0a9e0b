//! `beamfield track --wheel-odometry` and `--synthetic-odom-noise`: odometry that is not the
//! filter's own model (the wheel model of `beamfield_tools::track::wheels`), on the Intel log
//! and the checked-in Intel field.

mod common;

use beamfield::Pose;
use beamfield_tools::input::carmen::{CarmenLog, ReadOptions};
use beamfield_tools::track::{synthesize_odometry, WheelPreset};
use common::{bin, run_json};
use std::path::PathBuf;

fn log() -> PathBuf {
    host_tests::data_dir().join("laser_intel_lab/intel-corrected.log")
}

fn field() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../firmware/assets/intel.bin")
}

fn logged() -> Vec<Pose> {
    let log = CarmenLog::read_path(&log(), ReadOptions::default()).unwrap();
    log.scans.iter().map(|s| s.pose).collect()
}

/// Largest distance between corresponding poses, metres.
fn largest_gap(a: &[Pose], b: &[Pose]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(p, q)| (p.x_m - q.x_m).hypot(p.y_m - q.y_m))
        .fold(0.0, f32::max)
}

#[test]
fn wheel_odometry_is_seeded_and_not_the_synthetic_one() {
    let logged = logged();
    let mild = WheelPreset::Mild.odometry(&logged, 1);
    assert_eq!(mild.len(), logged.len());
    assert_eq!(mild[0], logged[0], "starts at the first logged pose");
    // Deterministic per seed, different across seeds and presets.
    assert_eq!(mild, WheelPreset::Mild.odometry(&logged, 1));
    assert!(largest_gap(&mild, &WheelPreset::Mild.odometry(&logged, 2)) > 0.1);
    let strong = WheelPreset::Strong.odometry(&logged, 1);
    assert!(largest_gap(&mild, &strong) > 0.1);
    // The wrong radii and wheelbase make it drift off the logged path by metres over ~500 m …
    assert!(largest_gap(&mild, &logged) > 1.0);
    // … and it is not the synthesized odometry of the same seed.
    let noise = beamfield::mcl::OdometryNoise::uniform(0.005).unwrap();
    let synthetic = synthesize_odometry(&noise, &logged, 1).unwrap();
    assert!(largest_gap(&mild, &synthetic) > 1.0);
    // The host tests' model is this one (a re-export), draw for draw.
    let host = host_tests::wheel_odometry::wheel_odometry(
        &logged,
        &host_tests::wheel_odometry::WheelErrors::MILD,
        1 ^ beamfield_tools::track::WHEEL_SEED_XOR,
    );
    assert_eq!(host, mild);
}

fn track(extra: &[&str]) -> serde_json::Value {
    let (f, l) = (field(), log());
    let mut args = vec![
        "--json",
        "track",
        "--field",
        f.to_str().unwrap(),
        "--log",
        l.to_str().unwrap(),
        "--scans",
        "150",
        "--seeds",
        "2",
    ];
    args.extend_from_slice(extra);
    run_json(bin().args(&args))
}

#[test]
fn a_run_on_wheel_odometry_names_it_and_tracks() {
    let wheels = track(&["--wheel-odometry", "mild"]);
    assert_eq!(wheels["odometry_model"], "wheels-mild");
    let text = wheels["odometry"].as_str().unwrap();
    assert!(text.contains("wheel model mild"), "{text}");
    assert!(text.contains("+1.5 %"), "names the wheelbase error: {text}");
    let rmse: Vec<f64> = wheels["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["metrics"]["trans_rmse_m"].as_f64().unwrap())
        .collect();
    assert_eq!(rmse.len(), 2);
    for r in &rmse {
        // Tracked: finite, and well under the 0.5 m that counts as lost.
        assert!(r.is_finite() && *r < 0.25, "RMSE {r} m");
    }
    // The same seeds give the same runs; the synthetic odometry gives other runs.
    assert_eq!(track(&["--wheel-odometry", "mild"])["runs"], wheels["runs"]);
    let synthetic = track(&[]);
    assert_eq!(synthetic["odometry_model"], "synthetic");
    assert_ne!(synthetic["runs"], wheels["runs"]);
    assert_ne!(
        track(&["--wheel-odometry", "strong"])["runs"],
        wheels["runs"]
    );
}

#[test]
fn synthetic_odometry_noise_can_differ_from_the_filters() {
    // Equal to --odom-noise: the default run exactly.
    let default = track(&["--odom-noise", "0.005"]);
    let same = track(&["--odom-noise", "0.005", "--synthetic-odom-noise", "0.005"]);
    assert_eq!(default["runs"], same["runs"]);
    // Noisier odometry than the filter assumes: other runs, still called synthetic.
    let noisier = track(&["--odom-noise", "0.005", "--synthetic-odom-noise", "0.02"]);
    assert_eq!(noisier["odometry_model"], "synthetic");
    assert_ne!(noisier["runs"], default["runs"]);
}

#[test]
fn wheel_odometry_conflicts_with_recorded_odometry() {
    let (f, l) = (field(), log());
    let (f, l) = (f.to_str().unwrap(), l.to_str().unwrap());
    for extra in [
        &["--odometry", "odom.txt"][..],
        &["--synthetic-odom-noise", "0.02"][..],
    ] {
        let mut args = vec![
            "track",
            "--field",
            f,
            "--log",
            l,
            "--wheel-odometry",
            "mild",
        ];
        args.extend_from_slice(extra);
        let out = bin().args(&args).output().unwrap();
        assert!(!out.status.success(), "{args:?} succeeded");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("cannot be used with"), "{err}");
    }
    let out = bin()
        .args([
            "track",
            "--field",
            f,
            "--log",
            l,
            "--wheel-odometry",
            "wobbly",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let help = bin().args(["track", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    for word in [
        "--wheel-odometry",
        "mild",
        "strong",
        "typical",
        "wheelbase +1.5 %",
    ] {
        assert!(help.contains(word), "help lacks {word}");
    }
}
