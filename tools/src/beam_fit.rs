//! Fitting the beam model's intrinsics (Thrun Table 6.2, the crate's EM) to a
//! CARMEN log with known poses, `z*` ray cast through a distance-field blob exactly as the
//! device does it ([`beamfield::RayCaster`]); the CLI is [`crate::cmd::fit`]. Also the map helpers the
//! tests and benches share.

use crate::input::carmen::{CarmenLog, LogError};
use crate::input::map::{Occupancy, OccupancyMap};
use crate::mapping::{build_from_log, GridGeometry, MappingError, MappingOptions, OccupiedCells};
use beamfield::em::{fit_slices, EmConfig, EmError, EmFit, ShapeUpdate, StopReason};
use beamfield::field::{BlobError, FieldView};
use beamfield::{
    BeamFieldModel, BeamIntrinsics, BeamModel, IntrinsicsError, Param, Pose, RayCastError,
    RayCaster, Stride,
};
use clap::{Args, ValueEnum};
use std::path::PathBuf;
use std::time::Instant;

/// Largest number of beams per scan `fit` reads (a `Scan`/`BeamLayout` capacity).
pub const FIT_MAX_BEAMS: usize = 1440;

/// The map_server thresholds used to turn a log-built log-odds grid into a trinary map.
pub const OCCUPIED_THRESH: f64 = 0.65;
/// See [`OCCUPIED_THRESH`].
pub const FREE_THRESH: f64 = 0.196;

impl OccupiedCells for OccupancyMap {
    fn geometry(&self) -> GridGeometry {
        GridGeometry {
            width: self.width as usize,
            height: self.height as usize,
            resolution_m: self.resolution_m,
            origin_x_m: self.origin_x_m,
            origin_y_m: self.origin_y_m,
        }
    }

    fn is_occupied(&self, col: usize, row: usize) -> bool {
        self.cells.get(row * self.width as usize + col) == Some(&Occupancy::Occupied)
    }
}

/// A map built from a log's own poses (the defaults of [`MappingOptions`], 5 cm cells,
/// map_server's thresholds), as `beamfield map from-log` would write it.
///
/// # Errors
/// [`MappingError`] from the mapping code.
pub fn map_from_log(log: &CarmenLog, max_range_m: f32) -> Result<OccupancyMap, MappingError> {
    let (lo, _) = build_from_log(log, &MappingOptions::new(max_range_m), |_, _| {})?;
    Ok(OccupancyMap::from_grid(
        &lo.to_occupancy(OCCUPIED_THRESH, FREE_THRESH),
    ))
}

/// `--lambda`: which σ/λ M-step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum LambdaUpdate {
    /// Table 6.2's closed forms (biased λ for truncated data; not monotone on every data set).
    Textbook,
    /// Truncation-aware, monotone M-step (the default).
    Truncated,
}

/// Largest `fit --iterations`: 10,000 (EM stops at its tolerance within a few dozen on the
/// shared logs; the trace holds one f64 per iteration).
pub const MAX_FIT_ITERATIONS: u32 = 10_000;

/// The options of a fit: which scans and beams, how many iterations, which M-step.
#[derive(Args, Debug, Clone, Copy)]
pub struct FitOptions {
    /// Largest number of EM iterations (M-steps), at most 10,000.
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(..=i64::from(MAX_FIT_ITERATIONS)))]
    pub iterations: u32,
    /// The σ/λ update: `truncated` (monotone, unbiased λ) or `textbook` (Table 6.2).
    #[arg(long, value_enum, default_value_t = LambdaUpdate::Truncated)]
    pub lambda: LambdaUpdate,
    /// Scans to use, `A..B` (0-based, B excluded); default all.
    #[arg(long, value_parser = parse_range)]
    pub scans: Option<(usize, usize)>,
    /// Use every S-th beam of each scan.
    #[arg(long, default_value_t = 1)]
    pub stride: usize,
    /// The sensor's max-range value, metres (default: detected in the log).
    #[arg(long = "max-range")]
    pub max_range: Option<f32>,
}

/// Parses `A..B` (`fit --scans`).
///
/// # Errors
/// A message for clap.
pub fn parse_range(s: &str) -> Result<(usize, usize), String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("`{s}`: expected A..B"))?;
    let a: usize = a.trim().parse().map_err(|e| format!("`{a}`: {e}"))?;
    let b: usize = b.trim().parse().map_err(|e| format!("`{b}`: {e}"))?;
    if a >= b {
        return Err(format!("`{s}`: empty range"));
    }
    Ok((a, b))
}

/// Anything that can go wrong in `beamfield fit`.
#[derive(Debug)]
pub enum FitError {
    /// Reading the blob file.
    Io(PathBuf, std::io::Error),
    /// A file that is not a regular file or over its size limit (docs/resource-limits.md).
    Read(crate::input::limits::ReadError),
    /// The blob is invalid.
    Blob(PathBuf, BlobError),
    /// The blob cannot be ray cast.
    RayCast(RayCastError),
    /// Reading the log.
    Log(LogError),
    /// The log has no max-range value and none was given, or it is invalid.
    Intrinsics(IntrinsicsError),
    /// The log has no scans in the range, or scans longer than [`FIT_MAX_BEAMS`].
    Scans(String),
    /// `--stride 0`.
    BadStride,
    /// `--iterations` above [`MAX_FIT_ITERATIONS`].
    BadIterations(u32),
    /// EM refused to run.
    Em(EmError),
}

impl std::fmt::Display for FitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Io(p, e) => write!(f, "{}: {e}", p.display()),
            Self::Read(e) => write!(f, "{e}"),
            Self::Blob(p, e) => write!(
                f,
                "{}: {e}{}",
                p.display(),
                crate::input::field_file::blob_hint(e)
            ),
            Self::RayCast(e) => write!(f, "blob cannot be ray cast: {e}"),
            Self::Log(e) => write!(f, "{e}"),
            Self::Intrinsics(e) => write!(f, "start intrinsics: {e}"),
            Self::Scans(e) => write!(f, "{e}"),
            Self::BadStride => f.write_str("--stride must be >= 1"),
            Self::BadIterations(n) => {
                write!(f, "--iterations {n}: must be at most {MAX_FIT_ITERATIONS}")
            }
            Self::Em(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for FitError {}

/// The result of [`fit_log`].
#[derive(Clone, Debug)]
pub struct FitReport {
    /// EM's result.
    pub fit: EmFit,
    /// The trace (mean log-likelihood per used beam after 0, 1, … M-steps, nats).
    pub trace: Vec<f64>,
    /// Scans used.
    pub scans: usize,
    /// (z, z*) pairs handed to EM.
    pub pairs: usize,
    /// Time to cast every z*, seconds.
    pub cast_s: f64,
    /// Time EM took, seconds.
    pub em_s: f64,
}

impl FitReport {
    /// The largest decrease between consecutive trace entries (0 when it never decreases).
    pub fn largest_decrease(&self) -> f64 {
        self.trace
            .windows(2)
            .map(|w| w[0] - w[1])
            .fold(0.0, f64::max)
    }
}

/// Casts z* for the chosen scans and beams, then runs EM from AMCL's defaults.
///
/// # Errors
/// [`FitError`] for a bad stride, scans that do not fit, an EM configuration error.
pub fn fit_log(
    view: FieldView<'_>,
    log: &CarmenLog,
    args: &FitOptions,
    mut progress: impl FnMut(usize, usize),
) -> Result<FitReport, FitError> {
    let stride = Stride::new(args.stride).ok_or(FitError::BadStride)?;
    if args.iterations > MAX_FIT_ITERATIONS {
        return Err(FitError::BadIterations(args.iterations));
    }
    let max_range_m = args
        .max_range
        .or(log.max_range.value_m())
        .ok_or(FitError::Intrinsics(IntrinsicsError::NonFinite(
            Param::MaxRange,
        )))?;
    let start = BeamIntrinsics::amcl_defaults(max_range_m).map_err(FitError::Intrinsics)?;
    let caster = RayCaster::new(view).map_err(FitError::RayCast)?;
    let model = BeamFieldModel::new(BeamModel::new(start), caster);
    let n = log
        .beams()
        .ok_or_else(|| FitError::Scans("log has no scans".into()))?;
    if n > FIT_MAX_BEAMS {
        return Err(FitError::Scans(format!(
            "scans have {n} beams, more than {FIT_MAX_BEAMS}"
        )));
    }
    let step = crate::input::carmen::carmen_beam_step_rad(n) as f32;
    let layout = beamfield::BeamLayout::<FIT_MAX_BEAMS>::uniform(
        -core::f32::consts::FRAC_PI_2,
        step,
        n,
        max_range_m,
        beamfield::SensorMount::CENTERED,
    )
    .map_err(|e| FitError::Scans(format!("layout: {e}")))?;
    let (a, b) = args.scans.unwrap_or((0, log.scans.len()));
    let chosen = log.scans.get(a..b.min(log.scans.len())).unwrap_or(&[]);
    if chosen.is_empty() {
        return Err(FitError::Scans(format!(
            "no scans in {a}..{b} (the log has {})",
            log.scans.len()
        )));
    }
    let t0 = Instant::now();
    let (mut z, mut z_star) = (Vec::new(), Vec::new());
    let mut buf = vec![f32::NAN; n];
    for (i, scan) in chosen.iter().enumerate() {
        let pose = Pose {
            x_m: scan.pose.x_m,
            y_m: scan.pose.y_m,
            theta_rad: scan.pose.theta_rad,
        };
        model.cast_layout(&layout, &pose, stride, &mut buf);
        for (&r, &s) in scan.ranges_m.iter().zip(&buf).step_by(stride.get()) {
            z.push(r);
            z_star.push(s);
        }
        if i % 100 == 0 || i + 1 == chosen.len() {
            progress(i + 1, chosen.len());
        }
    }
    let cast_s = t0.elapsed().as_secs_f64();
    let config = EmConfig {
        max_iterations: args.iterations,
        shape_update: match args.lambda {
            LambdaUpdate::Textbook => ShapeUpdate::Textbook,
            LambdaUpdate::Truncated => ShapeUpdate::Truncated,
        },
        ..EmConfig::default()
    };
    let mut trace = vec![0.0f64; args.iterations as usize + 1];
    let t1 = Instant::now();
    let fit = fit_slices(&config, start, &z, &z_star, &mut trace).map_err(FitError::Em)?;
    let em_s = t1.elapsed().as_secs_f64();
    trace.truncate(fit.trace_len);
    Ok(FitReport {
        fit,
        trace,
        scans: chosen.len(),
        pairs: z.len(),
        cast_s,
        em_s,
    })
}

/// The name of why EM stopped, as reported.
pub fn stop_name(s: StopReason) -> String {
    match s {
        StopReason::Converged => "converged".into(),
        StopReason::IterationLimit => "iteration limit".into(),
        StopReason::NoData => "no usable data".into(),
        StopReason::Degenerate(p) => format!("degenerate: {} ran to its bound", p.amcl_name()),
        _ => format!("{s:?}"),
    }
}

/// The fitted intrinsics under their AMCL names, `(name, value)`.
pub fn amcl_pairs(i: &BeamIntrinsics) -> [(&'static str, f32); 7] {
    [
        (Param::ZHit.amcl_name(), i.z_hit()),
        (Param::ZShort.amcl_name(), i.z_short()),
        (Param::ZMax.amcl_name(), i.z_max()),
        (Param::ZRand.amcl_name(), i.z_rand()),
        (Param::SigmaHit.amcl_name(), i.sigma_hit_m()),
        (Param::LambdaShort.amcl_name(), i.lambda_short_per_m()),
        (Param::MaxRange.amcl_name(), i.max_range_m()),
    ]
}
