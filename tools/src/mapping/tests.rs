//! Tests of the map builder: log-odds updates, beam segments, the extent and limits.

use super::*;
use crate::input::carmen::MaxRange;
use beamfield::Pose;

const NO_RETURN: f32 = 40.0;

fn log_of(scans: &[(Pose, Vec<f32>)]) -> CarmenLog {
    CarmenLog {
        scans: scans
            .iter()
            .enumerate()
            .map(|(k, (pose, ranges))| LaserScan {
                ranges_m: ranges.clone(),
                pose: *pose,
                odom_pose: *pose,
                pose_f64: (*pose).into(),
                timestamp_s: k as f64,
                logger_timestamp_s: k as f64,
                line: k + 1,
            })
            .collect(),
        max_range: MaxRange::Given(NO_RETURN),
        ..CarmenLog::default()
    }
}

fn build(log: &CarmenLog, free_cap: Option<f64>) -> (OccupancyGrid, MappingStats) {
    let mut o = MappingOptions::new(NO_RETURN);
    o.resolution_m = 0.1;
    o.max_range_free_m = free_cap;
    let (g, stats) = build_from_log(log, &o, |_, _| {}).unwrap();
    (g.to_occupancy(OCCUPIED_THRESH, FREE_THRESH), stats)
}

fn at(grid: &OccupancyGrid, x: f64, y: f64) -> Cell {
    let (c, r) = grid.geometry().cell_of(x, y).unwrap();
    grid.get(c, r).unwrap()
}

#[test]
fn max_range_readings_clear_up_to_the_cap_only() {
    // Five identical scans of 180 no-return beams from (0.05, 0.05) facing +x, cap 1 m:
    // a crossed cell gets 5 misses (once per scan) → −2.0 (clamped), p ≈ 0.12 < 0.196: free.
    let pose = Pose::new(0.05, 0.05, 0.0);
    let scans = vec![(pose, vec![NO_RETURN; 180]); 5];
    let (grid, stats) = build(&log_of(&scans), Some(1.0));
    assert_eq!(stats.max_range, 900);
    assert_eq!(stats.hits, 0);
    assert_eq!(
        grid.counts().0,
        0,
        "no occupied cell from max-range readings"
    );
    assert_eq!(at(&grid, 0.55, 0.05), Cell::Free); // ahead, within the cap
    assert_eq!(at(&grid, 0.05, -0.55), Cell::Free); // the −90° beam
    assert_eq!(at(&grid, 1.45, 0.05), Cell::Unknown); // beyond the cap
    assert_eq!(at(&grid, -0.55, 0.05), Cell::Unknown); // behind the sensor
                                                       // With no free-space claim for max-range readings: nothing at all.
    let (grid, _) = build(&log_of(&scans), None);
    assert_eq!(grid.counts().0 + grid.counts().1, 0);
}

#[test]
fn hits_are_occupied_and_the_ray_before_them_free() {
    // n = 6: bearings −90°, −60°, −30°, 0°, +30°, +60°. A wall at x = 2.05 m: the ±30° beams
    // read 2.0/cos 30° from (0.05, 0.05); the other beams have no return.
    let z = (2.0 / 30f64.to_radians().cos()) as f32;
    let pose = Pose::new(0.05, 0.05, 0.0);
    let scans = vec![(pose, vec![NO_RETURN, NO_RETURN, z, NO_RETURN, z, NO_RETURN]); 5];
    let (grid, stats) = build(&log_of(&scans), None);
    assert_eq!((stats.hits, stats.max_range), (10, 20));
    let dy = 2.0 * 30f64.to_radians().tan();
    assert_eq!(at(&grid, 2.05, 0.05 + dy), Cell::Occupied);
    assert_eq!(at(&grid, 2.05, 0.05 - dy), Cell::Occupied);
    assert_eq!(at(&grid, 1.05, 0.05 + dy / 2.0), Cell::Free);
    assert_eq!(at(&grid, 1.05, 0.05 - dy / 2.0), Cell::Free);
    assert_eq!(grid.counts().0, 2);
}

#[test]
fn a_hit_wins_over_a_pass_through_of_the_same_scan() {
    // 180 beams from (0.05, 0.05): beam 90 (0°) reads 3 m and runs along row 0; beam 91 (1°)
    // reads 1 m and ends at (1.0498, 0.0675), in cell (10, 0), which beam 90 crosses.
    // One scan: that cell gets the hit (+0.847, p = 0.7 > 0.65) and not the miss
    // (which would leave +0.44, p = 0.61: unknown).
    let mut ranges = vec![NO_RETURN; 180];
    ranges[90] = 3.0;
    ranges[91] = 1.0;
    let (grid, _) = build(&log_of(&[(Pose::new(0.05, 0.05, 0.0), ranges)]), None);
    let end = (
        0.05 + 1f64.to_radians().cos(),
        0.05 + 1f64.to_radians().sin(),
    );
    assert_eq!(
        grid.geometry().cell_of(end.0, end.1),
        grid.geometry().cell_of(1.05, 0.05)
    );
    assert_eq!(at(&grid, end.0, end.1), Cell::Occupied);
}

#[test]
fn bad_options_and_empty_logs_are_errors() {
    let log = log_of(&[(Pose::default(), vec![1.0])]);
    let mut o = MappingOptions::new(NO_RETURN);
    o.resolution_m = 0.0;
    assert_eq!(
        build_from_log(&log, &o, |_, _| {}).err(),
        Some(MappingError::BadOptions)
    );
    let o = MappingOptions::new(NO_RETURN);
    assert_eq!(
        build_from_log(&CarmenLog::default(), &o, |_, _| {}).err(),
        Some(MappingError::NoData)
    );
    let mut o = MappingOptions::new(NO_RETURN);
    o.resolution_m = 1e-6;
    assert!(matches!(
        build_from_log(&log, &o, |_, _| {}).err(),
        Some(MappingError::TooLarge { .. })
    ));
}
