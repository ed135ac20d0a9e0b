//! The CARMEN reader on the real Intel lab log, checked against the figures of
//! `data/laser_intel_lab/README.md` (counted independently of this code).

use beamfield::Reading;
use beamfield_tools::input::carmen::{CarmenLog, MaxRange, ReadOptions};

fn intel() -> CarmenLog {
    let path = host_tests::data_dir().join("laser_intel_lab/intel-corrected.log");
    CarmenLog::read_path(&path, ReadOptions::default()).unwrap()
}

#[test]
fn counts_match_the_readme() {
    let log = intel();
    assert_eq!(log.scans.len(), 910);
    assert!(log.scans.iter().all(|s| s.ranges_m.len() == 180));
    assert_eq!(log.beams(), Some(180));
    assert_eq!(log.comments, 2);
    assert_eq!(log.params.len(), 2);
    assert_eq!(log.frontlaser_offset_m, Some(0.0));
    assert_eq!(log.skipped.get("ODOM"), Some(&14_541));
    assert_eq!(log.skipped.get("NEFF"), Some(&910));
    assert_eq!(log.skipped.len(), 2, "{:?}", log.skipped);
    assert!(log.bad_lines.is_empty());
    // 16,365 lines in all: every one accounted for.
    let accounted = log.scans.len()
        + log.params.len()
        + log.comments
        + log.blank_lines
        + log.skipped.values().sum::<usize>();
    assert_eq!(accounted, 16_365);
}

#[test]
fn max_range_is_detected_as_81_83() {
    let log = intel();
    let MaxRange::Detected(d) = log.max_range else {
        panic!("not detected: {:?}", log.max_range);
    };
    assert_eq!(d.value_m, 81.83);
    assert_eq!(d.count, 4_172);
    let stats = log.stats();
    assert_eq!(stats.readings, 910 * 180);
    assert_eq!(stats.max_range_readings, 4_172);
    let share = stats.max_range_readings as f64 / stats.readings as f64;
    assert!((share - 0.0255).abs() < 0.0005, "{share}");
    assert_eq!(stats.above_max_range_readings, 0);
    assert_eq!(stats.invalid_readings, 0);
    assert_eq!(stats.min_range_m, 0.23);
    assert_eq!(stats.max_valid_range_m, 25.38);
    // The layout classifies exactly those readings as max range.
    let layout = log.layout::<180>().unwrap();
    assert_eq!(layout.max_range_m(), 81.83);
    let max_readings = log
        .scans
        .iter()
        .flat_map(|s| s.ranges_m.iter())
        .filter(|&&z| Reading::classify(z, layout.max_range_m()) == Reading::MaxRange)
        .count();
    assert_eq!(max_readings, 4_172);
}

#[test]
fn a_given_max_range_overrides_detection() {
    let path = host_tests::data_dir().join("laser_intel_lab/intel-corrected.log");
    let log = CarmenLog::read_path(
        &path,
        ReadOptions {
            max_range_m: Some(30.0),
            skip_bad_lines: false,
        },
    )
    .unwrap();
    assert_eq!(log.max_range, MaxRange::Given(30.0));
    assert_eq!(log.stats().above_max_range_readings, 4_172);
}

#[test]
fn poses_and_timestamps_match_the_readme() {
    let log = intel();
    let stats = log.stats();
    let b = stats.pose_extent.unwrap();
    // README: x ∈ [−9.23, 16.55], y ∈ [−22.13, 3.90], θ ∈ [−3.136, 3.247] (rounded there).
    for (got, want, tol) in [
        (b.x_min, -9.23, 0.005),
        (b.x_max, 16.55, 0.005),
        (b.y_min, -22.13, 0.005),
        (b.y_max, 3.90, 0.005),
        (f64::from(stats.theta_min_rad), -3.136, 0.0005),
        (f64::from(stats.theta_max_rad), 3.247, 0.0005),
    ] {
        assert!((got - want).abs() <= tol, "{got} vs {want}");
    }
    // Corrected pose in both fields.
    assert!(log.scans.iter().all(|s| s.pose == s.odom_pose));
    // First pose near (0.60, −0.03); first timestamp 32.9 s.
    let first = &log.scans[0];
    assert!((first.pose.x_m - 0.60).abs() < 0.01 && (first.pose.y_m + 0.03).abs() < 0.01);
    assert!(
        (first.timestamp_s - 32.9).abs() < 0.05,
        "{}",
        first.timestamp_s
    );
    // Non-monotone timestamps are tolerated and counted: 4 steps back, among them the scans
    // near lines 5647 and 12936.
    assert_eq!(stats.timestamp_steps_back, 4);
    let back_lines: Vec<usize> = log
        .scans
        .windows(2)
        .filter(|w| w[1].timestamp_s < w[0].timestamp_s)
        .map(|w| w[1].line)
        .collect();
    for readme_line in [5647, 12936] {
        assert!(
            back_lines.iter().any(|&l| l.abs_diff(readme_line) <= 20),
            "{back_lines:?} has nothing near {readme_line}"
        );
    }
}

#[test]
fn scans_convert_to_crate_types() {
    let log = intel();
    let layout = log.layout::<180>().unwrap();
    assert_eq!(layout.len(), 180);
    let deg = std::f32::consts::PI / 180.0;
    for (i, beam) in layout.beams().iter().enumerate() {
        let want = -90.0 * deg + i as f32 * deg;
        assert!((beam.bearing_rad - want).abs() < 1e-6, "beam {i}");
    }
    // Too small a capacity is an error, not a truncation.
    assert!(log.layout::<179>().is_err());
    let scan = log.scans[17].to_scan::<180>().unwrap();
    assert_eq!(scan.ranges_m(), log.scans[17].ranges_m.as_slice());
}
