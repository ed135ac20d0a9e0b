//! The math façade's documented error bounds (the table in `src/math/mod.rs`, asserted by
//! `tests/math_backend.rs`) for the backend this build of the tests uses, so that a test's
//! tolerance comes from the backend it runs against instead of assuming libm's accuracy.
//!
//! The host tests' `micromath` feature selects the crate's `micromath` backend (its `sin_cos`
//! and `atan2`); everything else always comes from libm.

/// The documented maximum absolute error of `beamfield::math::sin_cos` on [−2π, 2π], for
/// (the default backend, the `micromath` backend). Each of sine and cosine is within it.
pub const SIN_COS_ABS_BOUNDS: (f64, f64) = (6.4e-8, 1.1e-3);

/// The bound of [`SIN_COS_ABS_BOUNDS`] for the backend of this build.
pub const SIN_COS_ABS_ERROR: f64 = if cfg!(feature = "micromath") {
    SIN_COS_ABS_BOUNDS.1
} else {
    SIN_COS_ABS_BOUNDS.0
};

/// The part of [`SIN_COS_ABS_ERROR`] beyond one f32 rounding of a value of magnitude ≤ 1
/// (2^−24): the part a tolerance that already counts each sine and cosine as one rounding has
/// not yet budgeted. About 4e-9 for the default backend, 1.1e-3 for micromath.
pub const SIN_COS_EXCESS: f64 = {
    let e = SIN_COS_ABS_ERROR - 1.0 / 16_777_216.0;
    if e > 0.0 {
        e
    } else {
        0.0
    }
};
