//! The geometry check shared by the grids stored in a blob (the distance field's header and the
//! free-space section's grid): size, cell size and origin, each grid mapping a fault to its own
//! error type.
//!
//! Layering: this module sits just above `layout` and imports nothing else of `src/field/`; each
//! grid's module implements the conversion of [`GridFault`] into its own error type with
//! [`from_grid_fault`].

use super::layout::BLOB_MAX_SIDE;

/// What a grid's geometry can get wrong, in the order it is checked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum GridFault {
    /// A width or height of 0.
    ZeroSize,
    /// A side over [`BLOB_MAX_SIDE`], or a cell count the caller cannot hold.
    TooLarge,
    /// A cell size that is not finite and positive, or whose inverse is not finite.
    BadCellSize,
    /// An origin, or a far corner, that is not finite.
    BadOrigin,
}

/// Checks a `width` × `height` grid of `cell_size_m` cells whose lower-left corner is at
/// (`origin_x_m`, `origin_y_m`) metres: the sides, then the cell count `cells(width, height)`
/// gives (`None`: too large), then the cell size, then both corners. Returns the cell count.
pub(crate) fn check_grid<C>(
    width: u32,
    height: u32,
    cell_size_m: f32,
    origin_x_m: f32,
    origin_y_m: f32,
    cells: impl FnOnce(u32, u32) -> Option<C>,
) -> Result<C, GridFault> {
    if width == 0 || height == 0 {
        return Err(GridFault::ZeroSize);
    }
    if width > BLOB_MAX_SIDE || height > BLOB_MAX_SIDE {
        return Err(GridFault::TooLarge);
    }
    let count = cells(width, height).ok_or(GridFault::TooLarge)?;
    let cs = cell_size_m;
    if !(cs.is_finite() && cs > 0.0 && (1.0 / cs).is_finite()) {
        return Err(GridFault::BadCellSize);
    }
    let far_x = origin_x_m + width as f32 * cs;
    let far_y = origin_y_m + height as f32 * cs;
    if !(origin_x_m.is_finite() && origin_y_m.is_finite() && far_x.is_finite() && far_y.is_finite())
    {
        return Err(GridFault::BadOrigin);
    }
    Ok(count)
}

/// `From<GridFault>` for error types that have a variant of the same name for every fault
/// (invoked by each grid's module on its own error type).
macro_rules! from_grid_fault {
    ($($error:ty),+) => {$(
        impl From<GridFault> for $error {
            fn from(f: GridFault) -> Self {
                match f {
                    GridFault::ZeroSize => Self::ZeroSize,
                    GridFault::TooLarge => Self::TooLarge,
                    GridFault::BadCellSize => Self::BadCellSize,
                    GridFault::BadOrigin => Self::BadOrigin,
                }
            }
        }
    )+};
}
pub(crate) use from_grid_fault;
