//! The beam layouts the CARMEN reader assumes (`carmen_beam_step_rad`), checked against the
//! data: with the right layout, the end points of all scans at their corrected poses fall into
//! fewer 5 cm cells (the walls are thinner) than with the other candidate. 180 beams (Intel):
//! 180 intervals of 1°, −90° … +89°; 181 (Acapulco) and 361 (Belgioioso): 180 and 360
//! intervals, −90° … +90°. (The Edmonton log, 180 beams, is the tracking figures' holdout and
//! is not used here.)

use beamfield_tools::input::carmen::{carmen_beam_step_rad, CarmenLog, ReadOptions};
use std::collections::HashSet;
use std::f64::consts::{FRAC_PI_2, PI};

/// Distinct 5 cm cells holding an end point of a return under 40 m (every log's no-return
/// values are above 50 m), beam `i` at `−π/2 + i·step`.
fn occupied_cells(log: &CarmenLog, step: f64) -> usize {
    let mut cells = HashSet::new();
    for s in &log.scans {
        let p = s.pose_f64;
        for (i, &z) in s.ranges_m.iter().enumerate() {
            if !(z > 0.0 && z < 40.0) {
                continue;
            }
            let a = p.theta_rad - FRAC_PI_2 + i as f64 * step;
            let (x, y) = (
                p.x_m + f64::from(z) * a.cos(),
                p.y_m + f64::from(z) * a.sin(),
            );
            cells.insert(((x / 0.05).floor() as i64, (y / 0.05).floor() as i64));
        }
    }
    cells.len()
}

fn check(path: &str, beams: usize, other_step: f64) {
    let path = host_tests::data_dir().join(path);
    let log = CarmenLog::read_path(
        &path,
        ReadOptions {
            max_range_m: Some(50.0),
            ..ReadOptions::default()
        },
    )
    .unwrap();
    assert_eq!(log.beams(), Some(beams));
    let step = carmen_beam_step_rad(beams);
    // The reader's end points use the same bearing.
    let s = &log.scans[0];
    let last = beams - 1;
    let a = s.pose_f64.theta_rad - FRAC_PI_2 + last as f64 * step;
    let z = f64::from(s.ranges_m[last]);
    let (x, y) = s.endpoint(last).unwrap();
    assert!((x - (s.pose_f64.x_m + z * a.cos())).abs() < 1e-9);
    assert!((y - (s.pose_f64.y_m + z * a.sin())).abs() < 1e-9);
    let (ours, other) = (occupied_cells(&log, step), occupied_cells(&log, other_step));
    assert!(
        ours < other,
        "{}: {ours} cells with {}° steps, {other} with {}°",
        path.display(),
        step.to_degrees(),
        other_step.to_degrees()
    );
}

#[test]
fn steps_of_the_logs() {
    assert!((carmen_beam_step_rad(180).to_degrees() - 1.0).abs() < 1e-12);
    assert!((carmen_beam_step_rad(181).to_degrees() - 1.0).abs() < 1e-12);
    assert!((carmen_beam_step_rad(361).to_degrees() - 0.5).abs() < 1e-12);
    assert!((carmen_beam_step_rad(360).to_degrees() - 0.5).abs() < 1e-12);
    assert!(carmen_beam_step_rad(0).is_finite() && carmen_beam_step_rad(1).is_finite());
}

#[test]
fn intel_180_beams_span_180_intervals() {
    check("laser_intel_lab/intel-corrected.log", 180, PI / 179.0);
}

#[test]
fn acapulco_181_beams_span_180_intervals() {
    check("laser_acapulco/acapulco-corrected.log", 181, PI / 181.0);
}

#[test]
fn belgioioso_361_beams_span_360_intervals() {
    check("laser_belgioioso/belgioioso-corrected.log", 361, PI / 361.0);
}
