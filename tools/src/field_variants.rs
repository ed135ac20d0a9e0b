//! `beamfield field score-variants`: which state of a map (doors open or closed) explains a
//! scan. One distance transform per variant, the scan scored against each field at one pose
//! (Probabilistic Robotics, chapter 6, exercises: "one transform per variant"), the variants
//! ranked by log-likelihood. The per-cell minimum field (`field build --variant`) is what a
//! localizer carries; this is the question it cannot answer.

use crate::field_cmd::{build_blob, FieldCmdError};
use crate::input::carmen::{CarmenLog, LogError, ReadOptions};
use crate::input::map::{load_map_limited, OccupancyMap, DEFAULT_MAX_CELLS};
use beamfield::field::{FieldView, LikelihoodField, LikelihoodParams, DEFAULT_MAX_DIST_M};
use beamfield::{BeamLayout, Pose, Scan, SensorMount};
use clap::Args;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Most `--variant` maps `score-variants` takes: 16. Every variant is held with its field (about
/// 2 bytes per cell), so 16 maps at the default cell limit (16.8 M cells) stay near 540 MB.
pub const MAX_SCORE_VARIANTS: usize = 16;

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
    /// σ_hit of the likelihood field, metres.
    #[arg(long = "sigma-hit", default_value_t = 0.05)]
    pub sigma_hit: f32,
    /// z_hit weight.
    #[arg(long = "z-hit", default_value_t = 0.95)]
    pub z_hit: f32,
    /// z_rand weight.
    #[arg(long = "z-rand", default_value_t = 0.05)]
    pub z_rand: f32,
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

/// Why variants could not be scored.
#[derive(Debug)]
#[non_exhaustive]
pub enum ScoreVariantsError {
    /// Fewer than two variants.
    TooFewVariants(usize),
    /// More than [`MAX_SCORE_VARIANTS`] variants.
    TooManyVariants(usize),
    /// A variant could not be loaded, or its field built.
    Field(FieldCmdError),
    /// The log could not be read.
    Log(LogError),
    /// A bad option or an unusable scan (the message says which).
    Usage(String),
}

impl std::fmt::Display for ScoreVariantsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::TooFewVariants(n) => {
                write!(f, "{n} variant(s) given: pass at least two --variant maps")
            }
            Self::TooManyVariants(n) => write!(
                f,
                "{n} variants given: at most {MAX_SCORE_VARIANTS} (each is held in memory with \
                 its field)"
            ),
            Self::Field(e) => write!(f, "{e}"),
            Self::Log(e) => write!(f, "{e}"),
            Self::Usage(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for ScoreVariantsError {}

fn usage(m: impl Into<String>) -> ScoreVariantsError {
    ScoreVariantsError::Usage(m.into())
}

/// One variant's score.
#[derive(Clone, Debug, PartialEq)]
pub struct VariantScore {
    /// The variant's name (its file name as given).
    pub name: String,
    /// Log-likelihood of the scan at the pose, nats.
    pub log_likelihood: f32,
    /// Beams scored.
    pub scored: usize,
}

/// What `score-variants` found.
#[derive(Clone, Debug, PartialEq)]
pub struct VariantVerdict {
    /// Every variant's score, in the order given.
    pub scores: Vec<VariantScore>,
    /// Index of the variant that beats every other by more than the margin, if one does.
    pub preferred: Option<usize>,
    /// Best score minus second best, nats.
    pub lead_nats: f32,
}

/// Scores `scan` at `pose` against each map of `variants` (one transform each, `max_dist_m`)
/// and names the variant that beats every other by more than `margin_nats`, if any.
///
/// # Errors
/// [`ScoreVariantsError::TooFewVariants`], [`ScoreVariantsError::Field`] (a variant of another
/// geometry than the first, or a map the blob cannot hold).
pub fn score_variants<const N: usize>(
    variants: &[(String, OccupancyMap)],
    max_dist_m: f32,
    params: LikelihoodParams,
    layout: &BeamLayout<N>,
    scan: &Scan<N>,
    pose: &Pose,
    margin_nats: f32,
) -> Result<VariantVerdict, ScoreVariantsError> {
    let Some((_, first)) = variants.first() else {
        return Err(ScoreVariantsError::TooFewVariants(0));
    };
    if variants.len() < 2 {
        return Err(ScoreVariantsError::TooFewVariants(variants.len()));
    }
    let mut scores = Vec::with_capacity(variants.len());
    for (name, map) in variants {
        if (map.width, map.height) != (first.width, first.height)
            || map.resolution_m != first.resolution_m
            || map.origin_x_m != first.origin_x_m
            || map.origin_y_m != first.origin_y_m
        {
            return Err(ScoreVariantsError::Field(FieldCmdError::VariantMismatch(
                PathBuf::from(name),
            )));
        }
        let blob = build_blob(map, max_dist_m).map_err(ScoreVariantsError::Field)?;
        let view = FieldView::parse(&blob)
            .map_err(|e| ScoreVariantsError::Field(FieldCmdError::Header(e)))?;
        let s = LikelihoodField::new(view, params).score(layout, scan, pose);
        scores.push(VariantScore {
            name: name.clone(),
            log_likelihood: s.log_likelihood,
            scored: usize::from(s.scored),
        });
    }
    let mut order: Vec<usize> = (0..scores.len()).collect();
    order.sort_by(|&a, &b| {
        scores[b]
            .log_likelihood
            .total_cmp(&scores[a].log_likelihood)
    });
    let lead = scores[order[0]].log_likelihood - scores[order[1]].log_likelihood;
    Ok(VariantVerdict {
        preferred: (lead > margin_nats).then_some(order[0]),
        lead_nats: lead,
        scores,
    })
}

fn parse_pose(text: &str) -> Result<Pose, ScoreVariantsError> {
    let v: Vec<f32> = text
        .split(',')
        .map(|t| t.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| usage(format!("--pose {text:?}: expected X,Y,THETA (numbers)")))?;
    match v.as_slice() {
        [x, y, t] if v.iter().all(|a| a.is_finite()) => Ok(Pose::new(*x, *y, *t)),
        _ => Err(usage(format!(
            "--pose {text:?}: expected three finite numbers"
        ))),
    }
}

fn name_of(p: &Path) -> String {
    p.display().to_string()
}

/// Runs `beamfield field score-variants`; returns the text (or JSON) to print. Progress
/// (one line per variant loaded) goes to stderr.
///
/// # Errors
/// [`ScoreVariantsError`].
pub fn run_score_variants(a: &ScoreVariantsArgs, json: bool) -> Result<String, ScoreVariantsError> {
    if a.variants.len() < 2 {
        return Err(ScoreVariantsError::TooFewVariants(a.variants.len()));
    }
    if a.variants.len() > MAX_SCORE_VARIANTS {
        return Err(ScoreVariantsError::TooManyVariants(a.variants.len()));
    }
    if !(a.max_dist.is_finite() && a.max_dist > 0.0) {
        return Err(ScoreVariantsError::Field(FieldCmdError::BadMaxDist(
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
            .map_err(|e| ScoreVariantsError::Field(FieldCmdError::Map(e)))?;
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
    let params = LikelihoodParams::new(a.z_hit, a.z_rand, a.sigma_hit, max_range)
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
        Some(t) => parse_pose(t)?,
        None => s.pose,
    };
    crate::progress::note(&format!(
        "score-variants: one distance transform per variant ({} variants)",
        maps.len()
    ));
    let v = score_variants(&maps, a.max_dist, params, &layout, &scan, &pose, a.margin)?;
    let mut out = String::new();
    if json {
        out = serde_json::json!({
            "scan": a.scan,
            "pose_m_m_rad": [pose.x_m, pose.y_m, pose.theta_rad],
            "sigma_hit_m": a.sigma_hit,
            "margin_nats": a.margin,
            "variants": v.scores.iter().map(|s| serde_json::json!({
                "map": s.name,
                "log_likelihood_nats": s.log_likelihood,
                "beams_scored": s.scored,
            })).collect::<Vec<_>>(),
            "preferred": v.preferred.map(|i| v.scores[i].name.clone()),
            "lead_nats": v.lead_nats,
        })
        .to_string();
    } else {
        let _ = writeln!(
            out,
            "scan {} at ({:.3} m, {:.3} m, {:.4} rad), σ_hit {} m:",
            a.scan, pose.x_m, pose.y_m, pose.theta_rad, a.sigma_hit
        );
        for s in &v.scores {
            let _ = writeln!(
                out,
                "  {}: log-likelihood {:.3} nats ({} beams)",
                s.name, s.log_likelihood, s.scored
            );
        }
        match v.preferred {
            Some(i) => {
                let _ = write!(
                    out,
                    "preferred: {} (leads the next by {:.3} nats)",
                    v.scores[i].name, v.lead_nats
                );
            }
            None => {
                let _ = write!(
                    out,
                    "no variant preferred: the best leads the next by {:.3} nats, not more than \
                     --margin {} (the likelihood field sees only where beams end, so a door a \
                     scan's endpoints do not come near leaves the scores equal)",
                    v.lead_nats, a.margin
                );
            }
        }
    }
    Ok(out)
}
