//! Why a map could not be built from a log ([`MappingError`]), with the limits it names.

/// Errors building a map.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum MappingError {
    /// The log has no scan with a valid reading.
    NoData,
    /// An option is out of range (resolution or margin ≤ 0 or not finite, increments of the
    /// wrong sign, clamps not around 0, max range not positive).
    BadOptions,
    /// The extent at this resolution needs more than [`MappingOptions::max_cells`](super::MappingOptions::max_cells) cells.
    TooLarge {
        /// Cells along x.
        width: u64,
        /// Cells along y.
        height: u64,
        /// The limit, cells.
        max_cells: u64,
    },
    /// The map lies so far from the origin that f64 coordinates there are spaced more than
    /// [`MAX_COORDINATE_ULP_CELLS`] of a cell apart: cells could not be told apart reliably.
    Imprecise {
        /// The largest coordinate magnitude of the map (its extent with the margin), metres.
        magnitude_m: f64,
        /// The spacing of f64 values at that magnitude, metres.
        spacing_m: f64,
        /// The resolution asked for, metres.
        resolution_m: f64,
    },
}

/// Largest spacing of f64 coordinates allowed at the map's farthest point, as a fraction of
/// a cell: 1/1024. The builder computes cells from world coordinates in f64
/// (`(x − origin) / resolution`), so a coordinate is off by up to this spacing; at 1/1024 of
/// a cell, only end points within a thousandth of a cell from a cell edge can land in the
/// neighbouring cell. At 0.05 m cells this allows coordinates up to 2³⁸ m (2.7·10¹¹ m).
pub const MAX_COORDINATE_ULP_CELLS: f64 = 1.0 / 1024.0;

/// The spacing of f64 values at magnitude `m` (its unit in the last place).
pub(super) fn f64_spacing(m: f64) -> f64 {
    let m = m.abs();
    if !m.is_finite() {
        return f64::INFINITY;
    }
    let next = f64::from_bits(m.to_bits() + 1);
    next - m
}

/// Largest [`MappingOptions::max_cells`](super::MappingOptions::max_cells) (2²⁸ cells, 1 GiB of log-odds, 3.2 GiB in all).
pub const MAX_CELLS: u64 = 1 << 28;

impl std::fmt::Display for MappingError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NoData => f.write_str("the log has no scan with a valid reading"),
            Self::BadOptions => f.write_str("mapping options out of range"),
            Self::TooLarge {
                width,
                height,
                max_cells,
            } => write!(
                f,
                "map of {width} × {height} = {} cells is over the limit of {max_cells}; use a \
                 coarser resolution (or raise the limit with --max-cells)",
                width.saturating_mul(*height)
            ),
            Self::Imprecise {
                magnitude_m,
                spacing_m,
                resolution_m,
            } => write!(
                f,
                "poses and end points reach {magnitude_m:e} m from the origin, where f64 \
                 coordinates are {spacing_m:e} m apart: more than 1/1024 of a {resolution_m} m \
                 cell; move the log nearer the origin or use a coarser resolution"
            ),
        }
    }
}

impl std::error::Error for MappingError {}
