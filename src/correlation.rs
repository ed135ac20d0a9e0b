//! Map correlation, Thrun §6.5 (docs/models.md#features): rasterize the scan into a local map around
//! the pose, read the same window of the global map, and score the pose by the correlation
//! coefficient of the two, clipped at zero.
//!
//! ```text
//! ρ = Σ(m − m̄)(m_loc − m̄) / √( Σ(m − m̄)² · Σ(m_loc − m̄)² ),   score = max(ρ, 0)
//! ```
//!
//! with the sums over the cells of the window and `m̄` the mean cell value over **both** maps
//! (`m̄ = (Σm + Σm_loc) / 2n`), as the chapter defines it (this is not Pearson's coefficient,
//! which centres each map on its own mean).
//!
//! # Cell values
//! - Global map `m`: 1 where the blob's distance code is 0 (an occupied cell), 0 elsewhere. The
//!   blob stores distances only, so **unknown and free cells are indistinguishable** and both
//!   read 0. Window cells off the map read 0.
//! - Local map `m_loc`: 1 in every cell that holds at least one scan endpoint, 0 elsewhere.
//!   Free space along the rays is not marked: with the global map's unknown folded into free,
//!   a free mark would be the same value as "nothing seen", so it would change nothing.
//!
//! Both maps are binary, so the three sums reduce to four exact integer counts (`n` cells,
//! `a = Σm`, `b = Σm_loc`, `c = Σm·m_loc`) and
//!
//! ```text
//! ρ = (4nc − s²) / √( (4na − 4sa + s²) · (4nb − 4sb + s²) ),   s = a + b
//! ```
//!
//! which is evaluated in exact 64-bit integers up to the final division (no cancellation).
//! Because `m̄` mixes both maps, a denominator factor is 0 only when both maps are empty
//! (`s = 0`) or both full; `ρ` is then undefined and reported as 0, "no evidence". An empty local map against
//! an occupied window gives `ρ < 0` (score 0).
//!
//! # Window
//! The local grid has the global map's cell size and is aligned with its cells: `width × height`
//! cells (chosen by the caller, storage supplied by the caller), with the cell holding the
//! sensor at index `(width/2, height/2)`. Endpoints outside the window are dropped (and counted,
//! [`Correlation::outside_window`]); choose the window to cover `2·max_range` when every beam
//! should count.
//!
//! # Not a density
//! `max(ρ, 0)` is a similarity in `[0, 1]`, not `p(z | x, m)`: it does not integrate to one over
//! scans and does not grow with the number of beams. [`MapCorrelation`] implements
//! [`SensorModel`] returning `ln max(ρ, ε)` with [`CORRELATION_EPSILON`] so that it can be used as
//! (and compared with) a log-weight; its scale is not that of the other models.
//!
//! # Cost
//! Per pose: one `sin_cos`, a clear of the window, one projection and one byte store per beam,
//! one blob read per window cell, one `sqrt`. No allocation, no panic, no error branch.

use crate::field::FieldView;
use crate::math;
use crate::model::{SensorModel, Stride};
use crate::pose::Pose;
use crate::scan::{BeamLayout, Scan, ScanScore};
use core::cell::Cell;

/// `ε` of the [`SensorModel`] implementation: a pose whose clipped correlation is below it
/// scores `ln ε ≈ −6.91` nats. Chosen well below the correlations of plausible poses (tenths)
/// and large enough that one uninformative pose does not annihilate a particle's weight.
pub const CORRELATION_EPSILON: f32 = 1e-3;

/// The largest local grid accepted, cells (`2^20`, e.g. 1024 × 1024): keeps every count and
/// the integer form of `ρ` exact in `i64`.
pub const MAX_WINDOW_CELLS: usize = 1 << 20;

/// Why a local grid was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum CorrelationError {
    /// Width or height is 0.
    EmptyWindow,
    /// `width · height` exceeds [`MAX_WINDOW_CELLS`] (or overflows).
    WindowTooLarge,
    /// The buffer's length is not `width · height`.
    BufferLength {
        /// Length of the buffer given.
        given: usize,
        /// `width · height`.
        needed: usize,
    },
}

impl core::fmt::Display for CorrelationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::EmptyWindow => f.write_str("local grid width and height must be > 0"),
            Self::WindowTooLarge => write!(f, "local grid exceeds {MAX_WINDOW_CELLS} cells"),
            Self::BufferLength { given, needed } => {
                write!(f, "local grid buffer has {given} cells, needs {needed}")
            }
        }
    }
}

impl core::error::Error for CorrelationError {}

/// The correlation of one scan at one pose, with the counts behind it.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Correlation {
    /// `ρ` in `[−1, 1]`; 0 when undefined (both maps empty, or both full).
    pub rho: f32,
    /// Cells in the window (`n`).
    pub cells: u32,
    /// Occupied cells of the global map in the window (`Σm`).
    pub map_occupied: u32,
    /// Cells of the local map holding an endpoint (`Σm_loc`).
    pub local_occupied: u32,
    /// Cells occupied in both (`Σm·m_loc`).
    pub overlap: u32,
    /// Valid readings whose endpoint fell outside the window (not rasterized).
    pub outside_window: u16,
    /// The scan's bookkeeping: `scored` counts every valid reading that was projected
    /// (including those outside the window), as in [`ScanScore`]; `log_likelihood` is 0 here.
    pub counts: ScanScore,
}

impl Correlation {
    /// The chapter's score, `max(ρ, 0)`, in `[0, 1]`.
    pub fn score(&self) -> f32 {
        self.rho.max(0.0)
    }

    /// `ln max(ρ, ε)` with [`CORRELATION_EPSILON`], nats (not a log-density).
    pub fn log_score(&self) -> f32 {
        math::ln(self.rho.max(CORRELATION_EPSILON))
    }
}

/// `ρ` from the four counts (module docs), or 0 when undefined.
///
/// Exact in `i64` for `n ≤` [`MAX_WINDOW_CELLS`]; `a, b, c ≤ n` is assumed (the counts of one
/// window), and anything else still returns a finite value in `[−1, 1]` or 0.
pub fn rho_from_counts(n: u32, map_occupied: u32, local_occupied: u32, overlap: u32) -> f32 {
    let (n, a, b, c) = (
        i64::from(n),
        i64::from(map_occupied),
        i64::from(local_occupied),
        i64::from(overlap),
    );
    let s = a + b;
    let num = 4 * n * c - s * s;
    let da = 4 * n * a - 4 * s * a + s * s;
    let db = 4 * n * b - 4 * s * b + s * s;
    if da <= 0 || db <= 0 {
        return 0.0;
    }
    let rho = num as f32 / (math::sqrt(da as f32) * math::sqrt(db as f32));
    // Rounding can step a hair outside [−1, 1]; NaN cannot occur (both factors > 0).
    rho.clamp(-1.0, 1.0)
}

/// The map-correlation model over a distance-field blob, with a caller-owned local grid.
///
/// The grid is held as `&[Cell<u8>]` so that scoring takes `&self` (as [`SensorModel`] asks)
/// and still rewrites it: a model value is therefore not `Sync`; give each thread its own.
#[derive(Debug)]
pub struct MapCorrelation<'v, 'b> {
    view: FieldView<'v>,
    local: &'b [Cell<u8>],
    width: u32,
    height: u32,
}

impl<'v, 'b> MapCorrelation<'v, 'b> {
    /// A model reading `view`'s occupancy (code 0) with a `width × height` local grid stored in
    /// `buffer` (row-major, row 0 = lowest y; its contents are overwritten on every score).
    ///
    /// # Errors
    /// [`CorrelationError::EmptyWindow`], [`CorrelationError::WindowTooLarge`],
    /// [`CorrelationError::BufferLength`] when `buffer.len() != width · height`.
    pub fn new(
        view: FieldView<'v>,
        width: u32,
        height: u32,
        buffer: &'b mut [u8],
    ) -> Result<Self, CorrelationError> {
        if width == 0 || height == 0 {
            return Err(CorrelationError::EmptyWindow);
        }
        let needed = usize::try_from(u64::from(width) * u64::from(height))
            .map_err(|_| CorrelationError::WindowTooLarge)?;
        if needed > MAX_WINDOW_CELLS {
            return Err(CorrelationError::WindowTooLarge);
        }
        if buffer.len() != needed {
            return Err(CorrelationError::BufferLength {
                given: buffer.len(),
                needed,
            });
        }
        Ok(Self {
            view,
            local: Cell::from_mut(buffer).as_slice_of_cells(),
            width,
            height,
        })
    }

    /// The global map's view.
    pub fn view(&self) -> &FieldView<'v> {
        &self.view
    }

    /// Local grid width and height, cells.
    pub fn window(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Global cell indices of the window's cell `(0, 0)` for a sensor at map-frame metres
    /// `(x_m, y_m)`: the sensor's cell minus `(width/2, height/2)`. May be negative or past the
    /// map (those cells read as unoccupied).
    pub fn window_origin(&self, x_m: f32, y_m: f32) -> (i64, i64) {
        let (gx, gy) = self.view.to_grid(x_m, y_m);
        (
            cell_index(gx).saturating_sub(i64::from(self.width / 2)),
            cell_index(gy).saturating_sub(i64::from(self.height / 2)),
        )
    }

    /// The local grid as last rasterized (1 = endpoint), row-major, row 0 = lowest y.
    pub fn local_cells(&self) -> impl Iterator<Item = u8> + '_ {
        self.local.iter().map(Cell::get)
    }

    /// Correlates every `stride`-th reading of `scan` (read against `layout`) at `pose`.
    ///
    /// Readings are paired with the layout's beams in order; max-range, invalid and unpaired
    /// readings are skipped and counted as in [`ScanScore`].
    pub fn correlate_strided<const N: usize>(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
        pose: &Pose,
        stride: Stride,
    ) -> Correlation {
        for c in self.local {
            c.set(0);
        }
        let sensor = layout.mount().sensor_pose(pose);
        let (sin_t, cos_t) = math::sin_cos(sensor.theta_rad);
        let inv = self.view.inv_cell_size();
        let (ax, ay) = self.view.to_grid(sensor.x_m, sensor.y_m);
        let (ox, oy) = self.window_origin(sensor.x_m, sensor.y_m);
        let (c, s) = (cos_t * inv, sin_t * inv);
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        let max_r = layout.max_range_m();
        let (mut scored, mut max_range, mut invalid, mut outside) = (0u32, 0u32, 0u32, 0u32);
        let ranges = scan.ranges_m();
        let pairs = layout.beams().iter().zip(ranges).step_by(stride.get());
        for (beam, &r) in pairs {
            if r.is_nan() || r < 0.0 {
                invalid += 1;
                continue;
            }
            if r >= max_r {
                max_range += 1;
                continue;
            }
            scored += 1;
            let ux = c * beam.cos - s * beam.sin;
            let uy = s * beam.cos + c * beam.sin;
            let lx = cell_index(ax + r * ux).saturating_sub(ox);
            let ly = cell_index(ay + r * uy).saturating_sub(oy);
            let slot = if (0..w).contains(&lx) && (0..h).contains(&ly) {
                usize::try_from(ly * w + lx)
                    .ok()
                    .and_then(|i| self.local.get(i))
            } else {
                None
            };
            match slot {
                Some(cell) => cell.set(1),
                None => outside += 1,
            }
        }
        let (mut a, mut b, mut both) = (0u32, 0u32, 0u32);
        let rows = self.local.chunks_exact(self.width as usize);
        // Saturating, not `(oy..)`: a pose far off the map (or NaN) saturates the origin at
        // `i64::MAX`, and a range from there overflows.
        for (dy, row) in (0i64..).zip(rows) {
            let iy = oy.saturating_add(dy);
            for (dx, cell) in (0i64..).zip(row) {
                let ix = ox.saturating_add(dx);
                let m = u32::from(self.occupied(ix, iy));
                let l = u32::from(cell.get());
                a += m;
                b += l;
                both += m & l;
            }
        }
        let n = self.width * self.height;
        let unpaired = if stride.get() == 1 {
            ranges.len().saturating_sub(layout.len())
        } else {
            0
        };
        Correlation {
            rho: rho_from_counts(n, a, b, both),
            cells: n,
            map_occupied: a,
            local_occupied: b,
            overlap: both,
            outside_window: sat16(outside),
            counts: ScanScore {
                log_likelihood: 0.0,
                scored: sat16(scored),
                max_range: sat16(max_range),
                invalid: sat16(invalid),
                unpaired: sat16(unpaired),
            },
        }
    }

    /// As [`MapCorrelation::correlate_strided`] with every reading.
    pub fn correlate<const N: usize>(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
        pose: &Pose,
    ) -> Correlation {
        self.correlate_strided(layout, scan, pose, Stride::ONE)
    }

    /// True when global cell `(ix, iy)` is on the map and occupied (code 0).
    fn occupied(&self, ix: i64, iy: i64) -> bool {
        match (u32::try_from(ix), u32::try_from(iy)) {
            (Ok(x), Ok(y)) => self.view.code(x, y) == Some(0),
            _ => false,
        }
    }
}

impl<const N: usize> SensorModel<N> for MapCorrelation<'_, '_> {
    /// `log_likelihood = ln max(ρ, ε)` ([`CORRELATION_EPSILON`]): a similarity on a log scale,
    /// **not** a log-density of the scan; NaN for a pose with a NaN or infinite coordinate.
    /// The counts are those of [`Correlation::counts`].
    fn score_strided(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
        pose: &Pose,
        stride: Stride,
    ) -> ScanScore {
        let c = self.correlate_strided(layout, scan, pose, stride);
        ScanScore {
            // A NaN or infinite pose is nowhere: no finite score for it.
            log_likelihood: if pose.is_finite() {
                c.log_score()
            } else {
                f32::NAN
            },
            ..c.counts
        }
    }
}

/// The cell index of a continuous grid coordinate: `floor`, saturating (NaN gives 0).
fn cell_index(g: f32) -> i64 {
    math::floor(g) as i64
}

fn sat16<T: TryInto<u16>>(n: T) -> u16 {
    n.try_into().unwrap_or(u16::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{emit_blob, FieldHeader};
    use crate::pose::SensorMount;

    #[test]
    fn window_validation_table() {
        let h = FieldHeader::new(4, 4, 1.0, 0.0, 0.0);
        let mut blob = vec![0u8; h.required_len().unwrap()];
        emit_blob(&h, &[5; 16], &mut blob).unwrap();
        let view = FieldView::parse(&blob).unwrap();
        let cases: [(u32, u32, usize, Option<CorrelationError>); 5] = [
            (0, 3, 0, Some(CorrelationError::EmptyWindow)),
            (3, 0, 0, Some(CorrelationError::EmptyWindow)),
            (2048, 1024, 0, Some(CorrelationError::WindowTooLarge)),
            (
                3,
                3,
                8,
                Some(CorrelationError::BufferLength {
                    given: 8,
                    needed: 9,
                }),
            ),
            (3, 3, 9, None),
        ];
        for (w, hgt, len, want) in cases {
            let mut buf = vec![0u8; len];
            let got = MapCorrelation::new(view, w, hgt, &mut buf).err();
            assert_eq!(got, want, "{w}×{hgt}, buffer {len}");
        }
    }

    #[test]
    fn rho_closed_forms() {
        // Identical maps: ρ = 1. Complementary halves: ρ = −1. Empty local map: 0.
        assert!((rho_from_counts(10, 3, 3, 3) - 1.0).abs() < 1e-6);
        assert!((rho_from_counts(10, 5, 5, 0) + 1.0).abs() < 1e-6);
        // With the mean over both maps, an empty local map is not undefined: Σ(m_loc − m̄)² =
        // n·m̄² > 0 and ρ = −s²/√(da·s²) < 0 (clipped to 0 by the score). By hand, for n = 10,
        // a = 3: da = 120 − 36 + 9 = 93, ρ = −9/(3·√93).
        let want = -9.0 / (3.0 * 93f64.sqrt());
        assert!((f64::from(rho_from_counts(10, 3, 0, 0)) - want).abs() < 1e-6);
        assert!(rho_from_counts(10, 0, 4, 0) < 0.0);
        // Both maps empty: 0/0, reported as 0.
        assert_eq!(rho_from_counts(10, 0, 0, 0), 0.0);
    }

    #[test]
    fn skipped_readings_are_counted() {
        let h = FieldHeader::new(8, 8, 0.5, 0.0, 0.0);
        let mut blob = vec![0u8; h.required_len().unwrap()];
        emit_blob(&h, &[0; 64], &mut blob).unwrap();
        let view = FieldView::parse(&blob).unwrap();
        let mut buf = [9u8; 9];
        let m = MapCorrelation::new(view, 3, 3, &mut buf).unwrap();
        let layout = BeamLayout::<6>::uniform(0.0, 0.1, 5, 3.0, SensorMount::CENTERED).unwrap();
        let scan = Scan::<6>::from_ranges(&[0.1, f32::NAN, 2.9, -1.0, f32::INFINITY, 0.5]).unwrap();
        let c = m.correlate(&layout, &scan, &Pose::new(2.0, 2.0, 0.0));
        let k = c.counts;
        assert_eq!((k.scored, k.invalid, k.max_range, k.unpaired), (2, 2, 1, 1));
        // 2.9 m is 5+ cells away: outside the 3×3 window. Every map cell is occupied, so the
        // map term has no variance... yet the mixed mean keeps it defined: a = 9, b = 1, c = 1.
        assert_eq!(c.outside_window, 1);
        assert_eq!(
            (c.cells, c.map_occupied, c.local_occupied, c.overlap),
            (9, 9, 1, 1)
        );
        assert_eq!(m.local_cells().filter(|&v| v == 1).count(), 1);
    }
}
