//! Errors of the CARMEN reader: per line (with its number) and per log.

use std::fmt;
use std::path::PathBuf;

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
    /// A line longer than [`super::MAX_LINE_BYTES`] (the rest of it is skipped unread into
    /// memory).
    TooLong,
    /// A line that is not UTF-8.
    NotUtf8,
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
                write!(f, "beam count \"{token}\" is not a positive integer")
            }
            LineErrorKind::BeamCountMismatch { first, found } => write!(
                f,
                "FLASER has {found} beams but the first scan of the log has {first}"
            ),
            LineErrorKind::BadNumber { field, token } => {
                write!(f, "{field}: \"{token}\" is not a finite number")
            }
            LineErrorKind::BadParam => f.write_str("PARAM line without a name and a value"),
            LineErrorKind::TooLong => {
                write!(f, "longer than {} bytes (skipped)", super::MAX_LINE_BYTES)
            }
            LineErrorKind::NotUtf8 => f.write_str("not UTF-8 text"),
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
    /// A malformed line (only without [`super::ReadOptions::skip_bad_lines`]).
    Line(LineError),
    /// A `robot_frontlaser_offset` or given max range that is not finite, or a max range ≤ 0.
    BadOption(&'static str),
    /// The log file is longer than [`crate::input::limits::MAX_LOG_BYTES`].
    TooLarge {
        /// The file.
        path: std::path::PathBuf,
    },
    /// The file is of another kind (an image, a blob, a ROS 2 bag), not a CARMEN log.
    NotALog {
        /// The file.
        path: PathBuf,
        /// What it is.
        kind: crate::input::kind::FileKind,
    },
    /// The log holds more of something than the reader keeps (scans, PARAM lines, message
    /// types): what, and the limit.
    TooMany(&'static str, usize),
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
            Self::TooLarge { path } => write!(
                f,
                "{} is larger than {} bytes, the limit for a CARMEN log",
                path.display(),
                crate::input::limits::MAX_LOG_BYTES
            ),
            Self::NotALog { path, kind } => write!(
                f,
                "{} is {kind}, not a CARMEN log (a text file of FLASER lines){}",
                path.display(),
                if *kind == crate::input::kind::FileKind::Bag {
                    "; `beamfield track --bag` reads bags"
                } else {
                    ""
                }
            ),
            Self::TooMany(what, limit) => {
                write!(
                    f,
                    "the log has more than {limit} {what}, the limit for a log"
                )
            }
        }
    }
}

impl std::error::Error for LogError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io { source, .. } => Some(source),
            Self::Line(e) => Some(e),
            Self::BadOption(_)
            | Self::TooLarge { .. }
            | Self::NotALog { .. }
            | Self::TooMany(..) => None,
        }
    }
}
