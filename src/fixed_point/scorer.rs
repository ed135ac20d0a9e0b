//! [`FixedField`]: the likelihood field scored in integer arithmetic (see the module doc of
//! [`crate::fixed_point`] for the Q formats).

use super::{I16F16, I48F16};
use crate::field::{FieldView, LikelihoodField, CODE_MAX, LIKELIHOOD_TABLE_LEN};
use crate::math::{sat_i32, sin_cos_q30};
use crate::pose::Pose;
use crate::scan::{BeamLayout, Scan};

/// The largest scan the fixed-point scorer accepts, beams (the counts of [`FixedScore`] are
/// `u16`).
///
/// # Overflow bound of the sum
/// A term is an `I16F16`, so its raw value `t` satisfies `|t| ≤ 2³¹`. The sum of at most
/// `MAX_FIXED_BEAMS = 2¹⁶ − 1` terms therefore has `|Σ t| ≤ (2¹⁶ − 1)·2³¹ < 2⁴⁷`, which fits
/// the `i64` raw value of an `I48F16` with 16 bits to spare; the tempered product
/// `Σ t · κ_raw` with `κ_raw ≤ 2¹⁶` stays below `2⁶³`. Checked at compile time below and by a
/// test that scores the largest scan with every term at `I16F16::MIN`.
pub const MAX_FIXED_BEAMS: usize = u16::MAX as usize;

const _: () = assert!((MAX_FIXED_BEAMS as i128) * (1i128 << 31) * (1i128 << 16) < (1i128 << 63));

/// The longest range the scorer represents, cells: ranges are Q11.8 cells below `2¹⁹`, whose
/// integer part (below `2¹¹`) and fraction (below `2⁸`) are each multiplied by a Q1.15 unit
/// vector within an `i32`. The parameter set's `max_range_m` must be below this many cells.
pub const MAX_RANGE_CELLS: f32 = 2047.0;

/// Off-map excursions are clamped at this many cells per axis (Q.4 squares stay < 2³⁰); the
/// blob must reach code 255 within it.
const OFF_MAP_CLAMP_CELLS: i32 = 1024;

/// Why a fixed-point field, layout or scan could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FixedError {
    /// A per-code term is below `−32 768` nats (an `I16F16` cannot hold it).
    TermOutOfRange,
    /// The map is wider or taller than 2²² cells (Q.8 cell coordinates would overflow).
    MapTooLarge,
    /// The map origin is beyond ±32 768 m.
    OriginOutOfRange,
    /// `max_range_m` is [`MAX_RANGE_CELLS`] cells or more.
    RangeTooLong,
    /// The cell is larger than `d_max` or smaller than `d_max / 1020`: the off-map distance
    /// would not be represented.
    CellSizeUnsupported,
    /// More than [`MAX_FIXED_BEAMS`] beams.
    TooManyBeams,
    /// The mount offset is beyond ±32 768 m or not finite.
    MountOutOfRange,
    /// The pose is beyond ±32 768 m or not finite.
    PoseOutOfRange,
}

impl core::fmt::Display for FixedError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::TermOutOfRange => "a log-likelihood term is below -32768",
            Self::MapTooLarge => "map side above 2^22 cells",
            Self::OriginOutOfRange => "map origin beyond 32768 m",
            Self::RangeTooLong => "max range is 2047 cells or more",
            Self::CellSizeUnsupported => "cell size outside [d_max/1020, d_max]",
            Self::TooManyBeams => "more than 65535 beams",
            Self::MountOutOfRange => "mount offset out of range",
            Self::PoseOutOfRange => "pose out of range",
        })
    }
}

impl core::error::Error for FixedError {}

/// A robot pose in fixed point: position `I16F16` metres, heading as Q2.30 cos/sin.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FixedPose {
    x_m: I16F16,
    y_m: I16F16,
    cos_q30: i32,
    sin_q30: i32,
}

impl FixedPose {
    /// A pose from fixed-point position (metres) and heading (radians, any value): cos/sin by
    /// the integer [`sin_cos_q30`]. No floating point.
    pub fn new(x_m: I16F16, y_m: I16F16, theta_rad: I16F16) -> Self {
        let (cos_q30, sin_q30) = sin_cos_q30(theta_rad);
        Self {
            x_m,
            y_m,
            cos_q30,
            sin_q30,
        }
    }

    /// Converts an f32 pose (host side or boot time: three float conversions).
    ///
    /// # Errors
    /// [`FixedError::PoseOutOfRange`]: a coordinate not finite or beyond ±32 768 m.
    pub fn from_pose(pose: &Pose) -> Result<Self, FixedError> {
        let conv = |v: f32| I16F16::checked_from_num(v).ok_or(FixedError::PoseOutOfRange);
        if !pose.is_finite() {
            return Err(FixedError::PoseOutOfRange);
        }
        let theta = crate::pose::wrap_angle(pose.theta_rad);
        Ok(Self::new(conv(pose.x_m)?, conv(pose.y_m)?, conv(theta)?))
    }
}

/// A beam layout converted for the fixed-point scorer: Q1.15 unit vectors and the mount.
#[derive(Clone, Debug)]
pub struct FixedLayout<const N: usize> {
    /// `(cos, sin)` of each bearing, Q1.15.
    beams: heapless::Vec<(i32, i32), N>,
    mount_x_m: I16F16,
    mount_y_m: I16F16,
    mount_cos_q30: i32,
    mount_sin_q30: i32,
}

impl<const N: usize> FixedLayout<N> {
    /// Converts `layout` (float, once per layout).
    ///
    /// # Errors
    /// [`FixedError::TooManyBeams`] when `N > MAX_FIXED_BEAMS`, [`FixedError::MountOutOfRange`].
    pub fn new(layout: &BeamLayout<N>) -> Result<Self, FixedError> {
        if N > MAX_FIXED_BEAMS {
            return Err(FixedError::TooManyBeams);
        }
        let mut beams = heapless::Vec::new();
        for b in layout.beams() {
            // |cos|, |sin| ≤ 1: at most 2¹⁵ in Q1.15.
            let q = |v: f32| libm_round(v * 32_768.0);
            beams
                .push((q(b.cos), q(b.sin)))
                .map_err(|_| FixedError::TooManyBeams)?;
        }
        let m = layout.mount();
        let conv = |v: f32| I16F16::checked_from_num(v).ok_or(FixedError::MountOutOfRange);
        if !(m.x_m.is_finite() && m.y_m.is_finite() && m.yaw_rad.is_finite()) {
            return Err(FixedError::MountOutOfRange);
        }
        let (mc, ms) = sin_cos_q30(conv(crate::pose::wrap_angle(m.yaw_rad))?);
        Ok(Self {
            beams,
            mount_x_m: conv(m.x_m)?,
            mount_y_m: conv(m.y_m)?,
            mount_cos_q30: mc,
            mount_sin_q30: ms,
        })
    }

    /// Number of beams.
    pub fn len(&self) -> usize {
        self.beams.len()
    }

    /// `true` without beams.
    pub fn is_empty(&self) -> bool {
        self.beams.is_empty()
    }
}

fn libm_round(v: f32) -> i32 {
    // Round half up; saturating `as`: callers pass bounded finite values.
    crate::math::floor(v + 0.5) as i32
}

/// A scan converted once for a [`FixedField`]: ranges in Q11.8 cells, skipped readings
/// marked `−1`, counts kept.
#[derive(Clone, Debug)]
pub struct FixedScan<const N: usize> {
    ranges_q8: heapless::Vec<i32, N>,
    max_range: u16,
    invalid: u16,
}

impl<const N: usize> FixedScan<N> {
    /// Converts the f32 ranges of `scan` (metres) for `field`: one multiply, compare and
    /// conversion per reading — the only float work per scan. Max-range readings (`≥
    /// max_range_m`) and invalid ones (NaN, negative) are marked skipped and counted, like the
    /// f32 path.
    pub fn from_scan(scan: &Scan<N>, field: &FixedField<'_>) -> Self {
        let mut out = Self::empty();
        let max_r = field.max_range_m;
        let per_m = field.range_q8_per_m;
        for &r in scan.ranges_m() {
            let is_invalid = r.is_nan() || r < 0.0;
            let is_max = r >= max_r;
            let q = if is_invalid || is_max {
                -1
            } else {
                // r < max_range < 2047 cells: q < 2¹⁹.
                libm_round(r * per_m)
            };
            out.max_range = out.max_range.saturating_add(u16::from(is_max));
            out.invalid = out.invalid.saturating_add(u16::from(is_invalid));
            // Capacity equals the scan's: never fails.
            let _ = out.ranges_q8.push(q);
        }
        out
    }

    /// Converts integer millimetre ranges with no float at all (one integer multiply each):
    /// `0` is the usual "no return" code of lidar drivers and counts as invalid, and readings
    /// at or above the field's max range count as max-range. Readings past `N` are dropped and
    /// counted as invalid.
    pub fn from_ranges_mm(ranges_mm: &[u16], field: &FixedField<'_>) -> Self {
        let mut out = Self::empty();
        for &mm in ranges_mm {
            let is_invalid = mm == 0;
            let is_max = u32::from(mm) >= field.max_range_mm;
            let q = if is_invalid || is_max {
                -1
            } else {
                // mm < max_range_mm < 2047 cells, so the result is below 2¹⁹; the product is
                // formed in u64 (once per reading, not per pose).
                ((u64::from(mm) * u64::from(field.range_q8_per_mm_q16) + (1 << 15)) >> 16) as i32
            };
            out.max_range = out.max_range.saturating_add(u16::from(is_max));
            let dropped = out.ranges_q8.push(q).is_err();
            out.invalid = out.invalid.saturating_add(u16::from(is_invalid || dropped));
        }
        out
    }

    fn empty() -> Self {
        Self {
            ranges_q8: heapless::Vec::new(),
            max_range: 0,
            invalid: 0,
        }
    }

    /// The converted ranges, Q11.8 cells; `−1` marks a skipped reading.
    pub fn ranges_q8(&self) -> &[i32] {
        &self.ranges_q8
    }
}

/// A fixed-point scan score (the counterpart of [`crate::ScanScore`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FixedScore {
    /// Sum of the scored beams' terms, nats.
    pub log_likelihood: I48F16,
    /// Beams scored.
    pub scored: u16,
    /// Readings skipped as max-range.
    pub max_range: u16,
    /// Readings skipped as invalid.
    pub invalid: u16,
    /// Readings past the layout's last beam.
    pub unpaired: u16,
}

impl FixedScore {
    /// The tempered log-likelihood `κ · Σ terms` (docs/models.md#tempering), one fixed-point
    /// multiply. `κ` must be in `(0, 1]`; values outside are clamped there.
    pub fn tempered(&self, kappa: I16F16) -> I48F16 {
        let k = i64::from(kappa.to_bits()).clamp(1, 1 << 16);
        // |Σ| < 2⁴⁷ (see MAX_FIXED_BEAMS), k ≤ 2¹⁶: no overflow.
        I48F16::from_bits((self.log_likelihood.to_bits() * k) >> 16)
    }
}

/// The likelihood field over one blob and one parameter set, in fixed point.
#[derive(Clone, Debug)]
pub struct FixedField<'a> {
    view: FieldView<'a>,
    /// `I16F16` raw terms, one per code.
    table: [i32; LIKELIHOOD_TABLE_LEN],
    origin_x_m: I16F16,
    origin_y_m: I16F16,
    /// Cells per metre, Q.16.
    inv_cell_q16: i64,
    width_q8: i32,
    height_q8: i32,
    last_ix: i32,
    last_iy: i32,
    /// Code steps per cell, Q.8 (< 2¹⁶).
    steps_per_cell_q8: u32,
    max_range_m: f32,
    max_range_mm: u32,
    range_q8_per_m: f32,
    /// Q11.8 cells per millimetre, Q.16 (below 2³² for any cell above 0.26 mm).
    range_q8_per_mm_q16: u32,
}

impl<'a> FixedField<'a> {
    /// Rounds the f32 field's term table to `I16F16` (error ≤ 2⁻¹⁷ nats per term) and
    /// converts the blob's geometry. Float work, once per parameter set.
    ///
    /// # Errors
    /// [`FixedError`]: a term below `−32 768`, a map above 2²² cells a side, an origin beyond
    /// ±32 768 m, `max_range_m ≥ 2047` cells, a cell outside `[d_max/1020, d_max]`.
    pub fn new(field: &LikelihoodField<'a>) -> Result<Self, FixedError> {
        let view = *field.view();
        let mut table = [0i32; LIKELIHOOD_TABLE_LEN];
        for (q, &t) in table.iter_mut().zip(field.table().iter()) {
            *q = I16F16::checked_from_num(t)
                .ok_or(FixedError::TermOutOfRange)?
                .to_bits();
        }
        let (w, h) = (view.width(), view.height());
        if w > 1 << 22 || h > 1 << 22 {
            return Err(FixedError::MapTooLarge);
        }
        let hd = view.header();
        let conv = |v: f32| I16F16::checked_from_num(v).ok_or(FixedError::OriginOutOfRange);
        let cell = view.cell_size_m();
        let spc = cell / view.step_m();
        if !(0.25..256.0).contains(&spc) {
            return Err(FixedError::CellSizeUnsupported);
        }
        let max_range_m = field.params().max_range_m();
        let max_cells = max_range_m / cell;
        if max_cells.is_nan() || max_cells >= MAX_RANGE_CELLS {
            return Err(FixedError::RangeTooLong);
        }
        let range_q8_per_m = 256.0 / cell;
        let max_range_mm = -crate::math::floor(-max_range_m * 1000.0).min(65_536.0) as u32;
        Ok(Self {
            view,
            table,
            origin_x_m: conv(hd.origin_x_m)?,
            origin_y_m: conv(hd.origin_y_m)?,
            inv_cell_q16: i64::from(libm_round_u(65_536.0 / cell)),
            width_q8: (w as i32) << 8,
            height_q8: (h as i32) << 8,
            last_ix: (w as i32).saturating_sub(1),
            last_iy: (h as i32).saturating_sub(1),
            steps_per_cell_q8: libm_round_u(spc * 256.0),
            max_range_m,
            max_range_mm,
            range_q8_per_m,
            range_q8_per_mm_q16: libm_round_u(range_q8_per_m * 65.536),
        })
    }

    /// The per-code terms, `I16F16` raw bits (nats · 2¹⁶).
    pub fn table_bits(&self) -> &[i32; LIKELIHOOD_TABLE_LEN] {
        &self.table
    }

    /// The blob this field reads.
    pub fn view(&self) -> &FieldView<'a> {
        &self.view
    }

    /// Log-likelihood of `scan` with the robot at `pose`: integer arithmetic only.
    pub fn score<const N: usize>(
        &self,
        layout: &FixedLayout<N>,
        scan: &FixedScan<N>,
        pose: &FixedPose,
    ) -> FixedScore {
        self.score_with(layout, scan, pose, |_, _| {})
    }

    /// As [`FixedField::score`], calling `each(beam_index, table_index)` for every scored beam.
    pub fn score_with<const N: usize, F: FnMut(usize, usize)>(
        &self,
        layout: &FixedLayout<N>,
        scan: &FixedScan<N>,
        pose: &FixedPose,
        mut each: F,
    ) -> FixedScore {
        let (ax, ay, c15, s15) = self.sensor_in_grid(layout, pose);
        let mut sum: i64 = 0;
        let mut scored: u32 = 0;
        for (k, (&(bx, by), &r)) in layout.beams.iter().zip(scan.ranges_q8.iter()).enumerate() {
            let idx = self.beam_index(ax, ay, c15, s15, bx, by, r);
            let term = self.table.get(idx).copied().unwrap_or(0);
            let valid = r >= 0;
            sum += i64::from(if valid { term } else { 0 });
            scored += u32::from(valid);
            if valid {
                each(k, idx);
            }
        }
        FixedScore {
            log_likelihood: I48F16::from_bits(sum),
            scored: u16::try_from(scored).unwrap_or(u16::MAX),
            max_range: scan.max_range,
            invalid: scan.invalid,
            unpaired: u16::try_from(scan.ranges_q8.len().saturating_sub(layout.beams.len()))
                .unwrap_or(u16::MAX),
        }
    }

    /// The per-beam loop alone, kept out of line with an unmangled name so that the
    /// disassembly check (`cargo xtask nofloat`) can find it. Returns the raw `I48F16` sum.
    #[inline(never)]
    pub fn sum_beams(&self, beams: &[(i32, i32)], ranges_q8: &[i32], sensor: [i32; 4]) -> i64 {
        let [ax, ay, c15, s15] = sensor;
        let mut sum: i64 = 0;
        for (&(bx, by), &r) in beams.iter().zip(ranges_q8) {
            let idx = self.beam_index(ax, ay, c15, s15, bx, by, r);
            let term = self.table.get(idx).copied().unwrap_or(0);
            sum += i64::from(if r >= 0 { term } else { 0 });
        }
        sum
    }

    /// Scores with [`FixedField::sum_beams`] (no callback, no counts): the hot path for a
    /// particle filter. Returns the raw sum as `I48F16`.
    pub fn score_sum<const N: usize>(
        &self,
        layout: &FixedLayout<N>,
        scan: &FixedScan<N>,
        pose: &FixedPose,
    ) -> I48F16 {
        let (ax, ay, c, s) = self.sensor_in_grid(layout, pose);
        I48F16::from_bits(self.sum_beams(&layout.beams, &scan.ranges_q8, [ax, ay, c, s]))
    }

    /// Per pose: the sensor's position in Q.8 grid cells and its heading's cos/sin in Q1.15.
    /// Integer only (a handful of 64-bit multiplies).
    fn sensor_in_grid<const N: usize>(
        &self,
        layout: &FixedLayout<N>,
        pose: &FixedPose,
    ) -> (i32, i32, i32, i32) {
        let (c, s) = (i64::from(pose.cos_q30), i64::from(pose.sin_q30));
        let (mx, my) = (
            i64::from(layout.mount_x_m.to_bits()),
            i64::from(layout.mount_y_m.to_bits()),
        );
        // Q16 metres: x + xs·cosθ − ys·sinθ (|xs·c| < 2³¹·2³¹).
        let sx = i64::from(pose.x_m.to_bits()) + ((mx * c - my * s) >> 30);
        let sy = i64::from(pose.y_m.to_bits()) + ((mx * s + my * c) >> 30);
        // Q.8 cells: (Q16 m)·(Q16 cells/m) >> 24. |Δ| < 2¹⁸ m·2¹⁶; inv_cell < 2²⁶: < 2⁶¹.
        let gx = ((sx - i64::from(self.origin_x_m.to_bits())) * self.inv_cell_q16) >> 24;
        let gy = ((sy - i64::from(self.origin_y_m.to_bits())) * self.inv_cell_q16) >> 24;
        // Far-away poses are clamped to ±2²⁹ (Q.8): such endpoints are off the map by far more
        // than the clamp of the off-map distance anyway.
        let lim = 1i64 << 29;
        let (gx, gy) = (gx.clamp(-lim, lim) as i32, gy.clamp(-lim, lim) as i32);
        // Heading of the sensor: pose ∘ mount yaw, Q2.30 → Q1.15.
        let (mc, ms) = (
            i64::from(layout.mount_cos_q30),
            i64::from(layout.mount_sin_q30),
        );
        let hc = (c * mc - s * ms) >> 30;
        let hs = (s * mc + c * ms) >> 30;
        let to15 = |v: i64| sat_i32((v + (1 << 14)) >> 15).clamp(-(1 << 15), 1 << 15);
        (gx, gy, to15(hc), to15(hs))
    }

    /// One beam's table index (0..=255). Bounds: |c15|, |s15|, |bx|, |by| ≤ 2¹⁵ and
    /// `c² + s² ≤ 1 + 2⁻¹⁴`, so `|c·bx − s·by| ≤ 2³⁰(1 + 2⁻¹⁴)` and the rounded `u` has
    /// `|u| ≤ 2¹⁵ + 2`; `0 ≤ r < 2¹⁹` splits into whole cells `rh < 2¹¹` and a Q.8 fraction
    /// `rl < 2⁸`, so `rh·u < 2²⁷` and `rl·u < 2²⁴`; `|ax| ≤ 2²⁹` so the endpoint < 2³⁰.
    /// Wrapping operations keep the path panic-free in every profile; the bounds make wrapping
    /// unreachable.
    ///
    /// Rounding: `u` to nearest (≤ 2⁻¹⁶ per component, plus the Q1.15 rounding of the beam and
    /// heading vectors), `r·u` rounded twice (≤ 1/256 cell), `r` itself to 1/512 cell.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn beam_index(&self, ax: i32, ay: i32, c: i32, s: i32, bx: i32, by: i32, r: i32) -> usize {
        const HALF: i32 = 1 << 14;
        let ux = c
            .wrapping_mul(bx)
            .wrapping_sub(s.wrapping_mul(by))
            .wrapping_add(HALF)
            >> 15;
        let uy = s
            .wrapping_mul(bx)
            .wrapping_add(c.wrapping_mul(by))
            .wrapping_add(HALF)
            >> 15;
        let r = r.max(0);
        let (rh, rl) = (r >> 8, r & 0xFF);
        // Whole cells · Q1.15 = Q.15 → Q.8 (>> 7); Q.8 fraction · Q1.15 = Q.23 → Q.8 (>> 15);
        // each rounded to nearest.
        let part = |h: i32, l: i32, u: i32| {
            (h.wrapping_mul(u).wrapping_add(1 << 6) >> 7)
                .wrapping_add(l.wrapping_mul(u).wrapping_add(HALF) >> 15)
        };
        let (dx, dy) = (part(rh, rl, ux), part(rh, rl, uy));
        let gx = ax.wrapping_add(dx);
        let gy = ay.wrapping_add(dy);
        // `max`/`min`, not `clamp`: clamp asserts its bounds (a panic path).
        let cx = gx.max(0).min(self.width_q8);
        let cy = gy.max(0).min(self.height_q8);
        let ix = (cx >> 8).min(self.last_ix) as u32;
        let iy = (cy >> 8).min(self.last_iy) as u32;
        let code = self.view.code_on_map(ix, iy).unwrap_or(CODE_MAX);
        let (ex, ey) = (gx.wrapping_sub(cx), gy.wrapping_sub(cy));
        let extra = if (ex | ey) == 0 {
            0
        } else {
            self.off_map_codes(ex, ey)
        };
        (u32::from(code) + extra).min(u32::from(CODE_MAX)) as usize
    }

    /// The off-map distance in code steps (rounded), from the Q.8 excursion `(ex, ey)`.
    #[inline(never)]
    fn off_map_codes(&self, ex: i32, ey: i32) -> u32 {
        let lim = OFF_MAP_CLAMP_CELLS << 4;
        // Q.4 cells, clamped: squares < 2²⁰·… the sum < 2²⁹.
        let ex4 = (ex >> 4).clamp(-lim, lim);
        let ey4 = (ey >> 4).clamp(-lim, lim);
        let d2 = (ex4 * ex4 + ey4 * ey4) as u32; // Q.8 cells²
        let d_q4 = isqrt(d2); // Q.4 cells, ≤ 23 171
                              // Q.4 · Q.8 = Q.12 codes; d_q4·spc_q8 < 2¹⁵·2¹⁶.
        (d_q4 * self.steps_per_cell_q8 + (1 << 11)) >> 12
    }
}

fn libm_round_u(v: f32) -> u32 {
    crate::math::floor(v + 0.5) as u32
}

/// `⌊√v⌋`, bit by bit (16 iterations, integer only).
fn isqrt(v: u32) -> u32 {
    let mut rem = v;
    let mut root = 0u32;
    let mut bit = 1u32 << 30;
    while bit > rem {
        bit >>= 2;
    }
    while bit != 0 {
        if rem >= root + bit {
            rem -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    root
}

// The `fixed` crate has no defmt support: these print the raw bits with their scale.
#[cfg(feature = "defmt")]
impl defmt::Format for FixedPose {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(
            f,
            "FixedPose {{ x: {=i32}/65536 m, y: {=i32}/65536 m, cos: {=i32}/2^30, sin: {=i32}/2^30 }}",
            self.x_m.to_bits(),
            self.y_m.to_bits(),
            self.cos_q30,
            self.sin_q30
        );
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for FixedScore {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(
            f,
            "FixedScore {{ log_likelihood: {=i64}/65536 nats, scored: {=u16}, max_range: {=u16}, invalid: {=u16}, unpaired: {=u16} }}",
            self.log_likelihood.to_bits(),
            self.scored,
            self.max_range,
            self.invalid,
            self.unpaired
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isqrt_brute_force() {
        for v in (0u32..200_000).chain([(1 << 29) - 1, 1 << 29, u32::MAX >> 2]) {
            let r = isqrt(v);
            assert!(u64::from(r) * u64::from(r) <= u64::from(v), "{v}");
            assert!(u64::from(r + 1) * u64::from(r + 1) > u64::from(v), "{v}");
        }
    }
}
