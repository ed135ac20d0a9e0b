//! Map variants (doors open or closed): which state of a map explains a scan. One distance
//! transform per variant, the scan scored against each field at one pose (Probabilistic
//! Robotics, chapter 6, exercises: "one transform per variant"), the variants ranked by
//! log-likelihood. The per-cell minimum field (`field build --variant`, [`super::union_map`]) is
//! what a localizer carries; this is the question it cannot answer.

use super::{build_blob, same_geometry, FieldError};
use crate::input::carmen::LogError;
use crate::input::map::OccupancyMap;
use beamfield::field::{FieldView, LikelihoodField, LikelihoodParams};
use beamfield::{BeamLayout, Pose, Scan};
use std::path::PathBuf;

/// Most `--variant` maps `score-variants` takes: 16. Every variant is held with its field (about
/// 2 bytes per cell), so 16 maps at the default cell limit (16.8 M cells) stay near 540 MB.
pub const MAX_SCORE_VARIANTS: usize = 16;

/// Why variants could not be scored.
#[derive(Debug)]
#[non_exhaustive]
pub enum ScoreVariantsError {
    /// Fewer than two variants.
    TooFewVariants(usize),
    /// More than [`MAX_SCORE_VARIANTS`] variants.
    TooManyVariants(usize),
    /// A variant could not be loaded, or its field built.
    Field(FieldError),
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
        if !same_geometry(map, first) {
            return Err(ScoreVariantsError::Field(FieldError::VariantMismatch(
                PathBuf::from(name),
            )));
        }
        let blob = build_blob(map, max_dist_m).map_err(ScoreVariantsError::Field)?;
        let view = FieldView::parse(&blob)
            .map_err(|e| ScoreVariantsError::Field(FieldError::Header(e)))?;
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
