//! Tests of the CARMEN log reader: FLASER parsing, the max-range value, malformed lines.

use super::*;
use beamfield::Pose;

fn flaser(ranges: &[&str], trailer: &str) -> String {
    format!("FLASER {} {} {trailer}", ranges.len(), ranges.join(" "))
}

const TRAILER: &str = "1.0 2.0 0.5 1.0 2.0 0.5 10.25 host 10.3";

fn read(text: &str) -> Result<CarmenLog, LogError> {
    CarmenLog::read(text.as_bytes(), ReadOptions::default())
}

fn line_error(text: &str) -> LineError {
    match read(text) {
        Err(LogError::Line(e)) => e,
        other => panic!("expected a line error, got {other:?}"),
    }
}

#[test]
fn parses_a_small_log() {
    let text = format!(
        "# comment\nPARAM robot_frontlaser_offset 0.25 nohost 0\nODOM 0 0 0 0 0 0 1 h 1\n\n{}\nNEFF 3\n{}\n",
        flaser(&["1.5", "2.5", "9.0"], TRAILER),
        flaser(&["9.0", "0.5", "9.0"], "3 4 -1 5 6 7 9.0 host 9.5"),
    );
    let log = read(&text).unwrap();
    assert_eq!(log.scans.len(), 2);
    assert_eq!(log.comments, 1);
    assert_eq!(log.blank_lines, 1);
    assert_eq!(log.skipped.get("ODOM"), Some(&1));
    assert_eq!(log.skipped.get("NEFF"), Some(&1));
    assert_eq!(log.frontlaser_offset_m, Some(0.25));
    let s = &log.scans[1];
    assert_eq!(s.ranges_m, vec![9.0, 0.5, 9.0]);
    assert_eq!(s.pose, Pose::new(3.0, 4.0, -1.0));
    assert_eq!(s.odom_pose, Pose::new(5.0, 6.0, 7.0));
    assert_eq!(s.timestamp_s, 9.0);
    assert_eq!(s.logger_timestamp_s, 9.5);
    assert_eq!(s.line, 7);
    // 9.0 occurs 3 times, nothing else in [4.5, ∞): detected.
    assert_eq!(log.max_range.value_m(), Some(9.0));
    let layout = log.layout::<4>().unwrap();
    assert_eq!(layout.len(), 3);
    assert!((layout.beams()[0].bearing_rad + core::f32::consts::FRAC_PI_2).abs() < 1e-7);
    // An odd beam count spans 180° in n − 1 intervals: −90°, 0°, +90°.
    assert!(layout.beams()[1].bearing_rad.abs() < 1e-6);
    assert!((layout.beams()[2].bearing_rad - core::f32::consts::FRAC_PI_2).abs() < 1e-6);
    assert_eq!(log.robot_mount().x_m, 0.25);
    assert!(s.to_scan::<2>().is_err());
    assert_eq!(s.to_scan::<3>().unwrap().ranges_m(), &[9.0, 0.5, 9.0]);
}

#[test]
fn malformed_lines_carry_their_number_and_cause() {
    let good = flaser(&["1", "2"], TRAILER);
    // Too few trailer tokens.
    let e = line_error(&format!("{good}\nFLASER 2 1 2 1 2 3 4 5 6 7 host"));
    assert_eq!(e.line, 2);
    assert_eq!(
        e.kind,
        LineErrorKind::WrongTokenCount {
            beams: 2,
            expected: 11,
            found: 10
        }
    );
    // n that does not match the number of ranges.
    let e = line_error(&format!("FLASER 3 1 2 {TRAILER}"));
    assert_eq!(
        e.kind,
        LineErrorKind::WrongTokenCount {
            beams: 3,
            expected: 12,
            found: 11
        }
    );
    // n that differs from the first scan's.
    let e = line_error(&format!("{good}\n{}", flaser(&["1", "2", "3"], TRAILER)));
    assert_eq!(
        e.kind,
        LineErrorKind::BeamCountMismatch { first: 2, found: 3 }
    );
    // Unparsable range, pose, timestamp; non-finite pose.
    let e = line_error(&flaser(&["1", "x2"], TRAILER));
    assert_eq!(
        e.kind,
        LineErrorKind::BadNumber {
            field: Field::Range(1),
            token: "x2".into()
        }
    );
    let e = line_error(&flaser(&["1", "2"], "1 2 nan 1 2 3 4 h 5"));
    assert_eq!(
        e.kind,
        LineErrorKind::BadNumber {
            field: Field::Theta,
            token: "nan".into()
        }
    );
    let e = line_error(&flaser(&["1", "2"], "1 2 3 1 2 3 t h 5"));
    assert!(matches!(
        e.kind,
        LineErrorKind::BadNumber {
            field: Field::IpcTimestamp,
            ..
        }
    ));
    for bad_n in ["FLASER", "FLASER 0", "FLASER -3 1", "FLASER 2.5 1 2"] {
        assert!(
            matches!(line_error(bad_n).kind, LineErrorKind::BadBeamCount { .. }),
            "{bad_n}"
        );
    }
    assert_eq!(line_error("PARAM lonely").kind, LineErrorKind::BadParam);
    let e = line_error("PARAM robot_frontlaser_offset abc h 0");
    assert!(matches!(
        e.kind,
        LineErrorKind::BadNumber {
            field: Field::Param(_),
            ..
        }
    ));
    // The message names the line and the cause.
    let msg = line_error(&format!("{good}\nFLASER 2 1 2 3")).to_string();
    assert!(
        msg.starts_with("line 2: ") && msg.contains("found 3"),
        "{msg}"
    );
}

#[test]
fn skip_bad_lines_collects_instead_of_failing() {
    let text = format!(
        "{}\nFLASER 2 1\n{}",
        flaser(&["1", "2"], TRAILER),
        flaser(&["3", "4"], TRAILER)
    );
    let log = CarmenLog::read(
        text.as_bytes(),
        ReadOptions {
            skip_bad_lines: true,
            max_range_m: Some(8.0),
        },
    )
    .unwrap();
    assert_eq!(log.scans.len(), 2);
    assert_eq!(log.bad_lines.len(), 1);
    assert_eq!(log.bad_lines[0].line, 2);
    assert_eq!(log.max_range, MaxRange::Given(8.0));
}

#[test]
fn bad_given_max_range_is_rejected() {
    for m in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        let r = CarmenLog::read(
            &b""[..],
            ReadOptions {
                max_range_m: Some(m),
                skip_bad_lines: false,
            },
        );
        assert!(matches!(r, Err(LogError::BadOption(_))), "{m}");
    }
}

#[test]
fn detection_rule_table() {
    // (ranges, expected)
    // Real returns spread over 0.3 … 5.3 m.
    let spread: Vec<f32> = (0..200).map(|i| 0.3 + i as f32 * 0.025).collect();
    let with_sentinel = |v: f32, k: usize| {
        let mut r = spread.clone();
        r.extend(std::iter::repeat_n(v, k));
        r
    };
    // A dominant sentinel well above the returns.
    let d = detect_max_range(with_sentinel(81.83, 20).into_iter()).unwrap();
    assert_eq!((d.value_m, d.count), (81.83, 20));
    // No repeats at all: nothing to detect.
    assert_eq!(detect_max_range(spread.iter().copied()), None);
    // Too few repeats.
    assert_eq!(detect_max_range(with_sentinel(81.83, 2).into_iter()), None);
    // A sentinel that is not the largest value (error codes above it) is still found.
    let mut r = with_sentinel(8.0, 30);
    r.extend([8.01, 8.02, 8.02]);
    assert_eq!(detect_max_range(r.into_iter()).unwrap().value_m, 8.0);
    // A repeated value that does not dominate its neighbourhood is not a sentinel.
    let mut r = with_sentinel(8.0, 10);
    r.extend([7.0; 4]);
    assert_eq!(detect_max_range(r.into_iter()), None);
    // A repeated value in the middle of the returns is not at the top: not a sentinel.
    let mut r = spread.clone();
    r.extend([2.0; 50]);
    assert_eq!(detect_max_range(r.into_iter()), None);
    // Non-finite and negative readings are ignored.
    let mut r = with_sentinel(5.5, 10);
    r.extend([f32::NAN, f32::INFINITY, -1.0]);
    assert_eq!(detect_max_range(r.into_iter()).unwrap().value_m, 5.5);
}
