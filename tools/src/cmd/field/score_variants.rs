//! `beamfield field score-variants`: one scan of a log scored against each state of a map (doors
//! open or closed), and the variant that explains it, if one does ([`crate::blob::variants`]).

use crate::blob::variants::{score_variants, VariantVerdict, MAX_SCORE_VARIANTS};
use crate::blob::FieldError;
use crate::cmd::likelihood::LikelihoodArgs;
use crate::cmd::scored_log::parse_pose;
use crate::input::carmen::{CarmenLog, ReadOptions};
use crate::input::map::{load_map_limited, DEFAULT_MAX_CELLS};
use beamfield::field::DEFAULT_MAX_DIST_M;
use beamfield::{BeamLayout, Pose, Scan, SensorMount};
use clap::Args;
use serde::Serialize;
use std::fmt;
use std::path::{Path, PathBuf};

pub use crate::blob::variants::ScoreVariantsError;

/// Beam capacity of the scans read (CARMEN FLASER scans have 180 or 361 beams).
pub const MAX_BEAMS: usize = 1081;

/// `beamfield field score-variants`: score one scan of a log against each map variant.
#[derive(Args, Debug)]
pub struct ScoreVariantsArgs {
    /// The map variants' YAML files (map_server format), two or more: the same place with
    /// doors open or closed (same size, resolution and origin).
    #[arg(
        long = "variant",
        value_name = "MAP.yaml",
        required = true,
        num_args = 1
    )]
    pub variants: Vec<PathBuf>,
    /// The CARMEN log (FLASER lines with poses).
    #[arg(long)]
    pub log: PathBuf,
    /// Index of the scan in the log (0-based, FLASER lines in file order).
    #[arg(long)]
    pub scan: usize,
    /// Laser pose "X,Y,THETA" (metres, metres, radians); default: the logged pose.
    #[arg(long, allow_hyphen_values = true)]
    pub pose: Option<String>,
    /// The likelihood field's mixture.
    #[command(flatten)]
    pub likelihood: LikelihoodArgs,
    /// The sensor's max-range value, metres (default: detected in the log).
    #[arg(long = "max-range")]
    pub max_range: Option<f32>,
    /// Clamp distance d_max of each variant's field, metres.
    #[arg(long = "max-dist", default_value_t = DEFAULT_MAX_DIST_M)]
    pub max_dist: f32,
    /// A variant is "preferred" only when it beats every other by more than this many nats;
    /// otherwise the scan does not tell them apart.
    #[arg(long, default_value_t = 1.0)]
    pub margin: f32,
}

fn usage(m: impl Into<String>) -> ScoreVariantsError {
    ScoreVariantsError::Usage(m.into())
}

fn name_of(p: &Path) -> String {
    p.display().to_string()
}

/// Runs `beamfield field score-variants`. Progress
/// (one line per variant loaded) goes to stderr.
///
/// # Errors
/// [`ScoreVariantsError`].
pub fn run(a: &ScoreVariantsArgs) -> Result<ScoreVariantsReport, ScoreVariantsError> {
    if a.variants.len() < 2 {
        return Err(ScoreVariantsError::TooFewVariants(a.variants.len()));
    }
    if a.variants.len() > MAX_SCORE_VARIANTS {
        return Err(ScoreVariantsError::TooManyVariants(a.variants.len()));
    }
    if !(a.max_dist.is_finite() && a.max_dist > 0.0) {
        return Err(ScoreVariantsError::Field(FieldError::BadMaxDist(
            a.max_dist,
        )));
    }
    if !(a.margin.is_finite() && a.margin >= 0.0) {
        return Err(usage(format!(
            "--margin {}: must be finite and ≥ 0",
            a.margin
        )));
    }
    let mut maps = Vec::with_capacity(a.variants.len());
    for p in &a.variants {
        crate::progress::note(&format!("score-variants: loading {}", p.display()));
        let m = load_map_limited(p, DEFAULT_MAX_CELLS)
            .map_err(|e| ScoreVariantsError::Field(FieldError::Map(e)))?;
        maps.push((name_of(p), m));
    }
    let options = ReadOptions {
        max_range_m: a.max_range,
        ..ReadOptions::default()
    };
    let log = CarmenLog::read_path(&a.log, options).map_err(ScoreVariantsError::Log)?;
    let max_range = log.max_range.value_m().ok_or_else(|| {
        usage("the log's max-range value could not be detected: pass --max-range METRES")
    })?;
    let params = a
        .likelihood
        .params(max_range)
        .map_err(|e| usage(format!("likelihood field parameters: {e}")))?;
    let layout: BeamLayout<MAX_BEAMS> = log
        .layout_with_mount(SensorMount::CENTERED)
        .map_err(|e| usage(format!("beam layout of the log: {e}")))?;
    let s = log.scans.get(a.scan).ok_or_else(|| {
        usage(format!(
            "--scan {}: the log has {} scans",
            a.scan,
            log.scans.len()
        ))
    })?;
    let scan: Scan<MAX_BEAMS> = s
        .to_scan()
        .map_err(|e| usage(format!("scan {} (line {}): {e}", a.scan, s.line)))?;
    let pose = match &a.pose {
        Some(t) => parse_pose(t).map_err(usage)?,
        None => s.pose,
    };
    crate::progress::note(&format!(
        "score-variants: one distance transform per variant ({} variants)",
        maps.len()
    ));
    let v = score_variants(&maps, a.max_dist, params, &layout, &scan, &pose, a.margin)?;
    Ok(ScoreVariantsReport::new(a, &pose, &v))
}

/// One variant's line of the report.
#[derive(Debug, Serialize)]
pub struct VariantLine {
    /// The variant's file, as given.
    pub map: String,
    /// Log-likelihood of the scan, nats.
    pub log_likelihood_nats: f32,
    /// Beams scored.
    pub beams_scored: usize,
}

/// What `field score-variants` found.
#[derive(Debug, Serialize)]
pub struct ScoreVariantsReport {
    /// The scan's index.
    pub scan: usize,
    /// The pose scored (x m, y m, θ rad).
    pub pose_m_m_rad: [f32; 3],
    /// σ_hit, metres.
    pub sigma_hit_m: f32,
    /// The `--margin`, nats.
    pub margin_nats: f32,
    /// Every variant's score, in the order given.
    pub variants: Vec<VariantLine>,
    /// The variant that beats every other by more than the margin, if one does.
    pub preferred: Option<String>,
    /// Best score minus second best, nats.
    pub lead_nats: f32,
}

impl ScoreVariantsReport {
    fn new(a: &ScoreVariantsArgs, pose: &Pose, v: &VariantVerdict) -> Self {
        Self {
            scan: a.scan,
            pose_m_m_rad: [pose.x_m, pose.y_m, pose.theta_rad],
            sigma_hit_m: a.likelihood.sigma_hit,
            margin_nats: a.margin,
            variants: v
                .scores
                .iter()
                .map(|s| VariantLine {
                    map: s.name.clone(),
                    log_likelihood_nats: s.log_likelihood,
                    beams_scored: s.scored,
                })
                .collect(),
            preferred: v.preferred.map(|i| v.scores[i].name.clone()),
            lead_nats: v.lead_nats,
        }
    }
}

impl fmt::Display for ScoreVariantsReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [x, y, t] = self.pose_m_m_rad;
        writeln!(
            f,
            "scan {} at ({x:.3} m, {y:.3} m, {t:.4} rad), σ_hit {} m:",
            self.scan, self.sigma_hit_m
        )?;
        for s in &self.variants {
            writeln!(
                f,
                "  {}: log-likelihood {:.3} nats ({} beams)",
                s.map, s.log_likelihood_nats, s.beams_scored
            )?;
        }
        match &self.preferred {
            Some(name) => write!(
                f,
                "preferred: {name} (leads the next by {:.3} nats)",
                self.lead_nats
            ),
            None => write!(
                f,
                "no variant preferred: the best leads the next by {:.3} nats, not more than \
                 --margin {} (the likelihood field sees only where beams end, so a door a \
                 scan's endpoints do not come near leaves the scores equal)",
                self.lead_nats, self.margin_nats
            ),
        }
    }
}
