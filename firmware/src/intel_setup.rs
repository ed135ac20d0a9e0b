//! The model and the layout with which the Intel lab log's scans are scored on the device and
//! recomputed on the host: a tempered likelihood field over a distance-field blob, and the log's
//! FLASER layout. Included by the plan files that need them (`lidar_plan.rs`, `track_plan.rs`),
//! so the firmware and the host build them from the same lines.
//!
//! Only `core` and `beamfield`: it compiles for the Cortex-M and the host alike.

use beamfield::{BeamLayout, FieldView, LikelihoodField, LikelihoodParams, SensorMount, Tempered};

/// Beams per FLASER scan of the Intel log.
pub const BEAMS: usize = 180;

/// The likelihood field (`z_hit`, `z_rand`, `sigma_hit_m`, `max_range_m`) over `blob`, tempered
/// by `kappa`. The error names the part that was rejected: the blob, the parameters or the
/// tempering, checked in that order.
pub fn tempered_field(
    blob: &[u8],
    z_hit: f32,
    z_rand: f32,
    sigma_hit_m: f32,
    max_range_m: f32,
    kappa: f32,
) -> Result<Tempered<LikelihoodField<'_>>, &'static str> {
    let view = FieldView::parse(blob).map_err(|_| "map blob rejected")?;
    let params = LikelihoodParams::new(z_hit, z_rand, sigma_hit_m, max_range_m)
        .map_err(|_| "likelihood parameters rejected")?;
    Tempered::new(LikelihoodField::new(view, params), kappa, 1).map_err(|_| "tempering rejected")
}

/// The Intel log's layout: [`BEAMS`] beams from −90° in 1° steps, counter-clockwise, sensor at
/// the robot's centre (the logged poses are laser poses), up to `max_range_m`.
pub fn layout(max_range_m: f32) -> Result<BeamLayout<BEAMS>, &'static str> {
    BeamLayout::<BEAMS>::uniform(
        -core::f32::consts::FRAC_PI_2,
        core::f32::consts::PI / BEAMS as f32,
        BEAMS,
        max_range_m,
        SensorMount::CENTERED,
    )
    .map_err(|_| "beam layout rejected")
}
