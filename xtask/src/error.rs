//! The one error of every task: a variant per kind of failure, each saying what failed.

use std::fmt;
use std::io;
use std::path::{Path, PathBuf};
use std::process::ExitStatus;

/// What made a task fail.
#[derive(Debug)]
pub enum Error {
    /// A command could not be started.
    Spawn {
        /// The command line.
        command: String,
        /// Why.
        source: io::Error,
    },
    /// A command exited with a failure status.
    Command {
        /// The command line.
        command: String,
        /// Its status.
        status: ExitStatus,
    },
    /// A file or socket could not be read, written or connected.
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: io::Error,
    },
    /// A tool the task needs is missing; the message says how to install it.
    Missing(String),
    /// A firmware program did not run to a successful end under QEMU (timed out, locked up,
    /// exited non-zero).
    Qemu(String),
    /// What a program printed (the firmware, cargo, the counting plugin, a tool) could not be
    /// read as expected.
    Output(String),
    /// The counted regions do not pair with the names the firmware printed, or a region
    /// expected by name is missing or not expected.
    Regions(String),
    /// The data a firmware program sent (its `frame:` and `report:` lines,
    /// `beamfield_fixtures::report`) is malformed, or lacks or has more than the host expects.
    Report(ReportFault),
    /// The device's report differs from the host's recomputation.
    Mismatch(String),
    /// The host's own run of a plan, or what it builds the device's input from, failed.
    Host(String),
    /// A requirement is not met: a bound, a hard budget, an expectation of the plan.
    Requirement(String),
    /// A checked-in generated file differs from what its generator writes today.
    Stale {
        /// The file.
        path: PathBuf,
        /// The task that regenerates it.
        task: &'static str,
    },
}

/// What is wrong with the data a firmware program sent.
#[derive(Debug)]
pub enum ReportFault {
    /// A data line whose bytes do not decode (hex, the link's decoder, the report's decoder).
    Malformed {
        /// The line's number in the program's output, from 1.
        line: usize,
        /// Why.
        why: String,
    },
    /// The host expected this; the program's data ended.
    Missing {
        /// What the host expected.
        expected: String,
    },
    /// The host expected something else, or nothing more.
    Unexpected {
        /// What the host expected.
        expected: String,
        /// What the program sent.
        got: String,
    },
}

impl fmt::Display for ReportFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReportFault::Malformed { line, why } => {
                write!(f, "the device's data line {line} does not decode: {why}")
            }
            ReportFault::Missing { expected } => {
                write!(f, "the device's data ended; expected {expected}")
            }
            ReportFault::Unexpected { expected, got } => {
                write!(f, "expected {expected}, the device sent {got}")
            }
        }
    }
}

/// The result of a task step.
pub type Result<T = ()> = std::result::Result<T, Error>;

impl Error {
    /// An I/O failure on `path`.
    pub fn io(path: impl AsRef<Path>, source: io::Error) -> Self {
        Error::Io {
            path: path.as_ref().to_path_buf(),
            source,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Spawn { command, source } => write!(f, "cannot start `{command}`: {source}"),
            Error::Command { command, status } => write!(f, "`{command}` failed ({status})"),
            Error::Io { path, source } => write!(f, "{}: {source}", path.display()),
            Error::Stale { path, task } => write!(
                f,
                "{} is stale: run `cargo xtask {task}` and commit it",
                path.display()
            ),
            Error::Report(fault) => fault.fmt(f),
            Error::Missing(m)
            | Error::Qemu(m)
            | Error::Output(m)
            | Error::Regions(m)
            | Error::Mismatch(m)
            | Error::Host(m)
            | Error::Requirement(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Spawn { source, .. } | Error::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}
