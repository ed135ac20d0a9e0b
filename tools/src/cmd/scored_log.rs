//! The inputs `score` and `calibrate` share: the field blob, the CARMEN log and the likelihood
//! field's options ([`ModelArgs`]), read and checked once ([`load`]); their error type.
//!
//! The FLASER pose is the laser's pose, so scans are scored with a centred mount and poses are
//! laser poses (metres, radians in the map frame).

use crate::cmd::likelihood::LikelihoodArgs;
use crate::input::carmen::{CarmenLog, LogError, ReadOptions};
use beamfield::field::LikelihoodParams;
use beamfield::{BeamLayout, Pose, Scan, SensorMount};
use clap::Args;
use std::path::PathBuf;

/// Beam capacity of the scans these commands read (CARMEN FLASER scans have 180 or 361).
pub const MAX_BEAMS: usize = 1081;

/// The inputs of `score` and `calibrate`: the field, the log and the likelihood field.
#[derive(Args, Debug, Clone)]
pub struct ModelArgs {
    /// The distance-field blob (`beamfield field build`).
    #[arg(long)]
    pub field: PathBuf,
    /// The CARMEN log (FLASER lines with poses).
    #[arg(long)]
    pub log: PathBuf,
    /// The likelihood field's mixture.
    #[command(flatten)]
    pub likelihood: LikelihoodArgs,
    /// The sensor's max-range ("no return") value, metres (default: detected in the log, as
    /// `beamfield log info` reports it).
    #[arg(long = "max-range")]
    pub max_range: Option<f32>,
}

/// Errors of `score` and `calibrate`.
#[derive(Debug)]
#[non_exhaustive]
pub enum ScoreCmdError {
    /// The blob could not be read.
    Io(PathBuf, std::io::Error),
    /// A file that is not a regular file or over its size limit (docs/resource-limits.md).
    Read(crate::input::limits::ReadError),
    /// The blob is malformed.
    Blob(beamfield::field::BlobError),
    /// The log could not be read.
    Log(LogError),
    /// A bad option value.
    Usage(String),
    /// The plot could not be drawn.
    Plot(String),
}

impl std::fmt::Display for ScoreCmdError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Io(p, e) => write!(f, "{}: {e}", p.display()),
            Self::Read(e) => write!(f, "{e}"),
            Self::Blob(e) => write!(
                f,
                "bad field blob: {e}{}",
                crate::input::field_file::blob_hint(e)
            ),
            Self::Log(e) => write!(f, "{e}"),
            Self::Usage(m) => f.write_str(m),
            Self::Plot(m) => write!(f, "plot: {m}"),
        }
    }
}

impl std::error::Error for ScoreCmdError {}

/// A [`ScoreCmdError::Usage`].
pub fn usage(m: impl Into<String>) -> ScoreCmdError {
    ScoreCmdError::Usage(m.into())
}

/// The inputs of `score` and `calibrate`, read and checked.
pub struct Loaded {
    /// The field file.
    pub blob: Vec<u8>,
    /// The log.
    pub log: CarmenLog,
    /// The likelihood field's parameters (with the log's max-range value).
    pub params: LikelihoodParams,
    /// The log's beam layout, centred mount.
    pub layout: BeamLayout<MAX_BEAMS>,
}

/// Reads and checks the field and the log of `m`.
///
/// # Errors
/// [`ScoreCmdError`].
pub fn load(m: &ModelArgs) -> Result<Loaded, ScoreCmdError> {
    let blob = crate::input::limits::read_regular_file(
        &m.field,
        crate::input::limits::MAX_FIELD_FILE_BYTES,
        "field file",
    )
    .map_err(ScoreCmdError::Read)?;
    crate::input::field_file::parse_field_file(&blob).map_err(ScoreCmdError::Blob)?;
    let options = ReadOptions {
        max_range_m: m.max_range,
        ..ReadOptions::default()
    };
    let log = CarmenLog::read_path(&m.log, options).map_err(ScoreCmdError::Log)?;
    if log.scans.is_empty() {
        return Err(usage(format!(
            "{}: no FLASER scans in the log",
            m.log.display()
        )));
    }
    let max_range = log.max_range.value_m().ok_or_else(|| {
        usage("the log's max-range value could not be detected: pass --max-range METRES")
    })?;
    let params = m
        .likelihood
        .params(max_range)
        .map_err(|e| usage(format!("likelihood field parameters: {e}")))?;
    let layout = log
        .layout_with_mount(SensorMount::CENTERED)
        .map_err(|e| usage(format!("beam layout of the log: {e}")))?;
    Ok(Loaded {
        blob,
        log,
        params,
        layout,
    })
}

/// Scan `i` of `log` and its logged pose.
///
/// # Errors
/// [`ScoreCmdError::Usage`] when there is no such scan or it is malformed.
pub fn scan_of(log: &CarmenLog, i: usize) -> Result<(Scan<MAX_BEAMS>, Pose), ScoreCmdError> {
    let s = log
        .scans
        .get(i)
        .ok_or_else(|| usage(format!("scan {i}: the log has {} scans", log.scans.len())))?;
    let scan = s
        .to_scan()
        .map_err(|e| usage(format!("scan {i} (line {}): {e}", s.line)))?;
    Ok((scan, s.pose))
}

/// Parses a pose "X,Y,THETA" (`--pose` of `score` and `field score-variants`).
///
/// # Errors
/// The message for a [`ScoreCmdError::Usage`] (or its `score-variants` twin).
pub fn parse_pose(text: &str) -> Result<Pose, String> {
    let v: Vec<f32> = text
        .split(',')
        .map(|t| t.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--pose {text:?}: expected X,Y,THETA (numbers)"))?;
    match v.as_slice() {
        [x, y, t] if v.iter().all(|a| a.is_finite()) => Ok(Pose::new(*x, *y, *t)),
        _ => Err(format!("--pose {text:?}: expected three finite numbers")),
    }
}
