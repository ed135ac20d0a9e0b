//! Reading CARMEN "old format" laser logs (one message per line, whitespace-separated).
//!
//! ```text
//! FLASER n r_1 … r_n  x y theta  odom_x odom_y odom_theta  ipc_timestamp ipc_hostname logger_timestamp
//! PARAM  name value [host timestamp]
//! #      comment
//! ```
//!
//! - **FLASER**: exactly `n + 9` tokens after `n`. Ranges in metres; `x y theta` is the laser's
//!   pose and `odom_x odom_y odom_theta` the robot's (CARMEN writes the laser pose first). In a
//!   SLAM-corrected log such as the Intel lab log both hold the corrected pose. Angles are kept as
//!   written (the Intel log has θ up to 3.247, not wrapped).
//! - Beam `i` (0-based) is at bearing `−90° + i·180°/n`, counter-clockwise from the heading: a
//!   scan is [`BeamLayout::uniform`]`(−π/2, π/n, n, max_range, mount)`.
//! - **PARAM** lines are all kept ([`CarmenLog::params`]); `robot_frontlaser_offset` (metres,
//!   forward) is parsed into [`CarmenLog::frontlaser_offset_m`].
//! - Every other message type (ODOM, NEFF, RLASER, …) is skipped and counted per type
//!   ([`CarmenLog::skipped`]); `#` comments and blank lines are counted too. Nothing is dropped
//!   silently.
//!
//! # The max-range value
//! CARMEN writes "no return" as a sensor-specific number (81.83 in the Intel log, from a SICK
//! LMS); it is not in the file's header. Either it is given ([`ReadOptions::max_range_m`]) or it
//! is detected from the ranges by the rule of [`detect_max_range`].
//!
//! # Errors
//! A malformed line is a [`LineError`] with its 1-based line number and what was wrong. With
//! [`ReadOptions::skip_bad_lines`] the reader collects them in [`CarmenLog::bad_lines`] and goes
//! on; otherwise the first one stops the read.

mod detect;
mod error;
mod flaser;
mod stats;

pub use detect::{
    detect_max_range, Detection, DETECT_DOMINANCE, DETECT_MIN_REPEATS, DETECT_TOP_QUANTILE,
};
pub use error::{Field, LineError, LineErrorKind, LogError};
pub(crate) use stats::Extent;
pub use stats::{decimal_f64, serialize_f32, Bounds, LogStats};

use flaser::{parse_finite, parse_flaser};

use beamfield::{BeamLayout, Pose, Scan, ScanError, SensorMount};
use std::collections::BTreeMap;
use std::io::BufRead;
use std::path::Path;

/// Tokens after the ranges of a FLASER line: laser pose (3), robot pose (3), ipc timestamp,
/// ipc hostname, logger timestamp.
pub const FLASER_TRAILER_TOKENS: usize = 9;

/// One FLASER message.
#[derive(Clone, Debug, PartialEq)]
pub struct LaserScan {
    /// The ranges as written, metres, in beam order (beam `i` at `−90° + i·180°/n`). Max-range
    /// readings keep their sentinel value; [`beamfield::Reading::classify`] against the log's
    /// max range tells them apart.
    pub ranges_m: Vec<f32>,
    /// The laser's pose in the world frame (`x y theta`), metres and radians, θ as written.
    pub pose: Pose,
    /// The robot's pose (`odom_x odom_y odom_theta`), metres and radians.
    pub odom_pose: Pose,
    /// The laser's pose as parsed, in f64 ([`LaserScan::pose`] is it rounded to f32): what the
    /// map builder projects beams from, so that a log far from the origin keeps its precision.
    pub pose_f64: PoseF64,
    /// The ipc timestamp, seconds. Not necessarily increasing (the Intel log steps back 4 times).
    pub timestamp_s: f64,
    /// The logger timestamp, seconds.
    pub logger_timestamp_s: f64,
    /// 1-based line number in the log.
    pub line: usize,
}

impl LaserScan {
    /// The ranges as a fixed-capacity [`Scan`] for the `beamfield` models.
    ///
    /// # Errors
    /// [`ScanError::TooMany`] when the scan has more than `N` readings (nothing is truncated).
    pub fn to_scan<const N: usize>(&self) -> Result<Scan<N>, ScanError> {
        Scan::from_ranges(&self.ranges_m)
    }

    /// World-frame end point of beam `i` (metres), in f64 from the f64 pose
    /// ([`LaserScan::pose_f64`]), or `None` past the last beam. Uses the CARMEN bearing
    /// `−π/2 + i·π/n`; max-range readings are projected like any other.
    pub fn endpoint(&self, i: usize) -> Option<(f64, f64)> {
        let n = self.ranges_m.len();
        let r = f64::from(*self.ranges_m.get(i)?);
        let p = self.pose_f64;
        let a = p.theta_rad + carmen_bearing_rad(i, n);
        Some((p.x_m + r * a.cos(), p.y_m + r * a.sin()))
    }
}

/// A pose in f64 (metres, metres, radians).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseF64 {
    /// x, metres.
    pub x_m: f64,
    /// y, metres.
    pub y_m: f64,
    /// θ, radians.
    pub theta_rad: f64,
}

impl From<Pose> for PoseF64 {
    fn from(p: Pose) -> Self {
        Self {
            x_m: f64::from(p.x_m),
            y_m: f64::from(p.y_m),
            theta_rad: f64::from(p.theta_rad),
        }
    }
}

/// Bearing of beam `i` of `n` in a FLASER scan, radians: `−π/2 + i·π/n`, in f64.
pub fn carmen_bearing_rad(i: usize, n: usize) -> f64 {
    -std::f64::consts::FRAC_PI_2 + i as f64 * std::f64::consts::PI / n.max(1) as f64
}

/// How to read a log.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReadOptions {
    /// The max-range ("no return") value, metres. `None`: detect it ([`detect_max_range`]).
    pub max_range_m: Option<f32>,
    /// Collect malformed lines in [`CarmenLog::bad_lines`] and go on, instead of failing on the
    /// first one.
    pub skip_bad_lines: bool,
}

/// Where the log's max-range value came from.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum MaxRange {
    /// Given by the caller, metres.
    Given(f32),
    /// Detected by [`detect_max_range`].
    Detected(Detection),
    /// No value satisfies the detection rule and none was given. Models need one: ask the user.
    #[default]
    NotFound,
}

impl MaxRange {
    /// The value in metres, if any.
    pub fn value_m(&self) -> Option<f32> {
        match self {
            Self::Given(v) => Some(*v),
            Self::Detected(d) => Some(d.value_m),
            Self::NotFound => None,
        }
    }
}

/// The longest line read, bytes. A FLASER line of 1,081 beams (a 270° Hokuyo at 0.25°) is
/// about 9 KB; anything longer is a counted bad line, and its bytes past this are skipped
/// without being kept, so a log without newlines (`/dev/zero`, a broken pipe) costs bounded
/// memory.
pub const MAX_LINE_BYTES: usize = 64 * 1024;

/// Message types, PARAM names and values longer than this are shortened when stored (they are
/// printed back by `log info`).
const MAX_NAME_CHARS: usize = 64;

/// `s` as it may be printed: unchanged if it is at most [`MAX_NAME_CHARS`] of printable ASCII,
/// else escaped (`\u{1b}`, `\0`, …) and cut at [`MAX_NAME_CHARS`] characters with `…`. A
/// terminal never receives a control byte from the log.
pub(crate) fn printable(s: &str) -> String {
    if s.len() <= MAX_NAME_CHARS && s.bytes().all(|b| b.is_ascii_graphic()) {
        return s.to_string();
    }
    let mut out: String = s.escape_default().take(MAX_NAME_CHARS).collect();
    if s.escape_default().nth(MAX_NAME_CHARS).is_some() {
        out.push('…');
    }
    out
}

/// One line of the log as [`next_line`] read it.
enum Line<'a> {
    /// Its text, without the line end.
    Text(&'a str),
    /// Longer than [`MAX_LINE_BYTES`]; the rest of it was skipped.
    TooLong,
    /// Not UTF-8.
    NotUtf8,
}

/// Reads the next line into `buf` (at most [`MAX_LINE_BYTES`] of it kept), `None` at the end.
fn next_line<'a, R: BufRead>(
    reader: &mut R,
    buf: &'a mut Vec<u8>,
) -> std::io::Result<Option<Line<'a>>> {
    use std::io::Read;
    buf.clear();
    let limit = MAX_LINE_BYTES as u64 + 1;
    let n = reader.by_ref().take(limit).read_until(b'\n', buf)?;
    if n == 0 {
        return Ok(None);
    }
    if buf.last() == Some(&b'\n') {
        buf.pop();
        if buf.last() == Some(&b'\r') {
            buf.pop();
        }
    } else if buf.len() > MAX_LINE_BYTES {
        // Skip to the end of the line without keeping it.
        loop {
            let chunk = reader.fill_buf()?;
            if chunk.is_empty() {
                break;
            }
            if let Some(i) = chunk.iter().position(|&b| b == b'\n') {
                reader.consume(i + 1);
                break;
            }
            let len = chunk.len();
            reader.consume(len);
        }
        return Ok(Some(Line::TooLong));
    }
    Ok(Some(match std::str::from_utf8(buf) {
        Ok(t) => Line::Text(t),
        Err(_) => Line::NotUtf8,
    }))
}

/// Malformed lines kept in [`CarmenLog::bad_lines`] (the others are counted only).
pub const MAX_BAD_LINES_KEPT: usize = 1000;
/// Most FLASER scans a log may have: 1,048,576 (the Intel log has 910; a 40 Hz laser logs about
/// 7 hours in as many). More is [`LogError::TooMany`].
pub const MAX_LOG_SCANS: usize = 1 << 20;
/// Most PARAM lines a log may have (a CARMEN log has a few hundred). More is
/// [`LogError::TooMany`].
pub const MAX_LOG_PARAMS: usize = 10_000;
/// Most distinct other message types a log may have (ODOM, NEFF, RLASER, …). More is
/// [`LogError::TooMany`].
pub const MAX_LOG_MESSAGE_TYPES: usize = 1000;

/// A read log.
#[derive(Clone, Debug, Default)]
pub struct CarmenLog {
    /// The FLASER scans, in file order.
    pub scans: Vec<LaserScan>,
    /// Every PARAM line's `(name, value)`, in file order.
    pub params: Vec<(String, String)>,
    /// `robot_frontlaser_offset`, metres forward, if the log has it.
    pub frontlaser_offset_m: Option<f32>,
    /// Lines of other message types, counted per type (ODOM, NEFF, …).
    pub skipped: BTreeMap<String, usize>,
    /// `#` comment lines.
    pub comments: usize,
    /// Blank lines.
    pub blank_lines: usize,
    /// Malformed lines, when read with [`ReadOptions::skip_bad_lines`]: the first
    /// [`MAX_BAD_LINES_KEPT`] of them ([`CarmenLog::bad_line_count`] counts them all).
    pub bad_lines: Vec<LineError>,
    /// Malformed lines in all (when read with [`ReadOptions::skip_bad_lines`]).
    pub bad_line_count: usize,
    /// The max-range value: given, detected or not found.
    pub max_range: MaxRange,
}

impl CarmenLog {
    /// Reads a log file.
    ///
    /// # Errors
    /// [`LogError::Io`] when the file cannot be read, [`LogError::Line`] for the first malformed
    /// line (unless [`ReadOptions::skip_bad_lines`]), [`LogError::BadOption`] for a given max
    /// range that is not finite and positive.
    ///
    /// At most [`crate::input::limits::MAX_LOG_BYTES`] are read: a longer file (or a FIFO or device
    /// that does not end, such as `/dev/zero`) is [`LogError::TooLarge`], whatever its lines.
    pub fn read_path(path: &Path, options: ReadOptions) -> Result<Self, LogError> {
        use std::io::Read;
        let file = std::fs::File::open(path).map_err(|source| LogError::Io {
            path: Some(path.to_path_buf()),
            source,
        })?;
        let mut reader = std::io::BufReader::new(
            file.take(crate::input::limits::MAX_LOG_BYTES.saturating_add(1)),
        );
        let read = Self::read(&mut reader, options);
        // More than the limit was there: the file is too large, whatever a cut line says.
        if reader.get_ref().limit() == 0 {
            return Err(LogError::TooLarge {
                path: path.to_path_buf(),
            });
        }
        read.map_err(|e| match e {
            LogError::Io { path: None, source } => LogError::Io {
                path: Some(path.to_path_buf()),
                source,
            },
            other => other,
        })
    }

    /// Reads a log from any buffered reader.
    ///
    /// # Errors
    /// As [`CarmenLog::read_path`].
    pub fn read<R: BufRead>(reader: R, options: ReadOptions) -> Result<Self, LogError> {
        if let Some(m) = options.max_range_m {
            if !(m.is_finite() && m > 0.0) {
                return Err(LogError::BadOption(
                    "the max range must be a finite number of metres > 0",
                ));
            }
        }
        let mut log = Self::default();
        let mut reader = reader;
        let mut buf = Vec::new();
        let mut number = 0usize;
        loop {
            let io = |source| LogError::Io { path: None, source };
            let Some(line) = next_line(&mut reader, &mut buf).map_err(io)? else {
                break;
            };
            number += 1;
            let parsed = match line {
                Line::Text(text) => log.parse_line(text, number)?,
                Line::TooLong => Err(LineError {
                    line: number,
                    kind: LineErrorKind::TooLong,
                }),
                Line::NotUtf8 => Err(LineError {
                    line: number,
                    kind: LineErrorKind::NotUtf8,
                }),
            };
            if let Err(e) = parsed {
                if options.skip_bad_lines {
                    log.bad_line_count += 1;
                    if log.bad_lines.len() < MAX_BAD_LINES_KEPT {
                        log.bad_lines.push(e);
                    }
                } else {
                    return Err(LogError::Line(e));
                }
            }
        }
        log.max_range = match options.max_range_m {
            Some(m) => MaxRange::Given(m),
            None => detect_max_range(log.scans.iter().flat_map(|s| s.ranges_m.iter().copied()))
                .map_or(MaxRange::NotFound, MaxRange::Detected),
        };
        Ok(log)
    }

    /// Parses one line into the log; the outer error is a limit of the whole log, the inner
    /// one a malformed line.
    fn parse_line(&mut self, line: &str, number: usize) -> Result<Result<(), LineError>, LogError> {
        let mut tokens = line.split_whitespace();
        let Some(kind) = tokens.next() else {
            self.blank_lines += 1;
            return Ok(Ok(()));
        };
        if kind.starts_with('#') {
            self.comments += 1;
            return Ok(Ok(()));
        }
        match kind {
            "FLASER" if self.scans.len() >= MAX_LOG_SCANS => {
                return Err(LogError::TooMany("FLASER scans", MAX_LOG_SCANS))
            }
            "PARAM" if self.params.len() >= MAX_LOG_PARAMS => {
                return Err(LogError::TooMany("PARAM lines", MAX_LOG_PARAMS))
            }
            "FLASER" | "PARAM" => {}
            other
                if self.skipped.len() >= MAX_LOG_MESSAGE_TYPES
                    && !self.skipped.contains_key(&printable(other)) =>
            {
                return Err(LogError::TooMany(
                    "distinct message types",
                    MAX_LOG_MESSAGE_TYPES,
                ))
            }
            _ => {}
        }
        Ok(self.parse_message(kind, tokens, number))
    }

    fn parse_message<'a>(
        &mut self,
        kind: &str,
        mut tokens: impl Iterator<Item = &'a str>,
        number: usize,
    ) -> Result<(), LineError> {
        match kind {
            "FLASER" => {
                let first_n = self.scans.first().map(|s| s.ranges_m.len());
                let scan = parse_flaser(tokens, number, first_n)?;
                self.scans.push(scan);
            }
            "PARAM" => {
                let (Some(name), Some(value)) = (tokens.next(), tokens.next()) else {
                    return Err(LineError {
                        line: number,
                        kind: LineErrorKind::BadParam,
                    });
                };
                if name == "robot_frontlaser_offset" {
                    let v = parse_finite::<f32>(value, Field::Param(printable(name)), number)?;
                    self.frontlaser_offset_m = Some(v);
                }
                self.params.push((printable(name), printable(value)));
            }
            other => *self.skipped.entry(printable(other)).or_insert(0) += 1,
        }
        Ok(())
    }

    /// Number of beams per scan (that of the first scan; the reader enforces it for all).
    pub fn beams(&self) -> Option<usize> {
        self.scans.first().map(|s| s.ranges_m.len())
    }

    /// The sensor layout for scoring at the FLASER (laser) pose [`LaserScan::pose`]:
    /// `uniform(−π/2, π/n, n, max_range, CENTERED)`.
    ///
    /// To score at the robot pose [`LaserScan::odom_pose`] instead, build the layout with
    /// [`CarmenLog::robot_mount`].
    ///
    /// # Errors
    /// [`ScanError::Empty`] when the log has no scan, [`ScanError::BadMaxRange`] when it has no
    /// max-range value ([`MaxRange::NotFound`]), [`ScanError::TooMany`] when `n > N`.
    pub fn layout<const N: usize>(&self) -> Result<BeamLayout<N>, ScanError> {
        self.layout_with_mount(SensorMount::CENTERED)
    }

    /// As [`CarmenLog::layout`], with an explicit sensor mount.
    ///
    /// # Errors
    /// As [`CarmenLog::layout`], plus [`ScanError::BadMount`].
    pub fn layout_with_mount<const N: usize>(
        &self,
        mount: SensorMount,
    ) -> Result<BeamLayout<N>, ScanError> {
        let n = self.beams().ok_or(ScanError::Empty)?;
        let max_range_m = self.max_range.value_m().ok_or(ScanError::BadMaxRange)?;
        let step = (std::f64::consts::PI / n as f64) as f32;
        BeamLayout::uniform(-core::f32::consts::FRAC_PI_2, step, n, max_range_m, mount)
    }

    /// The laser's mount on the robot from `robot_frontlaser_offset` (forward offset, metres;
    /// zero when the log has none).
    pub fn robot_mount(&self) -> SensorMount {
        SensorMount {
            x_m: self.frontlaser_offset_m.unwrap_or(0.0),
            y_m: 0.0,
            yaw_rad: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert!((layout.beams()[2].bearing_rad - core::f32::consts::PI / 6.0).abs() < 1e-6);
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
}
