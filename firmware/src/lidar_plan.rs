//! What the LiDAR sensor path computes once a scan is assembled, shared word for word by the
//! firmware (`src/bin/lidar_uart.rs`) and the host's recomputation of it (`cargo xtask lidar`,
//! `xtask/src/lidar_ref.rs`), so the two can be compared to the printed digits.
//!
//! Only `core` and `beamfield`: it compiles for the Cortex-M and the host alike. It uses the
//! demo's model and pose grid (`demo_plan.rs`, included beside it as `super::demo_plan`), the
//! Intel log's model and layout (`intel_setup.rs`), and holds the log segment the stream is
//! made of (`assets/lidar_segment.rs`).

use super::demo_plan::{COARSE, KAPPA, POSES, SIGMA_HIT_M, Z_HIT, Z_RAND};
use beamfield::lidar::{AssemblerConfig, AssemblerError, ScanAssembler};
use beamfield::{
    normalize_log_weights, BeamLayout, LikelihoodField, NormalizeError, Pose, Scan, Tempered,
};

#[path = "intel_setup.rs"]
mod intel_setup;
pub use intel_setup::BEAMS;

/// One real scan of the log with its logged (corrected) laser pose
/// (`firmware/assets/lidar_segment.rs`).
pub struct DemoScan {
    /// Index of the FLASER line in the log.
    pub log_index: u32,
    /// Logged laser pose `[x_m, y_m, theta_rad]`.
    pub pose: [f32; 3],
    /// The 180 ranges, metres (the log's max-range value means "no return").
    pub ranges_m: [f32; BEAMS],
}

/// The log's scans sent as the stream: `SCANS` and the log's `MAX_RANGE_M` (generated; a range
/// of 3.14 m is not π).
#[allow(clippy::approx_constant)]
pub mod segment {
    use super::DemoScan;
    include!("../assets/lidar_segment.rs");
}

/// The model and the layout the scans are scored with.
pub struct Setup<'a> {
    /// The tempered likelihood field over the linked distance-field blob.
    pub tempered: Tempered<LikelihoodField<'a>>,
    /// The Intel log's layout: 180 beams from −90° in 1° steps, counter-clockwise, sensor at the
    /// robot's centre (the logged poses are laser poses).
    pub layout: BeamLayout<BEAMS>,
}

/// Builds the model and layout: the demo's likelihood field (σ_hit, z_hit, z_rand, κ) over
/// `blob`, and the Intel layout with `max_range_m`. The error names the part that was
/// rejected.
pub fn setup(blob: &[u8], max_range_m: f32) -> Result<Setup<'_>, &'static str> {
    let tempered =
        intel_setup::tempered_field(blob, Z_HIT, Z_RAND, SIGMA_HIT_M, max_range_m, KAPPA)?;
    let layout = intel_setup::layout(max_range_m)?;
    Ok(Setup { tempered, layout })
}

/// The assembler for the Intel layout: every valid point up to the layout's maximum range.
pub fn assembler(setup: &Setup<'_>) -> Result<ScanAssembler<BEAMS>, AssemblerError> {
    ScanAssembler::new(&setup.layout, AssemblerConfig::for_layout(&setup.layout))
}

/// How an assembled scan compares with the log's ranges of the same scan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LogMatch {
    /// Beams equal to the log's range to the LD06's resolution (1 mm), or empty where the log
    /// has no return (its max-range value).
    pub matching: u16,
    /// Beams empty where the log has a range: their points were in a frame dropped for its
    /// checksum.
    pub missing: u16,
    /// Beams with a range the log does not have there (an assembler that bins into the wrong
    /// beam, or a point from a corrupted frame).
    pub wrong: u16,
}

/// Compares `scan` with `log_ranges_m` beam by beam. An LD06 distance is whole millimetres, so
/// a range that survived the trip differs from the log's by at most half a millimetre (plus
/// f32 rounding).
pub fn compare(scan: &Scan<BEAMS>, log_ranges_m: &[f32; BEAMS], max_range_m: f32) -> LogMatch {
    let mut m = LogMatch::default();
    let got = scan.ranges_m();
    for i in 0..BEAMS {
        let log = log_ranges_m.get(i).copied().unwrap_or(f32::NAN);
        let r = got.get(i).copied().unwrap_or(f32::NAN);
        let no_return = log >= max_range_m;
        if r.is_nan() {
            if no_return {
                m.matching += 1;
            } else {
                m.missing += 1;
            }
        } else if !no_return && (r - log).abs() <= 0.0005 + 1e-5 {
            m.matching += 1;
        } else {
            m.wrong += 1;
        }
    }
    m
}

/// What one assembled scan scored.
#[derive(Clone, Copy, Debug)]
pub struct Scored {
    /// Beams the likelihood field scored (not empty, not max-range).
    pub valid: u16,
    /// The best pose of the demo's coarse grid around the logged pose.
    pub best: Pose,
    /// The tempered log-likelihood at `best`, nats.
    pub log_likelihood: f32,
    /// Effective sample size of the grid's normalized weights.
    pub ess: f32,
}

/// Scores `scan` at every pose of the demo's coarse grid around `logged` (17 × 17 × 21
/// hypotheses, ±20 cm, ±5°) into `weights`, normalizes them in place, and returns the best.
///
/// # Errors
/// When the weights cannot be normalized (no finite score).
pub fn score(
    setup: &Setup<'_>,
    scan: &Scan<BEAMS>,
    logged: &Pose,
    weights: &mut [f32; POSES],
) -> Result<Scored, NormalizeError> {
    let prepared = setup.tempered.prepare(&setup.layout, scan);
    for (i, w) in weights.iter_mut().enumerate() {
        *w = prepared.score(&COARSE.pose(logged, i)).log_likelihood;
    }
    let norm = normalize_log_weights(weights)?;
    let best = COARSE.pose(logged, norm.best);
    let at_best = prepared.score(&best);
    Ok(Scored {
        valid: at_best.scored,
        best,
        log_likelihood: at_best.log_likelihood,
        ess: norm.ess,
    })
}
