#![doc = include_str!("../README.md")]
#![cfg_attr(not(test), no_std)]

pub mod beam;
pub mod beam_field;
mod build_info;
pub mod correlation;
pub mod diagnostic;
pub mod em;
mod error;
pub mod field;
#[cfg(feature = "fixed")]
pub mod fixed_point;
pub mod gaussian;
pub mod intrinsics;
pub mod landmark;
pub mod lidar;
pub mod math;
pub mod mcl;
pub mod model;
pub mod pose;
pub mod raycast;
pub mod scan;
pub mod sonar;
pub mod tempered;
#[cfg(test)]
mod test_rng;
// With `micromath`, its sin/cos are used instead and this module only runs its tests.
#[cfg_attr(feature = "micromath", allow(dead_code))]
mod trig;

pub use beam::{BeamModel, Components, BEAM_LOG_FLOOR};
pub use beam_field::BeamFieldModel;
pub use build_info::{BuildInfo, BUILD_INFO};
pub use correlation::{
    Correlation, CorrelationError, MapCorrelation, CORRELATION_EPSILON, MAX_WINDOW_CELLS,
};
pub use diagnostic::Lag1;
pub use error::Error;
pub use field::{
    edt_scratch_len, emit_blob, emit_blob_from_squared_cells, emit_blob_tiled,
    emit_blob_tiled_clamped, squared_edt, tiled_max_len, tiled_scratch_len, BlobError, EdtError,
    EdtScratch, FieldHeader, FieldView, LikelihoodError, LikelihoodField, LikelihoodParam,
    LikelihoodParams, PreparedScan, DEFAULT_MAX_DIST_M, EDT_INFINITY,
};
pub use intrinsics::{BeamIntrinsics, IntrinsicsError, Param};
pub use landmark::{
    Feature, FeatureNoise, IntersectionError, Landmark, LandmarkError, TwoFeaturePoses,
};
pub use model::{SensorModel, Stride};
pub use pose::{wrap_angle, Pose, SensorMount};
pub use raycast::{CastTrace, RayCastError, RayCaster};
pub use scan::{Beam, BeamLayout, Reading, Scan, ScanError, ScanScore};
pub use tempered::{
    effective_sample_size, normalize_log_weights, NormalizeError, Normalized, TemperError,
    Tempered, TemperedScan,
};
