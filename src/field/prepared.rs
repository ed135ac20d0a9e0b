//! [`PreparedScan`]: one scan made ready to be scored at many poses by a [`LikelihoodField`].
//!
//! Most callers score many pose hypotheses against one scan (a particle filter's update, a
//! grid search). Everything about the scan that does not depend on the pose is done once by
//! [`LikelihoodField::prepare`]: max-range and invalid readings are dropped (and counted), and
//! each kept beam's endpoint is stored in the robot frame (the sensor mount's offset and yaw
//! applied once), in grid cells, as a fixed-point pair:
//! `(x, y) = (x_s + z·cos(θ_s + β), y_s + z·sin(θ_s + β)) / cell_size`.
//!
//! # Cost per beam
//! Per pose: one `sin_cos` (of the robot's heading; the mount is already applied), the robot's
//! grid position, and `cos θ`, `sin θ` in fixed point (Q2.30). Per beam: the rotation and
//! translation as four "multiply, keep the high word, add or subtract" operations
//! (`c ± ((a·b) >> 32)`, one `smmla`/`smmls` each on a Cortex-M4), two arithmetic shifts to
//! whole cells (floor, so negative coordinates need no special case), one index multiply-add,
//! two unsigned compares (column on the map; the slice's own bound, which covers the row), one
//! byte read, one table read and one `f32` add. `cargo xtask insns` counts it on the target.
//! On the host, `cargo bench -p host-tests --bench field` times it.
//! Endpoints off the map take the same out-of-line path as [`LikelihoodField::score`] (the
//! distance to the map's edge is charged, docs/models.md#field).
//!
//! # Numbers
//! With `F` fractional bits in grid coordinates ([`PreparedScan::frac_bits`], 16 for maps and
//! ranges under ~8,000 cells), the fixed-point endpoint differs from the exact endpoint of the
//! same `f32` inputs by less than `4·2^−F` cells plus a few `f32` roundings of the stored
//! `(x, y)` (`≤ 2^−23·R`, `R` the range in cells). [`LikelihoodField::score`] computes the
//! endpoint in `f32` with a different rounding order. The two paths therefore read the same
//! cell, and so add the same table entry, except for endpoints within that distance of a cell
//! edge (or, off the map, of a code-rounding boundary); when no beam differs the two scores are
//! bit for bit equal, because terms are added in the same (bearing) order. The host tests
//! count such beams on real maps and scans (`host-tests/tests/field_prepared.rs`).
//!
//! # Memory
//! 8 bytes per kept beam (two `i32`) plus 36 bytes: 2,916 bytes for 360 beams, 1,476 for 180.
//!
//! # Fast-path conditions
//! The integer path is taken when the robot's grid position is within a range computed at
//! preparation (the map's size plus the scan's reach, so that no fixed-point sum overflows and
//! the `u32` cell index cannot wrap back onto the map). A pose outside it (far off the map) is
//! scored by a per-beam `f32` path with the same result semantics. A pose with a NaN or
//! infinite coordinate scores NaN.

use super::likelihood::{LikelihoodField, LIKELIHOOD_TABLE_LEN};
#[cfg(feature = "tiled-field")]
use super::tiled::FullTileRows;
use super::view::Cells;
use crate::math;
use crate::model::Stride;
use crate::pose::Pose;
use crate::scan::{BeamLayout, Scan, ScanScore};
use heapless::Vec;

/// Fractional bits of `cos θ` and `sin θ` in the per-pose fixed-point rotation (Q2.30).
const TRIG_BITS: i32 = 30;
/// Most fractional bits of a grid coordinate on the fast path.
const MAX_FRAC_BITS: u32 = 16;

/// A scan prepared for scoring at many poses against the [`LikelihoodField`] that made it.
///
/// Built by [`LikelihoodField::prepare`] or [`LikelihoodField::prepare_strided`]; it borrows
/// the field, so it can only be scored against the geometry (cell size, `z_max`) it was
/// prepared for. See the module docs for its cost, numbers and memory.
#[derive(Clone, Debug)]
pub struct PreparedScan<'f, const N: usize> {
    field: &'f LikelihoodField<'f>,
    /// Kept beams' endpoints in the robot frame, cells, with `frac_bits + 2` fractional bits.
    points: Vec<[i32; 2], N>,
    /// `F`: fractional bits of grid coordinates on the fast path.
    frac_bits: u32,
    /// The fast path is taken when `|ax| < limit_x` and `limit_y_lo < ay < limit_y_hi`
    /// (robot position, cells).
    limit_x: f32,
    limit_y_lo: f32,
    limit_y_hi: f32,
    /// Counts as [`ScanScore`] reports them (`log_likelihood` unused).
    counts: ScanScore,
    /// The sensor's position in the robot frame (the mount's offset), metres.
    sensor_m: [f32; 2],
}

impl<'a> LikelihoodField<'a> {
    /// Prepares `scan` (read against `layout`) for scoring at many poses with
    /// [`PreparedScan::score`]: drops max-range and invalid readings (counting them) and stores
    /// each kept beam's endpoint in the robot frame. Costs two passes over the beams and one
    /// `sin_cos` (of the mount's yaw).
    pub fn prepare<const N: usize>(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
    ) -> PreparedScan<'_, N> {
        self.prepare_strided(layout, scan, Stride::ONE)
    }

    /// As [`LikelihoodField::prepare`], keeping beams `0, s, 2s, …` only (`s = stride`), like
    /// [`LikelihoodField::score_strided_with`]: beams left out are neither scored nor counted;
    /// `unpaired` still counts every reading past the layout's end.
    pub fn prepare_strided<const N: usize>(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
        stride: Stride,
    ) -> PreparedScan<'_, N> {
        let view = self.view();
        let inv = view.inv_cell_size();
        let max_r = self.params().max_range_m();
        let ranges = scan.ranges_m();
        let stepped = || layout.beams().iter().zip(ranges).step_by(stride.get());
        let mount = layout.mount();
        let (sin_m, cos_m) = math::sin_cos(mount.yaw_rad);
        // One pass for the counts (as `score_strided_with` counts: NaN is neither valid nor
        // max-range, hence invalid) and the scan's reach in cells (every kept endpoint is
        // within it of the robot).
        let mut reach = 0.0f32;
        let (mut scored, mut max_range, mut paired) = (0u32, 0u32, 0u32);
        for (_, &r) in stepped() {
            let keep = (r >= 0.0) & (r < max_r);
            if keep {
                reach = reach.max(r * inv);
            }
            scored += u32::from(keep);
            max_range += u32::from(r >= max_r);
            paired += 1;
        }
        let offset = math::sqrt(mount.x_m * mount.x_m + mount.y_m * mount.y_m) * inv;
        // Whole cells, rounded up (so every bound below is conservative), plus one.
        let reach = ceil_u32(reach)
            .saturating_add(ceil_u32(offset))
            .saturating_add(1);
        let side = view.width().max(view.height());
        // F: the most fractional bits such that a robot anywhere within a map's side of the
        // map, plus twice the reach, stays inside ±2^(30−F) (no i32 overflow, with margin).
        // Integer arithmetic throughout: no f64, which a Cortex-M4F would do in software.
        let need = side
            .saturating_add(reach.saturating_mul(2))
            .saturating_add(4);
        let mut frac_bits = MAX_FRAC_BITS;
        while frac_bits > 0 && need >= 1u32 << (30 - frac_bits) {
            frac_bits -= 1;
        }
        let scale = pow2(frac_bits as i32 + 2);
        let mut points = Vec::new();
        for (beam, &r) in stepped().filter(|&(_, &r)| (r >= 0.0) & (r < max_r)) {
            // Saturating conversion: only an endpoint beyond 2^29 cells could saturate, and
            // then only at F = 0 (see the module docs); it is clamped, not wrapped.
            let ux = cos_m * beam.cos - sin_m * beam.sin;
            let uy = sin_m * beam.cos + cos_m * beam.sin;
            let x = round_to_i32((mount.x_m + r * ux) * inv * scale);
            let y = round_to_i32((mount.y_m + r * uy) * inv * scale);
            // `points` has the layout's capacity and at most one entry per beam.
            let _ = points.push([x, y]);
        }
        // Overflow bound of the fixed-point sums, and the bounds under which the u32 cell
        // index cannot wrap around onto the map (module docs), in whole cells. Each is rounded
        // towards the safe side: `floor((2^32 − 1 − len) / w)` and `floor((2^32 − 1) / w)` are
        // at most the exact `floor((2^32 − len) / w)` and `floor(2^32 / w)`, and the limits
        // are converted to `f32` towards zero.
        let reach = i64::from(reach);
        let fixed_limit = (1i64 << (31 - frac_bits)) - 2 * reach - 4;
        let w = view.width();
        let room = u32::try_from(view.cell_count())
            .ok()
            .map(|len| u32::MAX - len)
            .and_then(|room| room.checked_div(w));
        let (below, above) = match (room, u32::MAX.checked_div(w)) {
            (Some(b), Some(a)) => (i64::from(b) - reach - 4, i64::from(a) - reach - 4),
            // A payload of 2^32 cells or more, or no columns: no pose takes the fast path.
            _ => (-1, -1),
        };
        let invalid = paired - scored - max_range;
        PreparedScan {
            field: self,
            points,
            frac_bits,
            limit_x: toward_zero_f32(fixed_limit),
            limit_y_lo: -toward_zero_f32(below.min(fixed_limit)),
            limit_y_hi: toward_zero_f32(above.min(fixed_limit)),
            counts: ScanScore {
                log_likelihood: 0.0,
                scored: sat16(scored),
                max_range: sat16(max_range),
                invalid: sat16(invalid),
                unpaired: sat16(ranges.len().saturating_sub(layout.len())),
            },
            sensor_m: [mount.x_m, mount.y_m],
        }
    }
}

impl<'f, const N: usize> PreparedScan<'f, N> {
    /// Log-likelihood of the prepared scan with the robot at `pose`: the same report as
    /// [`LikelihoodField::score`] of the scan it was prepared from (see the module docs for
    /// how the two can differ).
    pub fn score(&self, pose: &Pose) -> ScanScore {
        self.score_with(pose, |_, _| {})
    }

    /// As [`PreparedScan::score`], calling `each(j, distance_m)` for the `j`-th kept beam (in
    /// bearing order; max-range and invalid readings were dropped, so `j` counts kept beams
    /// only) with the quantized endpoint distance (metres) that was scored.
    ///
    /// A pose with a NaN or infinite coordinate scores NaN: it is no place on the map, and a
    /// finite score would let it win a filter's update (`each` is called for the beams of a
    /// NaN heading at a finite position, with meaningless distances, and not at all for a NaN
    /// position).
    pub fn score_with<F: FnMut(usize, f32)>(&self, pose: &Pose, mut each: F) -> ScanScore {
        let view = self.field.view();
        let table = self.field.table();
        let step = view.step_m();
        let (sin_t, cos_t) = math::sin_cos(pose.theta_rad);
        let (ax, ay) = view.to_grid(pose.x_m, pose.y_m);
        let mut sum = 0.0f32;
        if self.fixed_point_at(ax, ay) {
            let trig = pow2(TRIG_BITS);
            let (c, s) = (round_to_i32(cos_t * trig), round_to_i32(sin_t * trig));
            let f = self.frac_bits;
            // The usual case with a constant shift; the same code otherwise.
            sum = if f == MAX_FRAC_BITS {
                self.fixed_path::<F, true>(ax, ay, c, s, f, &mut each)
            } else {
                self.fixed_path::<F, false>(ax, ay, c, s, f, &mut each)
            };
            // A NaN or infinite heading (its sine is NaN; the fixed-point path read it as 0):
            // `sin − sin` is NaN then and 0 otherwise, two instructions and no branch. A NaN or
            // infinite position never takes this path.
            #[allow(clippy::eq_op)] // NaN − NaN is the point: not 0.
            {
                sum += sin_t - sin_t;
            }
        } else if !pose.is_finite() {
            return ScanScore {
                log_likelihood: f32::NAN,
                ..self.counts
            };
        } else {
            let inv_scale = pow2(-(self.frac_bits as i32) - 2);
            for (j, p) in self.points.iter().enumerate() {
                let (x, y) = (p[0] as f32 * inv_scale, p[1] as f32 * inv_scale);
                let gx = ax + (cos_t * x - sin_t * y);
                let gy = ay + (sin_t * x + cos_t * y);
                let code = view.table_index(gx, gy);
                sum += table.get(usize::from(code)).copied().unwrap_or(0.0);
                each(j, f32::from(code) * step);
            }
        }
        ScanScore {
            log_likelihood: sum,
            ..self.counts
        }
    }

    /// The fixed-point path: `(ax, ay)` the robot's grid position, `(c, s)` its heading's
    /// cosine and sine in Q2.30, `f` the fractional bits (`FIX16`: `f` is 16, known at
    /// compile time, which frees a register in the loop).
    ///
    /// The per-beam loop ([`on_map_run`]) has no call in it: it stops at the first endpoint
    /// off the map and returns the endpoints from there on; that beam is charged here
    /// ([`off_map`]) and the loop resumes after it. Terms are added in bearing order either way.
    #[inline(always)]
    fn fixed_path<E: FnMut(usize, f32), const FIX16: bool>(
        &self,
        ax: f32,
        ay: f32,
        c: i32,
        s: i32,
        f: u32,
        each: &mut E,
    ) -> f32 {
        // One loop per encoding, chosen once per pose: no dispatch per beam.
        match self.field.view().cells() {
            Cells::Raw(codes) => self.fixed_path_over::<_, E, FIX16>(codes, ax, ay, c, s, f, each),
            #[cfg(feature = "tiled-field")]
            Cells::Tiled(tiles) => {
                let rows = tiles.full_rows(self.field.view().height());
                self.fixed_path_over::<_, E, FIX16>(rows, ax, ay, c, s, f, each)
            }
        }
    }

    /// [`PreparedScan::fixed_path`] over one encoding's cells.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn fixed_path_over<C: CellRead, E: FnMut(usize, f32), const FIX16: bool>(
        &self,
        cells: C,
        ax: f32,
        ay: f32,
        c: i32,
        s: i32,
        f: u32,
        each: &mut E,
    ) -> f32 {
        let view = self.field.view();
        let step = view.step_m();
        let scale = pow2(f as i32);
        let k = FixedPose {
            cells,
            table: self.field.table(),
            w: view.width(),
            h: view.height(),
            ax: round_to_i32(ax * scale),
            ay: round_to_i32(ay * scale),
            #[cfg(not(target_arch = "arm"))]
            c,
            s,
            #[cfg(target_arch = "arm")]
            nc: c.wrapping_neg(),
            #[cfg(not(target_arch = "arm"))]
            ns: s.wrapping_neg(),
        };
        let points: &[[i32; 2]] = &self.points;
        let n = points.len();
        let mut sum = 0.0f32;
        let mut rest = points;
        loop {
            let (partial, stop) =
                on_map_run::<C, E, FIX16>(&k, rest, n - rest.len(), sum, f, step, each);
            sum = partial;
            let Some((p, tail)) = stop.split_first() else {
                return sum;
            };
            let (gx, gy) = k.grid(p);
            let (term, code) = off_map(self.field, gx, gy, f);
            sum += term;
            each(n - stop.len(), f32::from(code) * step);
            rest = tail;
        }
    }

    /// Whether [`PreparedScan::score`] at `pose` takes the fixed-point path (true for every
    /// pose within a map's side of the map, for maps up to 16,000 cells a side; false far off
    /// it or for NaN), rather than the per-beam `f32` path. Both give the same result semantics; this is for tests and
    /// measurements.
    pub fn uses_fixed_point(&self, pose: &Pose) -> bool {
        let (ax, ay) = self.field.view().to_grid(pose.x_m, pose.y_m);
        self.fixed_point_at(ax, ay)
    }

    /// The fast-path test on the robot's grid position (NaN fails every comparison).
    #[inline(always)]
    fn fixed_point_at(&self, ax: f32, ay: f32) -> bool {
        (ax.abs() < self.limit_x) & (ay > self.limit_y_lo) & (ay < self.limit_y_hi)
    }

    /// The field this scan was prepared for.
    pub fn field(&self) -> &'f LikelihoodField<'f> {
        self.field
    }

    /// Kept beams (those scored at every pose).
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when no beam was kept (every reading max-range or invalid).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// `F`: fractional bits of grid coordinates on the fixed-point path (16 unless the map's
    /// side plus twice the scan's reach exceeds ~16,000 cells). The fixed-point endpoint is
    /// within `4·2^−F` cells (plus `f32` roundings of the stored endpoint) of the exact one.
    pub fn frac_bits(&self) -> u32 {
        self.frac_bits
    }

    /// The counts every score of this scan reports (its `log_likelihood` is 0).
    pub fn counts(&self) -> ScanScore {
        self.counts
    }

    /// The kept beams' endpoints in the robot frame, cells, as `(x, y)` with
    /// `frac_bits() + 2` fractional bits.
    pub fn endpoints(&self) -> &[[i32; 2]] {
        &self.points
    }

    /// A copy keeping only the beams `j` (kept-beam index, as in [`PreparedScan::score_with`])
    /// for which `keep(j)` is true, in the same order; its counts report the beams left as
    /// `scored` (the other counts are this scan's). Every beam left scores exactly as here at
    /// every pose (the fast path's limits, computed for the whole scan's reach, hold for any
    /// subset of it). Memory: one more `PreparedScan<N>` (8 bytes per beam of capacity `N`
    /// plus the header), wherever the caller puts it.
    pub fn retain<K: FnMut(usize) -> bool>(&self, mut keep: K) -> Self {
        let mut points = Vec::new();
        for (j, p) in self.points.iter().enumerate() {
            if keep(j) {
                // At most as many as `self.points`, which fit the same capacity.
                let _ = points.push(*p);
            }
        }
        let dropped = self.points.len().saturating_sub(points.len()) as u32;
        let counts = ScanScore {
            scored: sat16(points.len() as u32),
            invalid: sat16(u32::from(self.counts.invalid).saturating_add(dropped)),
            ..self.counts
        };
        Self {
            points,
            counts,
            ..*self
        }
    }

    /// The sensor's position in the map frame (metres) with the robot at `pose`.
    pub fn sensor_at(&self, pose: &Pose) -> (f32, f32) {
        let (s, c) = math::sin_cos(pose.theta_rad);
        let [x, y] = self.sensor_m;
        (pose.x_m + c * x - s * y, pose.y_m + s * x + c * y)
    }

    /// Kept beam `j`'s endpoint in the map frame (metres) with the robot at `pose` (`f32`, from
    /// the stored fixed-point endpoint), or `None` past the last kept beam. `sin_cos` is the
    /// pose's heading's sine and cosine (the caller computes them once per pose).
    pub fn endpoint_at(&self, pose: &Pose, (s, c): (f32, f32), j: usize) -> Option<(f32, f32)> {
        let p = self.points.get(j)?;
        let to_m = pow2(-(self.frac_bits as i32) - 2) * self.field.view().cell_size_m();
        let (x, y) = (p[0] as f32 * to_m, p[1] as f32 * to_m);
        Some((pose.x_m + c * x - s * y, pose.y_m + s * x + c * y))
    }
}

/// One encoding's cells as the fixed-point loop reads them.
trait CellRead: Copy {
    /// The code of cell `(ix, iy)` of a `w × h` map, `None` off the map (`ix`, `iy` are the
    /// floored grid coordinates as `u32`: negatives wrap to large values).
    fn read(&self, ix: u32, iy: u32, w: u32, h: u32) -> Option<u8>;
}

impl CellRead for &[u8] {
    /// Encoding 1: one byte read.
    #[inline(always)]
    fn read(&self, ix: u32, iy: u32, w: u32, _h: u32) -> Option<u8> {
        // Row-major index in u32 arithmetic: rows off the map (either side) land past the
        // payload's end, as the y limits guarantee; columns are checked here.
        let i = iy.wrapping_mul(w).wrapping_add(ix) as usize;
        if ix < w {
            self.get(i).copied()
        } else {
            None
        }
    }
}

#[cfg(feature = "tiled-field")]
impl CellRead for FullTileRows<'_> {
    /// Encoding 2: the column checked here, the row by the index's bounds check (rows of a
    /// partial last row of tiles give `None` too: [`off_map`] reads them exactly).
    #[inline(always)]
    fn read(&self, ix: u32, iy: u32, w: u32, _h: u32) -> Option<u8> {
        if ix < w {
            self.code(ix, iy)
        } else {
            None
        }
    }
}

/// What the fixed-point loop reads at one pose.
struct FixedPose<'a, C> {
    /// The map's distance codes.
    cells: C,
    /// The per-code log-likelihood terms.
    table: &'a [f32; LIKELIHOOD_TABLE_LEN],
    /// The map's width, cells.
    w: u32,
    /// The map's height, cells.
    h: u32,
    /// The robot's grid position, cells, with `f` fractional bits.
    ax: i32,
    ay: i32,
    /// The cosine and sine of the robot's heading, Q2.30, and the negatives the target's form
    /// of [`FixedPose::grid`] uses (`|c|, |s| ≤ 2^30`, so negation is exact).
    #[cfg(not(target_arch = "arm"))]
    c: i32,
    s: i32,
    #[cfg(target_arch = "arm")]
    nc: i32,
    #[cfg(not(target_arch = "arm"))]
    ns: i32,
}

impl<C: CellRead> FixedPose<'_, C> {
    /// The grid point (cells, `f` fractional bits) of a robot-frame endpoint (`f + 2`
    /// fractional bits): rotation and translation as four "multiply, keep the high word, add
    /// or subtract" operations. The limits of the fast path keep these sums in range.
    ///
    /// `gx = ax + ⌊c·x/2^32⌋ − ⌈s·y/2^32⌉` and `gy = ay + ⌊s·x/2^32⌋ + ⌊c·y/2^32⌋`, wrapping
    /// (mod 2^32). For any `a ≠ i32::MIN`, [`mul_hi_sub`]`(acc, a, b)` and
    /// [`mul_hi_add`]`(acc, −a, b)` are the same number: both are `acc + ⌊−a·b/2^32⌋` mod 2^32
    /// (the i64 form may wrap, which changes its high word by a multiple of 2^32 only). So the
    /// two spellings below give identical bits; each is the shorter one for its target:
    ///
    /// - Arm: a chain of two accumulating multiplies per coordinate (`smmla`/`smmls`) with the
    ///   translation as the first accumulator, reading only `nc` and `s`. Written as two
    ///   additions, LLVM reassociated `gy` into three instructions (`smmul`, `smmla`, `add`).
    /// - Elsewhere (x86-64): only additions of high words (multiply, shift, add), reading `c`,
    ///   `s` and `ns`; the subtraction form costs a shift and a mask more per term there.
    #[inline(always)]
    fn grid(&self, p: &[i32; 2]) -> (i32, i32) {
        let (x, y) = (p[0], p[1]);
        #[cfg(target_arch = "arm")]
        let (gx, gy) = (
            mul_hi_sub(mul_hi_sub(self.ax, self.nc, x), self.s, y),
            mul_hi_sub(mul_hi_add(self.ay, self.s, x), self.nc, y),
        );
        #[cfg(not(target_arch = "arm"))]
        let (gx, gy) = (
            mul_hi_add(mul_hi_add(self.ax, self.c, x), self.ns, y),
            mul_hi_add(mul_hi_add(self.ay, self.s, x), self.c, y),
        );
        (gx, gy)
    }

    /// The distance code of the cell under endpoint `p`, or `None` when it is off the map
    /// (`shift` = `f`).
    #[inline(always)]
    fn code(&self, p: &[i32; 2], shift: u32) -> Option<u8> {
        let (gx, gy) = self.grid(p);
        // Arithmetic shift: floor, so a point just left of or below the map gets −1.
        let ix = gx.wrapping_shr(shift) as u32;
        let iy = gy.wrapping_shr(shift) as u32;
        self.cells.read(ix, iy, self.w, self.h)
    }

    /// The table's term for `code` (a code is ≤ 255 and the table has 256 entries: the check
    /// folds away).
    #[inline(always)]
    fn term(&self, code: u8) -> f32 {
        self.table.get(usize::from(code)).copied().unwrap_or(0.0)
    }
}

/// Adds the terms of `points` to `sum`, in order, up to the first endpoint off the map;
/// returns the sum and the endpoints from that one on (empty when every one was on the map).
/// `each` gets `(first + j, distance)` for the `j`-th endpoint of `points`.
///
/// No call inside, so everything stays in registers; not inlined, so its register allocation
/// is its own. The position of an endpoint is found from its address when needed (on exit, or
/// for a non-trivial `each`), so the loop keeps no counter.
#[inline(never)]
fn on_map_run<'p, C: CellRead, E: FnMut(usize, f32), const FIX16: bool>(
    k: &FixedPose<'_, C>,
    points: &'p [[i32; 2]],
    first: usize,
    mut sum: f32,
    f: u32,
    step: f32,
    each: &mut E,
) -> (f32, &'p [[i32; 2]]) {
    let shift = if FIX16 { MAX_FRAC_BITS } else { f };
    let at = |p: &[i32; 2]| {
        (p as *const [i32; 2] as usize - points.as_ptr() as usize)
            / core::mem::size_of::<[i32; 2]>()
    };
    for p in points {
        let Some(code) = k.code(p, shift) else {
            return (sum, points.get(at(p)..).unwrap_or_default());
        };
        sum += k.term(code);
        each(first + at(p), f32::from(code) * step);
    }
    (sum, &[])
}

/// The term and table index of a fixed-point grid point the fast path found off the map:
/// converted to `f32` (exact for `|g| < 2^24`, rounded monotonically beyond, so the on-map test
/// cannot change its answer) and charged as [`LikelihoodField::score`] charges it.
#[inline(never)]
#[cold]
fn off_map(field: &LikelihoodField<'_>, gx: i32, gy: i32, f: u32) -> (f32, u8) {
    // A tiled blob's loop leaves the cells of a partial last row of tiles here: on the map,
    // read at the same integer cell the raw loop reads.
    #[cfg(feature = "tiled-field")]
    if let Cells::Tiled(_) = field.view().cells() {
        let (ix, iy) = (gx.wrapping_shr(f) as u32, gy.wrapping_shr(f) as u32);
        if let Some(code) = field.view().code(ix, iy) {
            let term = field.table().get(usize::from(code)).copied().unwrap_or(0.0);
            return (term, code);
        }
    }
    let inv = pow2(-(f as i32));
    let code = field.view().table_index(gx as f32 * inv, gy as f32 * inv);
    let term = field.table().get(usize::from(code)).copied().unwrap_or(0.0);
    (term, code)
}

/// `acc + floor(a·b / 2^32)`: the high word of the 64-bit product, added (`smmla` on a
/// Cortex-M4).
#[inline(always)]
fn mul_hi_add(acc: i32, a: i32, b: i32) -> i32 {
    acc.wrapping_add(((i64::from(a) * i64::from(b)) >> 32) as i32)
}

/// `acc − ceil(a·b / 2^32)`, i.e. `floor((acc·2^32 − a·b) / 2^32)`: the 64-bit difference's
/// high word (`smmls` on a Cortex-M4). Used on Arm only (see [`FixedPose::grid`]).
#[cfg(any(target_arch = "arm", test))]
#[inline(always)]
fn mul_hi_sub(acc: i32, a: i32, b: i32) -> i32 {
    (((i64::from(acc) << 32).wrapping_sub(i64::from(a) * i64::from(b))) >> 32) as i32
}

/// `2^e`, exactly, for `−126 ≤ e ≤ 127` (built from its bits; the exponents used here are
/// within ±32).
fn pow2(e: i32) -> f32 {
    f32::from_bits(((e.clamp(-126, 127) + 127) as u32) << 23)
}

/// The smallest whole number of cells not below `v` (`v ≥ 0` here; NaN gives 0, values beyond
/// `u32::MAX` saturate).
fn ceil_u32(v: f32) -> u32 {
    let t = v as u32;
    if (t as f32) < v {
        t.saturating_add(1)
    } else {
        t
    }
}

/// `v` as an `f32`, rounded towards zero (so a bound never grows in magnitude); magnitudes
/// beyond `u32::MAX` are first clamped to it (also towards zero). Once per preparation: not
/// inlined (flash).
#[inline(never)]
fn toward_zero_f32(v: i64) -> f32 {
    let m = u32::try_from(v.unsigned_abs()).unwrap_or(u32::MAX);
    let mut f = m as f32;
    // `f as u32` saturates at `u32::MAX`, so compare in u64.
    if u64::from(f as u32) > u64::from(m) || f >= 4_294_967_296.0 {
        // Rounded up: the next `f32` towards zero (`f` is positive and finite here).
        f = f32::from_bits(f.to_bits() - 1);
    }
    if v < 0 {
        -f
    } else {
        f
    }
}

/// Rounds half away from zero and saturates (NaN gives 0).
fn round_to_i32(v: f32) -> i32 {
    (if v >= 0.0 { v + 0.5 } else { v - 0.5 }) as i32
}

fn sat16<T: TryInto<u16>>(n: T) -> u16 {
    n.try_into().unwrap_or(u16::MAX)
}

#[cfg(test)]
mod tests {
    use super::{mul_hi_add, mul_hi_sub};

    /// The identity [`super::FixedPose::grid`] relies on: subtracting the high word of `a·b`
    /// (rounded up) is adding the high word of `(−a)·b` (rounded down), bit for bit, for every
    /// accumulator (wrapping included) and `|a| ≤ 2^30`; so the Arm and the other spelling of
    /// the grid point agree.
    #[test]
    fn subtracting_is_adding_the_negated_product() {
        let mut rng = crate::mcl::XorShift64::new(0x9e37_79b9_7f4a_7c15u64);
        let mut next = || rng.next_word();
        let edges = [i32::MIN, i32::MIN + 1, -1, 0, 1, i32::MAX - 1, i32::MAX];
        let a_edges = [-(1 << 30), -(1 << 30) + 1, -1, 0, 1, (1 << 30) - 1, 1 << 30];
        for round in 0..200_000u32 {
            let r = next();
            let acc = if round % 7 == 0 {
                edges[(r % 7) as usize]
            } else {
                r as i32
            };
            let a = if round % 5 == 0 {
                a_edges[((r >> 8) % 7) as usize]
            } else {
                ((r >> 16) as i32) >> 1
            };
            let b = if round % 3 == 0 {
                edges[((r >> 24) % 7) as usize]
            } else {
                (r >> 32) as i32
            };
            assert_eq!(
                mul_hi_sub(acc, a, b),
                mul_hi_add(acc, -a, b),
                "{acc} {a} {b}"
            );
            // The two spellings of a grid point (x on the left, y on the right).
            let (c, s) = (a, ((r >> 3) as i32) >> 1);
            let (x, y) = (b, (r >> 40) as i32);
            let arm = (
                mul_hi_sub(mul_hi_sub(acc, -c, x), s, y),
                mul_hi_sub(mul_hi_add(acc, s, x), -c, y),
            );
            let other = (
                mul_hi_add(mul_hi_add(acc, c, x), -s, y),
                mul_hi_add(mul_hi_add(acc, s, x), c, y),
            );
            assert_eq!(arm, other, "{acc} {c} {s} {x} {y}");
        }
    }
}
