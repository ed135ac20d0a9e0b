//! The race's data, shared by `benches/race.rs`, `tests/race_smoothness.rs` and the race's
//! examples and tests: the Intel lab map's distance-field blob as the demo firmware links it
//! (`firmware/assets/intel.bin`, built from the log by `cargo xtask demo-assets`: 5 cm cells,
//! map_server thresholds, d_max 2 m), real scans of the log with their logged laser poses, and
//! both models' parameters as fitted to this log.

use beamfield::{
    BeamFieldModel, BeamIntrinsics, BeamLayout, BeamModel, FieldView, LikelihoodField,
    LikelihoodParams, Pose, RayCaster, Scan, SensorMount,
};
use beamfield_tools::input::carmen::{CarmenLog, ReadOptions};

/// Beams per FLASER scan of the Intel log.
pub const N: usize = 180;

/// Every this many scans of the 910 is used (91 scans, spread over the whole run).
pub const SCAN_EVERY: usize = 10;

/// σ_hit of both models, metres: the crate's EM fit of the beam model on this log
/// (docs/beam-on-device.md, `laser_sigma_hit` 0.058836), as the demo firmware uses it.
pub const SIGMA_HIT_M: f32 = 0.058836;

/// The log, its layout and the picked scans with their logged (laser) poses.
pub struct RaceData {
    /// The demo blob's bytes.
    pub blob: Vec<u8>,
    /// The log's max-range value, metres (81.83).
    pub max_range_m: f32,
    /// FLASER layout: beam i at −90° + i·1°, no mount offset (the poses are the laser's).
    pub layout: BeamLayout<N>,
    /// `(index in the log, scan, logged pose)`.
    pub scans: Vec<(usize, Scan<N>, Pose)>,
}

/// Reads the blob and the log.
pub fn load() -> RaceData {
    let blob_path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../firmware/assets/intel.bin");
    let blob = std::fs::read(&blob_path).unwrap_or_else(|e| panic!("{}: {e}", blob_path.display()));
    let log_path = host_tests::data_dir().join("laser_intel_lab/intel-corrected.log");
    let log = CarmenLog::read_path(&log_path, ReadOptions::default()).unwrap();
    let max_range_m = log.max_range.value_m().unwrap();
    let layout: BeamLayout<N> = log.layout_with_mount(SensorMount::CENTERED).unwrap();
    let scans = log
        .scans
        .iter()
        .enumerate()
        .step_by(SCAN_EVERY)
        .map(|(i, s)| (i, s.to_scan::<N>().unwrap(), s.pose))
        .collect();
    RaceData {
        blob,
        max_range_m,
        layout,
        scans,
    }
}

/// The beam model's intrinsics as fitted by `beamfield fit` on this log (truncated update,
/// docs/beam-on-device.md). The four weights are renormalized to sum to 1 in f32.
pub fn beam_intrinsics(max_range_m: f32) -> BeamIntrinsics {
    let w = [0.878328f32, 0.057550, 0.023807, 0.040316];
    let s: f32 = w.iter().sum();
    BeamIntrinsics::new(
        w[0] / s,
        w[1] / s,
        w[2] / s,
        w[3] / s,
        SIGMA_HIT_M,
        0.070119,
        max_range_m,
    )
    .unwrap()
}

/// The likelihood field's parameters: AMCL's z_hit 0.95 and z_rand 0.05, σ_hit as fitted (the
/// demo firmware's choice).
pub fn field_params(max_range_m: f32) -> LikelihoodParams {
    LikelihoodParams::new(0.95, 0.05, SIGMA_HIT_M, max_range_m).unwrap()
}

/// Both models over one blob.
pub fn models(data: &RaceData) -> (BeamFieldModel<'_>, LikelihoodField<'_>) {
    let view = FieldView::parse(&data.blob).unwrap();
    let beam = BeamFieldModel::new(
        BeamModel::new(beam_intrinsics(data.max_range_m)),
        RayCaster::new(view).unwrap(),
    );
    let field = LikelihoodField::new(view, field_params(data.max_range_m));
    (beam, field)
}

/// Both models with AMCL's default parameters instead (σ_hit 0.2 m; beam weights 0.95, 0.1,
/// 0.05, 0.05 renormalized, λ_short 0.1/m; field z_hit 0.95, z_rand 0.05): the smoothness
/// comparison at a σ four cells wide.
#[allow(dead_code)]
pub fn models_amcl(data: &RaceData) -> (BeamFieldModel<'_>, LikelihoodField<'_>) {
    let view = FieldView::parse(&data.blob).unwrap();
    let beam = BeamFieldModel::new(
        BeamModel::new(BeamIntrinsics::amcl_defaults(data.max_range_m).unwrap()),
        RayCaster::new(view).unwrap(),
    );
    let field = LikelihoodField::new(
        view,
        LikelihoodParams::amcl_defaults(data.max_range_m).unwrap(),
    );
    (beam, field)
}
