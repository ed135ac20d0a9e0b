//! What the Willow Garage program computes (`src/bin/willow.rs`), shared word for word with the
//! host's check of it (`cargo xtask willow` recomputes it with this module and the same crate
//! on the same blob, and compares every printed score bit for bit).
//!
//! The Willow map has no laser log, so the scan is made on the device: 180 beams cast through
//! the blob from [`CENTRE`] (`RayCaster`), then scored by the likelihood field at a grid of
//! poses around it three ways: through a `PreparedScan` (the fast path), through
//! `LikelihoodField::score` (the per-pose path) and by the fixed-point scorer
//! (`beamfield::fixed_point`, integer arithmetic only; the library's `fixed` feature).
//!
//! Only `core` and `beamfield`: it compiles for the Cortex-M and the host alike.

use beamfield::fixed_point::{FixedField, FixedLayout, FixedPose, FixedScan};
use beamfield::{
    BeamLayout, FieldView, LikelihoodField, LikelihoodParams, Pose, RayCaster, Scan, SensorMount,
};

/// Beams of the simulated scan (1° apart over 180°).
pub const BEAMS: usize = 180;
/// The simulated lidar's maximum range, metres.
pub const MAX_RANGE_M: f32 = 20.0;
/// Where the scan is cast from: a free cell near the map's middle, 1.1 m from the nearest
/// wall (cell (537, 464) of the 5 cm map), heading 0.3 rad.
pub const CENTRE: [f32; 3] = [26.875, 23.225, 0.3];
/// Poses scored: 5 × 5 offsets of 5 cm in x and y, 5 headings 2° apart.
pub const POSES: usize = 125;

/// Pose `i` of the grid around [`CENTRE`] (x fastest, then y, then heading).
pub fn pose(i: usize) -> Pose {
    let ix = (i % 5) as f32 - 2.0;
    let iy = ((i / 5) % 5) as f32 - 2.0;
    let it = (i / 25) as f32 - 2.0;
    Pose::new(
        CENTRE[0] + 0.05 * ix,
        CENTRE[1] + 0.05 * iy,
        CENTRE[2] + (2.0 * it).to_radians(),
    )
}

/// Why the plan could not run (each is a rejected input).
#[derive(Clone, Copy, Debug)]
pub enum PlanError {
    /// The blob did not parse.
    Blob,
    /// The ray caster, layout, scan or parameters were rejected.
    Setup,
}

/// One pose's scores: prepared path, per-pose path (f32 bits) and fixed-point (`I48F16` bits).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Scores {
    /// `PreparedScan::score`, f32 bits.
    pub prepared: u32,
    /// `LikelihoodField::score`, f32 bits.
    pub per_pose: u32,
    /// `FixedField::score`, the `I48F16` sum's bits.
    pub fixed: i64,
}

/// Casts the scan from [`CENTRE`] and scores it at every pose into `scores`; returns the
/// blob's encoding and the number of beams kept.
///
/// # Errors
/// [`PlanError`].
pub fn run(blob: &[u8], scores: &mut [Scores; POSES]) -> Result<(u8, usize), PlanError> {
    let view = FieldView::parse(blob).map_err(|_| PlanError::Blob)?;
    let caster = RayCaster::new(view).map_err(|_| PlanError::Setup)?;
    let layout = BeamLayout::<BEAMS>::uniform(
        -core::f32::consts::FRAC_PI_2,
        core::f32::consts::PI / BEAMS as f32,
        BEAMS,
        MAX_RANGE_M,
        SensorMount::CENTERED,
    )
    .map_err(|_| PlanError::Setup)?;
    let mut ranges = [0.0f32; BEAMS];
    for (r, b) in ranges.iter_mut().zip(layout.beams()) {
        *r = caster.cast(CENTRE[0], CENTRE[1], CENTRE[2] + b.bearing_rad, MAX_RANGE_M);
    }
    let scan = Scan::<BEAMS>::from_ranges(&ranges).map_err(|_| PlanError::Setup)?;
    let params = LikelihoodParams::amcl_defaults(MAX_RANGE_M).map_err(|_| PlanError::Setup)?;
    let field = LikelihoodField::new(view, params);
    let prepared = field.prepare(&layout, &scan);
    let fixed = FixedField::new(&field).map_err(|_| PlanError::Setup)?;
    let fixed_layout = FixedLayout::new(&layout).map_err(|_| PlanError::Setup)?;
    let fixed_scan = FixedScan::from_scan(&scan, &fixed);
    for (i, s) in scores.iter_mut().enumerate() {
        let p = pose(i);
        let fp = FixedPose::from_pose(&p).map_err(|_| PlanError::Setup)?;
        *s = Scores {
            prepared: prepared.score(&p).log_likelihood.to_bits(),
            per_pose: field.score(&layout, &scan, &p).log_likelihood.to_bits(),
            fixed: fixed
                .score(&fixed_layout, &fixed_scan, &fp)
                .log_likelihood
                .to_bits(),
        };
    }
    Ok((view.encoding(), prepared.len()))
}
