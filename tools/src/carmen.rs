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

use beamfield::{BeamLayout, Pose, Scan, ScanError, SensorMount};
use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::io::BufRead;
use std::path::{Path, PathBuf};

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

    /// World-frame end point of beam `i` (metres), in f64, or `None` past the last beam.
    /// Uses the CARMEN bearing `−π/2 + i·π/n`; max-range readings are projected like any other.
    pub fn endpoint(&self, i: usize) -> Option<(f64, f64)> {
        let n = self.ranges_m.len();
        let r = f64::from(*self.ranges_m.get(i)?);
        let a = f64::from(self.pose.theta_rad) + carmen_bearing_rad(i, n);
        Some((
            f64::from(self.pose.x_m) + r * a.cos(),
            f64::from(self.pose.y_m) + r * a.sin(),
        ))
    }
}

/// Bearing of beam `i` of `n` in a FLASER scan, radians: `−π/2 + i·π/n`, in f64.
pub fn carmen_bearing_rad(i: usize, n: usize) -> f64 {
    -std::f64::consts::FRAC_PI_2 + i as f64 * std::f64::consts::PI / n.max(1) as f64
}

/// Which field of a line could not be read as a number.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Field {
    /// Range `i` (0-based).
    Range(usize),
    /// Laser x.
    X,
    /// Laser y.
    Y,
    /// Laser θ.
    Theta,
    /// Robot (odometry) x.
    OdomX,
    /// Robot (odometry) y.
    OdomY,
    /// Robot (odometry) θ.
    OdomTheta,
    /// ipc timestamp.
    IpcTimestamp,
    /// logger timestamp.
    LoggerTimestamp,
    /// The value of a PARAM line, by name.
    Param(String),
}

impl fmt::Display for Field {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Range(i) => write!(f, "range {i}"),
            Self::X => f.write_str("x"),
            Self::Y => f.write_str("y"),
            Self::Theta => f.write_str("theta"),
            Self::OdomX => f.write_str("odom_x"),
            Self::OdomY => f.write_str("odom_y"),
            Self::OdomTheta => f.write_str("odom_theta"),
            Self::IpcTimestamp => f.write_str("ipc_timestamp"),
            Self::LoggerTimestamp => f.write_str("logger_timestamp"),
            Self::Param(name) => write!(f, "parameter {name}"),
        }
    }
}

/// What was wrong with one line.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum LineErrorKind {
    /// A FLASER line whose token count does not match its `n`: `n + 9` tokens were expected
    /// after `n`.
    WrongTokenCount {
        /// The line's beam count `n`.
        beams: usize,
        /// `n + 9`.
        expected: usize,
        /// Tokens actually found after `n`.
        found: usize,
    },
    /// The beam count `n` is missing, not an integer, or zero.
    BadBeamCount {
        /// The token found (empty when missing).
        token: String,
    },
    /// The beam count differs from the first scan's: one log, one sensor layout.
    BeamCountMismatch {
        /// `n` of the first FLASER line.
        first: usize,
        /// `n` of this line.
        found: usize,
    },
    /// A token that is not a number, or a pose or timestamp that is not finite.
    BadNumber {
        /// Which field.
        field: Field,
        /// The token as written.
        token: String,
    },
    /// A PARAM line without a name or value.
    BadParam,
}

/// A malformed line: its 1-based number and what was wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LineError {
    /// 1-based line number.
    pub line: usize,
    /// What was wrong.
    pub kind: LineErrorKind,
}

impl fmt::Display for LineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: ", self.line)?;
        match &self.kind {
            LineErrorKind::WrongTokenCount {
                beams,
                expected,
                found,
            } => write!(
                f,
                "FLASER with {beams} beams needs {expected} tokens after the beam count \
                 ({beams} ranges + 9), found {found}"
            ),
            LineErrorKind::BadBeamCount { token } if token.is_empty() => {
                f.write_str("FLASER without a beam count")
            }
            LineErrorKind::BadBeamCount { token } => {
                write!(f, "beam count {token:?} is not a positive integer")
            }
            LineErrorKind::BeamCountMismatch { first, found } => write!(
                f,
                "FLASER has {found} beams but the first scan of the log has {first}"
            ),
            LineErrorKind::BadNumber { field, token } => {
                write!(f, "{field}: {token:?} is not a finite number")
            }
            LineErrorKind::BadParam => f.write_str("PARAM line without a name and a value"),
        }
    }
}

impl std::error::Error for LineError {}

/// Errors reading a whole log.
#[derive(Debug)]
#[non_exhaustive]
pub enum LogError {
    /// The file could not be opened or read.
    Io {
        /// The path, when reading from a file.
        path: Option<PathBuf>,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A malformed line (only without [`ReadOptions::skip_bad_lines`]).
    Line(LineError),
    /// A `robot_frontlaser_offset` or given max range that is not finite, or a max range ≤ 0.
    BadOption(&'static str),
}

impl fmt::Display for LogError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Io {
                path: Some(p),
                source,
            } => write!(f, "cannot read {}: {source}", p.display()),
            Self::Io { path: None, source } => write!(f, "cannot read log: {source}"),
            Self::Line(e) => e.fmt(f),
            Self::BadOption(what) => f.write_str(what),
        }
    }
}

impl std::error::Error for LogError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io { source, .. } => Some(source),
            Self::Line(e) => Some(e),
            Self::BadOption(_) => None,
        }
    }
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

/// A detected max-range value and the evidence for it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Detection {
    /// The value, metres.
    pub value_m: f32,
    /// Readings exactly equal to it.
    pub count: usize,
    /// The most repeated other value at or above half of it, and its count (the runner-up the
    /// dominance test compared against), if any.
    pub runner_up: Option<(f32, usize)>,
}

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
    /// Malformed lines, when read with [`ReadOptions::skip_bad_lines`].
    pub bad_lines: Vec<LineError>,
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
    pub fn read_path(path: &Path, options: ReadOptions) -> Result<Self, LogError> {
        let file = std::fs::File::open(path).map_err(|source| LogError::Io {
            path: Some(path.to_path_buf()),
            source,
        })?;
        Self::read(std::io::BufReader::new(file), options).map_err(|e| match e {
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
        for (index, line) in reader.lines().enumerate() {
            let line = line.map_err(|source| LogError::Io { path: None, source })?;
            if let Err(e) = log.parse_line(&line, index + 1) {
                if options.skip_bad_lines {
                    log.bad_lines.push(e);
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

    fn parse_line(&mut self, line: &str, number: usize) -> Result<(), LineError> {
        let mut tokens = line.split_whitespace();
        let Some(kind) = tokens.next() else {
            self.blank_lines += 1;
            return Ok(());
        };
        if kind.starts_with('#') {
            self.comments += 1;
            return Ok(());
        }
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
                    let v = parse_finite::<f32>(value, Field::Param(name.to_string()), number)?;
                    self.frontlaser_offset_m = Some(v);
                }
                self.params.push((name.to_string(), value.to_string()));
            }
            other => *self.skipped.entry(other.to_string()).or_insert(0) += 1,
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

    /// Summary statistics of the log (for `beamfield log info`).
    pub fn stats(&self) -> LogStats {
        let mut s = LogStats {
            scans: self.scans.len(),
            beams: self.beams(),
            ..LogStats::default()
        };
        let max_range = self.max_range.value_m();
        let mut pose = Extent::default();
        let mut prev_t: Option<f64> = None;
        for scan in &self.scans {
            pose.add(decimal_f64(scan.pose.x_m), decimal_f64(scan.pose.y_m));
            s.theta_min_rad = s.theta_min_rad.min(scan.pose.theta_rad);
            s.theta_max_rad = s.theta_max_rad.max(scan.pose.theta_rad);
            if let Some(p) = prev_t {
                if scan.timestamp_s < p {
                    s.timestamp_steps_back += 1;
                }
            }
            prev_t = Some(scan.timestamp_s);
            s.readings += scan.ranges_m.len();
            for &r in &scan.ranges_m {
                match max_range {
                    Some(m) if r == m => s.max_range_readings += 1,
                    Some(m) if r > m => s.above_max_range_readings += 1,
                    _ => {
                        if r.is_finite() && r >= 0.0 {
                            s.min_range_m = s.min_range_m.min(r);
                            s.max_valid_range_m = s.max_valid_range_m.max(r);
                        } else {
                            s.invalid_readings += 1;
                        }
                    }
                }
            }
        }
        s.pose_extent = pose.finish();
        s
    }
}

/// A bounding box, metres.
#[derive(Clone, Copy, Debug, PartialEq, Default, serde::Serialize)]
pub struct Bounds {
    /// Smallest x.
    pub x_min: f64,
    /// Largest x.
    pub x_max: f64,
    /// Smallest y.
    pub y_min: f64,
    /// Largest y.
    pub y_max: f64,
}

/// Accumulates a bounding box.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Extent(Option<Bounds>);

impl Extent {
    pub(crate) fn add(&mut self, x: f64, y: f64) {
        if !(x.is_finite() && y.is_finite()) {
            return;
        }
        let b = self.0.get_or_insert(Bounds {
            x_min: x,
            x_max: x,
            y_min: y,
            y_max: y,
        });
        b.x_min = b.x_min.min(x);
        b.x_max = b.x_max.max(x);
        b.y_min = b.y_min.min(y);
        b.y_max = b.y_max.max(y);
    }

    pub(crate) fn finish(self) -> Option<Bounds> {
        self.0
    }
}

/// The f64 with the same shortest decimal text as `v` (0.23f32 → 0.23, not 0.23000000417…),
/// for reports of values that were written in decimal.
pub fn decimal_f64(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::from(v))
}

/// Serializes an f32 as the f64 with the same shortest decimal text (81.83, not
/// 81.83000183105469); non-finite values become `null`.
pub fn serialize_f32<S: serde::Serializer>(v: &f32, s: S) -> Result<S::Ok, S::Error> {
    let shortest = decimal_f64(*v);
    if shortest.is_finite() {
        s.serialize_f64(shortest)
    } else {
        s.serialize_none()
    }
}

/// What `beamfield log info` prints.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LogStats {
    /// FLASER scans.
    pub scans: usize,
    /// Beams per scan.
    pub beams: Option<usize>,
    /// All readings.
    pub readings: usize,
    /// Readings exactly at the max-range value.
    pub max_range_readings: usize,
    /// Readings above the max-range value (treated as max range by the models).
    pub above_max_range_readings: usize,
    /// NaN, infinite or negative readings (below the max range).
    pub invalid_readings: usize,
    /// Smallest valid reading, metres.
    #[serde(serialize_with = "serialize_f32")]
    pub min_range_m: f32,
    /// Largest reading below the max-range value, metres.
    #[serde(serialize_with = "serialize_f32")]
    pub max_valid_range_m: f32,
    /// Laser pose extent, metres.
    pub pose_extent: Option<Bounds>,
    /// Smallest θ as written, radians.
    #[serde(serialize_with = "serialize_f32")]
    pub theta_min_rad: f32,
    /// Largest θ as written, radians.
    #[serde(serialize_with = "serialize_f32")]
    pub theta_max_rad: f32,
    /// Places where the ipc timestamp is smaller than the previous scan's.
    pub timestamp_steps_back: usize,
}

impl Default for LogStats {
    fn default() -> Self {
        Self {
            scans: 0,
            beams: None,
            readings: 0,
            max_range_readings: 0,
            above_max_range_readings: 0,
            invalid_readings: 0,
            min_range_m: f32::INFINITY,
            max_valid_range_m: f32::NEG_INFINITY,
            pose_extent: None,
            theta_min_rad: f32::INFINITY,
            theta_max_rad: f32::NEG_INFINITY,
            timestamp_steps_back: 0,
        }
    }
}

fn parse_finite<T>(token: &str, field: Field, line: usize) -> Result<T, LineError>
where
    T: std::str::FromStr + Into<f64> + Copy,
{
    match token.parse::<T>() {
        Ok(v) if v.into().is_finite() => Ok(v),
        _ => Err(LineError {
            line,
            kind: LineErrorKind::BadNumber {
                field,
                token: token.to_string(),
            },
        }),
    }
}

fn parse_flaser<'a>(
    mut tokens: impl Iterator<Item = &'a str>,
    line: usize,
    first_n: Option<usize>,
) -> Result<LaserScan, LineError> {
    let err = |kind| LineError { line, kind };
    let n_token = tokens.next().unwrap_or("");
    let n = match n_token.parse::<usize>() {
        Ok(n) if n > 0 => n,
        _ => {
            return Err(err(LineErrorKind::BadBeamCount {
                token: n_token.to_string(),
            }))
        }
    };
    let rest: Vec<&str> = tokens.collect();
    let expected = n.saturating_add(FLASER_TRAILER_TOKENS);
    if rest.len() != expected {
        return Err(err(LineErrorKind::WrongTokenCount {
            beams: n,
            expected,
            found: rest.len(),
        }));
    }
    if let Some(first) = first_n {
        if first != n {
            return Err(err(LineErrorKind::BeamCountMismatch { first, found: n }));
        }
    }
    let (range_tokens, trailer) = rest.split_at(n);
    let mut ranges_m = Vec::with_capacity(n);
    for (i, t) in range_tokens.iter().enumerate() {
        // Ranges may be anything numeric (inf, nan): the reading policy classifies them later.
        let v = t.parse::<f32>().map_err(|_| {
            err(LineErrorKind::BadNumber {
                field: Field::Range(i),
                token: (*t).to_string(),
            })
        })?;
        ranges_m.push(v);
    }
    let fields = [
        Field::X,
        Field::Y,
        Field::Theta,
        Field::OdomX,
        Field::OdomY,
        Field::OdomTheta,
    ];
    let mut pose = [0.0f32; 6];
    for ((slot, field), token) in pose.iter_mut().zip(fields).zip(trailer) {
        *slot = parse_finite::<f32>(token, field, line)?;
    }
    let [x, y, th, ox, oy, oth] = pose;
    let (ipc, logger) = match trailer {
        [.., ipc, _host, logger] => (
            parse_finite::<f64>(ipc, Field::IpcTimestamp, line)?,
            parse_finite::<f64>(logger, Field::LoggerTimestamp, line)?,
        ),
        // Unreachable: the token count was checked above; report it as a count error anyway.
        _ => {
            return Err(err(LineErrorKind::WrongTokenCount {
                beams: n,
                expected,
                found: rest.len(),
            }))
        }
    };
    Ok(LaserScan {
        ranges_m,
        pose: Pose::new(x, y, th),
        odom_pose: Pose::new(ox, oy, oth),
        timestamp_s: ipc,
        logger_timestamp_s: logger,
        line,
    })
}

/// Smallest number of exact repeats for a detected max-range value.
pub const DETECT_MIN_REPEATS: usize = 3;
/// How many times more often the max-range value must occur than any other value at or above
/// half of it.
pub const DETECT_DOMINANCE: usize = 5;
/// The top band searched for the max-range value: readings at or above this quantile.
pub const DETECT_TOP_QUANTILE: f64 = 0.95;

/// Detects a log's max-range ("no return") value from its ranges.
///
/// A no-return sentinel is one exact number, written for every beam without an echo; real
/// returns are spread over many values (even at the log's 1 cm print resolution). The rule:
///
/// 1. Take the finite, non-negative readings; the top band is those at or above the
///    [`DETECT_TOP_QUANTILE`] (95 %) quantile.
/// 2. The candidate `v` is the most repeated exact value in the top band (ties: the larger).
/// 3. `v` is accepted when it occurs at least [`DETECT_MIN_REPEATS`] times and at least
///    [`DETECT_DOMINANCE`] (5) times as often as every other value `≥ v/2` (the runner-up).
///
/// Values above `v` (for example SICK error codes just above the sentinel) do not prevent
/// detection as long as `v` dominates them; the models treat them as max range too. A log with
/// no sentinel at all (every beam echoed) gives `None`: give the value instead.
///
/// On the Intel log: 81.83, 4,172 times; the runner-up in `[40.9, ∞)` does not exist (the largest
/// real return is 25.38 m).
pub fn detect_max_range(ranges_m: impl Iterator<Item = f32>) -> Option<Detection> {
    let mut values: Vec<f32> = ranges_m.filter(|r| r.is_finite() && *r >= 0.0).collect();
    if values.is_empty() {
        return None;
    }
    values.sort_by(f32::total_cmp);
    let q_index = ((values.len() - 1) as f64 * DETECT_TOP_QUANTILE).floor() as usize;
    let threshold = *values.get(q_index)?;
    let mut counts: HashMap<u32, usize> = HashMap::new();
    for v in &values {
        *counts.entry(v.to_bits()).or_insert(0) += 1;
    }
    let (candidate, count) = counts
        .iter()
        .map(|(&bits, &c)| (f32::from_bits(bits), c))
        .filter(|(v, _)| *v >= threshold)
        .max_by(|a, b| a.1.cmp(&b.1).then(a.0.total_cmp(&b.0)))?;
    let runner_up = counts
        .iter()
        .map(|(&bits, &c)| (f32::from_bits(bits), c))
        .filter(|(v, _)| *v >= 0.5 * candidate && *v != candidate)
        .max_by(|a, b| a.1.cmp(&b.1).then(a.0.total_cmp(&b.0)));
    let runner_count = runner_up.map_or(0, |r| r.1);
    if count >= DETECT_MIN_REPEATS && count >= DETECT_DOMINANCE.saturating_mul(runner_count) {
        Some(Detection {
            value_m: candidate,
            count,
            runner_up,
        })
    } else {
        None
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
