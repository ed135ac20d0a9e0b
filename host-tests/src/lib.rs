//! Host-side reference and helpers for testing `beamfield`.
//!
//! [`reference`] is an f64 implementation written straight from `shared/design/models.md`,
//! independent of the crate's f32 code: it shares no function with it (std's f64 math, not the
//! crate's math façade), so an error in one is not silently copied into the other.

pub mod reference;
