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
//! - Beam `i` (0-based) is at bearing `−90° + i·s`, counter-clockwise from the heading, with
//!   `s` = [`carmen_beam_step_rad`]`(n)`: `180°/n` for an even `n` (180 beams: −90° … +89°),
//!   `180°/(n − 1)` for an odd `n` (181 or 361 beams: −90° … +90°); a scan is
//!   [`BeamLayout::uniform`]`(−π/2, s, n, max_range, mount)`.
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
mod scan;
mod stats;

pub use detect::{
    detect_max_range, Detection, DETECT_DOMINANCE, DETECT_MIN_REPEATS, DETECT_TOP_QUANTILE,
};
pub use error::{Field, LineError, LineErrorKind, LogError};
pub use scan::{carmen_beam_step_rad, carmen_bearing_rad, LaserScan, PoseF64};
pub(crate) use stats::Extent;
pub use stats::{decimal_f64, serialize_f32, Bounds, LogStats};

use flaser::{parse_finite, parse_flaser};

use beamfield::{BeamLayout, ScanError, SensorMount};
use std::collections::BTreeMap;
use std::io::BufRead;
use std::path::Path;

/// Tokens after the ranges of a FLASER line: laser pose (3), robot pose (3), ipc timestamp,
/// ipc hostname, logger timestamp.
pub const FLASER_TRAILER_TOKENS: usize = 9;

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
    /// [`LogError::Io`] when the file cannot be read, [`LogError::NotALog`] for an image, a blob
    /// or a bag, [`LogError::Line`] for the first malformed line (unless
    /// [`ReadOptions::skip_bad_lines`]), [`LogError::BadOption`] for a given max range that is
    /// not finite and positive.
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
        // An image, a blob or a bag given as the log: said as such, not as its first bad line.
        // Its first bytes are looked at in the reader's buffer (a FIFO is read once).
        let head = reader.fill_buf().map_err(|source| LogError::Io {
            path: Some(path.to_path_buf()),
            source,
        })?;
        if let Some(kind) = crate::input::kind::file_kind(head) {
            return Err(LogError::NotALog {
                path: path.to_path_buf(),
                kind,
            });
        }
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
    /// `uniform(−π/2, s, n, max_range, CENTERED)`, `s` = [`carmen_beam_step_rad`]`(n)`.
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
        let step = carmen_beam_step_rad(n) as f32;
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
mod tests;
