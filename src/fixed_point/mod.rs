//! The likelihood field (Thrun Table 6.3, docs/models.md#field) in fixed point, for MCUs without an
//! FPU (Cortex-M0/M0+, Cortex-M3, rv32imc). Behind the `fixed` feature.
//!
//! The scorer reads the same [`FieldView`](crate::field::FieldView) blob as the f32
//! [`LikelihoodField`](crate::field::LikelihoodField) and reproduces its score with integer
//! arithmetic only: no floating-point operation per beam and none per pose. Floats are used
//! only where a parameter set, a layout or a scan is converted (see "Where floats remain").
//!
//! # Q formats
//! | quantity | format | range | resolution |
//! |---|---|---|---|
//! | pose / mount position, map origin | `I16F16` metres | ±32 768 m | 15.3 µm |
//! | pose heading | `I16F16` radians | any (reduced) | 15.3 µrad |
//! | pose / mount cos, sin ([`sin_cos_q30`]) | Q2.30 (`i32`) | ±2 | 9.3e-10 |
//! | sensor heading, beam unit vectors in the loop | Q1.15 (`i32`) | ±1 | 3.1e-5 |
//! | range | Q11.8 cells (`i32`, < 2¹⁹) | < 2 048 cells | 1/256 cell |
//! | endpoint, sensor position | Q.8 cells (`i32`) | ±2²³ cells | 1/256 cell |
//! | per-code log term | `I16F16` nats | ±32 768 | 1.5e-5 (rounded: error ≤ 2⁻¹⁷) |
//! | scan sum, tempered score | `I48F16` nats | see [`MAX_FIXED_BEAMS`] | 1.5e-5 |
//! | κ | `I16F16`, `0 < κ ≤ 1` | | 1.5e-5 |
//!
//! # Where floats remain
//! - [`FixedField::new`]: the 256 f32 terms of the f32 table are rounded to `I16F16` (once per
//!   parameter set), and the blob's origin and cell size are converted (once per blob).
//! - [`FixedLayout::new`]: the beam unit vectors and the mount, once per layout.
//! - [`FixedScan::from_scan`]: one f32 multiply, one compare and one conversion per reading,
//!   once per scan (not per pose): on a Cortex-M0 about 3 soft-float calls per reading. A driver
//!   that delivers integer millimetres skips this with [`FixedScan::from_ranges_mm`] (one
//!   integer multiply per reading).
//! - [`FixedPose::from_pose`] is a convenience for the host; on the device
//!   [`FixedPose::new`] takes the heading in `I16F16` radians and computes cos/sin with the
//!   integer [`sin_cos_q30`] (error below 7e-8, 5.7e-8 measured, plus the angle's 15 µrad
//!   quantization).

mod scorer;

/// The integer sine and cosine live in the math module (`crate::math`, with the crate's other
/// elementary functions); re-exported here beside the scorer that uses them.
pub use crate::math::sin_cos_q30;
pub use scorer::{
    FixedError, FixedField, FixedLayout, FixedPose, FixedScan, FixedScore, MAX_FIXED_BEAMS,
    MAX_RANGE_CELLS,
};

/// Signed Q16.16: metres, radians, nats.
pub type I16F16 = fixed::types::I16F16;
/// Signed Q48.16: the scan's log-likelihood sum, nats.
pub type I48F16 = fixed::types::I48F16;
