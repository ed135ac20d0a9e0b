//! Ray casting through a distance-field blob: the beam model's `z*` on the device.
//!
//! # Which cells stop a ray
//! The blob stores, per cell, the Euclidean distance from the cell's centre to the centre of
//! the nearest occupied cell, quantized as `code = round(d / step)` with `step = d_max / 255`.
//! An occupied cell has `d = 0`, hence code 0. Every other cell is at least one cell length
//! away from any occupied cell (`d ≥ s`, `s` the cell size), so its code is `round(s / step)`
//! or more, which is ≥ 1 exactly when `s ≥ step / 2`, i.e. `d_max ≤ 510·s`. Under that
//! condition **code 0 ⇔ occupied**, and [`RayCaster::new`] checks it: a blob that breaks it
//! (a very coarse step on a fine grid, e.g. `d_max = 30 m` on 5 cm cells) is refused with
//! [`RayCastError::StepTooCoarse`] rather than giving walls one cell too thick. Unknown cells
//! are not occupied in the blob, so they do not stop a ray (as in the host reference,
//! `ray_cast_grid` in the tools).
//!
//! # Algorithm
//! A grid traversal (Amanatides & Woo 1987) that visits, in order, every cell the ray crosses,
//! accelerated by sphere tracing: in a cell with code `c` no occupied cell lies within
//!
//! ```text
//! safe = c·step − step/2 − √2·s
//! ```
//!
//! of any point of the cell (the stored distance is within `step/2` of the centre-to-centre
//! distance; a point of the cell is within `s/√2` of its centre, and an occupied cell's
//! boundary within `s/√2` of its own). So when `safe` exceeds [`JUMP_MIN_CELLS`] cells the ray
//! jumps that far at once and restarts the traversal there; near walls it steps cell by cell.
//! The ray first is clipped to the map's rectangle; nothing off the map is occupied, so a ray
//! that leaves the map, or that never meets an occupied cell within range, returns the range
//! limit. A ray starting inside an occupied cell returns 0.
//!
//! The traversal walks a linear index into the payload (±1 per x step, ±width per y step) and
//! counts the steps left to each edge of the map, so a cell costs one load, two integer compares
//! and one f32 compare; the jump test is an integer compare against the smallest code that
//! jumps (tabulated once). [`RayCaster::with_min_jump_cells`] sets that threshold: on the
//! Intel race (91 real scans, 16,380 casts) the default 2 cells takes 6.2 jumps and 6.5 cell
//! steps per cast on average; 8 cells takes 3.2 and 22.4 (fewer scattered memory reads: faster
//! on a host with caches, slower on the Cortex-M4F, where a jump costs more instructions than
//! a step; docs/race.md). [`RayCaster::cast_dir_traced`] counts them per cast.
//!
//! # Several rays at once
//! A single cast is a chain of dependent work: each jump's landing cell comes from the code
//! just read, through a few f32 operations, a conversion and a load. [`RayCaster::cast_dirs`]
//! casts many directions from one start with [`CAST_LANES`] rays in flight: each ray runs its
//! cell steps up to its next jump, then the next ray takes over, so the core overlaps one
//! ray's jump with another's steps. Every ray runs the same per-ray code as
//! [`RayCaster::cast_dir`], so the ranges are identical bit for bit (tested on every beam of
//! many poses on the Intel blob and on random blobs). On the host the race's casts take about
//! 0.8× the time this way (docs/race.md); on the Cortex-M4F, with nothing to overlap, it only
//! adds instructions, so [`crate::BeamFieldModel`] casts one by one there.
//!
//! The returned range is the distance, metres, from the start to where the ray enters the
//! first occupied cell (f32 arithmetic in cell units; the traversal never skips a cell the ray
//! crosses except by rounding at exact corner passages).

use crate::field::FieldView;
use crate::math;

/// Jumps shorter than this many cells are not worth restarting the traversal for.
pub const JUMP_MIN_CELLS: f32 = 2.0;

/// Rays [`RayCaster::cast_dirs`] traces at once, interleaved.
pub const CAST_LANES: usize = 8;

/// Why a blob cannot be ray cast.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum RayCastError {
    /// The distance step `d_max/255` exceeds twice the cell size, so a free cell next to a
    /// wall could read code 0 and occupied cells cannot be told from their neighbours.
    StepTooCoarse,
}

impl core::fmt::Display for RayCastError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::StepTooCoarse => f.write_str("distance step exceeds twice the cell size"),
        }
    }
}

impl core::error::Error for RayCastError {}

/// Counts of the work one cast did, for profiling where the time goes
/// ([`RayCaster::cast_dir_traced`]). The plain casts count nothing and cost nothing for it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CastTrace {
    /// Sphere-tracing jumps: each one skips `safe` cells and restarts the traversal.
    pub jumps: u32,
    /// Cell-to-cell steps of the grid traversal (cells visited one by one).
    pub steps: u32,
}

/// What the traversal reports as it goes; a no-op for the plain casts.
trait Probe {
    fn jump(&mut self);
    fn step(&mut self);
}

/// Counts nothing.
struct NoProbe;

impl Probe for NoProbe {
    #[inline(always)]
    fn jump(&mut self) {}
    #[inline(always)]
    fn step(&mut self) {}
}

impl Probe for CastTrace {
    #[inline(always)]
    fn jump(&mut self) {
        self.jumps = self.jumps.saturating_add(1);
    }
    #[inline(always)]
    fn step(&mut self) {
        self.steps = self.steps.saturating_add(1);
    }
}

/// A ray caster over one blob: the per-blob constants, computed once.
#[derive(Clone, Copy, Debug)]
pub struct RayCaster<'a> {
    view: FieldView<'a>,
    /// The payload, row-major (row 0 = lowest y), `stride` codes per row; empty for a tiled
    /// blob, whose cells are read through [`FieldView`] (a miss here falls back to it).
    codes: &'a [u8],
    stride: usize,
    last_ix: u32,
    last_iy: u32,
    width_f: f32,
    height_f: f32,
    /// Code step in cell units.
    step_cells: f32,
    /// `step/2 + √2` in cell units: subtracted from a stored distance to get a safe jump.
    jump_margin_cells: f32,
    /// The smallest code whose safe jump exceeds [`JUMP_MIN_CELLS`] (256: none does).
    jump_code: u16,
}

impl<'a> RayCaster<'a> {
    /// Checks that code 0 means "occupied" for this blob (see the module docs).
    ///
    /// # Errors
    /// [`RayCastError::StepTooCoarse`] when `d_max/255 > 2·cell_size`.
    pub fn new(view: FieldView<'a>) -> Result<Self, RayCastError> {
        let cell = view.cell_size_m();
        let step = view.step_m();
        if step > 2.0 * cell {
            return Err(RayCastError::StepTooCoarse);
        }
        let step_cells = step / cell;
        let jump_margin_cells = 0.5 * step_cells + core::f32::consts::SQRT_2;
        // The same comparison the traversal made per cell before it was tabulated here: a code
        // jumps iff `code·step − margin > JUMP_MIN_CELLS` (monotone in the code).
        Ok(Self {
            view,
            codes: view.codes(),
            stride: view.width() as usize,
            last_ix: view.width().saturating_sub(1),
            last_iy: view.height().saturating_sub(1),
            width_f: view.width() as f32,
            height_f: view.height() as f32,
            step_cells,
            jump_margin_cells,
            jump_code: jump_code(step_cells, jump_margin_cells, JUMP_MIN_CELLS),
        }
        .with_min_jump_cells(JUMP_MIN_CELLS))
    }

    /// A cell past encoding 1's slice: a tiled blob's cell, or `None` past the map. Out of
    /// line, so the traversal's loop keeps only the raw read. Only with `tiled-field`: without
    /// it a miss of the raw slice is past the map, and the traversal gives `None` in line.
    #[cfg(feature = "tiled-field")]
    #[inline(never)]
    #[cold]
    fn code_slow(&self, idx: usize) -> Option<u8> {
        self.view.code_at_index(idx)
    }

    /// The same caster, jumping only where the safe jump exceeds `cells` (cell lengths;
    /// default [`JUMP_MIN_CELLS`]). A tuning knob for speed only: every jump is safe, so any
    /// value casts to the same first occupied cell (the entry distance may differ by f32
    /// rounding, as the traversal restarts at other points). NaN or negative reads as 0.
    pub fn with_min_jump_cells(mut self, cells: f32) -> Self {
        let cells = if cells >= 0.0 { cells } else { 0.0 };
        self.jump_code = jump_code(self.step_cells, self.jump_margin_cells, cells);
        self
    }

    /// The blob this caster reads.
    pub fn view(&self) -> &FieldView<'a> {
        &self.view
    }

    /// Distance, metres, from `(x_m, y_m)` (map frame) along `angle_rad` to the first occupied
    /// cell, or `max_range_m` when there is none within it (including a ray that leaves the
    /// map). Never more than `max_range_m`; NaN input gives `max_range_m`.
    pub fn cast(&self, x_m: f32, y_m: f32, angle_rad: f32, max_range_m: f32) -> f32 {
        let (s, c) = math::sin_cos(angle_rad);
        self.cast_dir(x_m, y_m, c, s, max_range_m)
    }

    /// As [`RayCaster::cast`], with the direction given as a unit vector `(ux, uy)`.
    pub fn cast_dir(&self, x_m: f32, y_m: f32, ux: f32, uy: f32, max_range_m: f32) -> f32 {
        self.cast_dir_probed(x_m, y_m, ux, uy, max_range_m, &mut NoProbe)
    }

    /// As [`RayCaster::cast_dir`] (same result, bit for bit), also adding the jumps and cell
    /// steps the cast took to `trace`.
    pub fn cast_dir_traced(
        &self,
        x_m: f32,
        y_m: f32,
        ux: f32,
        uy: f32,
        max_range_m: f32,
        trace: &mut CastTrace,
    ) -> f32 {
        self.cast_dir_probed(x_m, y_m, ux, uy, max_range_m, trace)
    }

    /// As [`RayCaster::cast_dir`] for many directions from one start: `out[i]` receives the
    /// range along the unit vector `dirs[i] = [ux, uy]`, bit for bit what `cast_dir` returns
    /// (a shorter `out` receives what fits; entries past `dirs` are left alone).
    ///
    /// The rays are interleaved, [`CAST_LANES`] at a time: each runs its cell steps until its
    /// next sphere-tracing jump, then the next one takes over, so the out-of-order core can
    /// work on one ray's cell steps while another's jump (a chain of dependent arithmetic and a
    /// load) completes. Stack: one ray state per lane (≈ 100 bytes each on a 64-bit host).
    pub fn cast_dirs(
        &self,
        x_m: f32,
        y_m: f32,
        dirs: &[[f32; 2]],
        max_range_m: f32,
        out: &mut [f32],
    ) {
        self.cast_dirs_lanes::<CAST_LANES>(x_m, y_m, dirs, max_range_m, out);
    }

    /// [`RayCaster::cast_dirs`] with `K` lanes instead of [`CAST_LANES`] (`K ≤ 1`: one ray at a
    /// time): the same results for every `K`, only the speed differs.
    pub fn cast_dirs_lanes<const K: usize>(
        &self,
        x_m: f32,
        y_m: f32,
        dirs: &[[f32; 2]],
        max_range_m: f32,
        out: &mut [f32],
    ) {
        let (ox, oy) = self.view.to_grid(x_m, y_m);
        let range_cells = max_range_m * self.view.inv_cell_size();
        let to_m = |done: Option<f32>| match done {
            Some(t) => (t * self.view.cell_size_m()).min(max_range_m),
            None => max_range_m,
        };
        if K <= 1 {
            for (&[ux, uy], o) in dirs.iter().zip(out.iter_mut()) {
                *o = to_m(self.cast_grid(ox, oy, ux, uy, range_cells, &mut NoProbe));
            }
            return;
        }
        let n = dirs.len().min(out.len());
        // Lane `k` traces `rays[k]` for `out[slots[k]]`; an idle lane has slot `usize::MAX`.
        let mut rays = [Ray::IDLE; K];
        let mut slots = [usize::MAX; K];
        let mut next = 0usize;
        let mut busy = 0usize;
        // Starts the next ray that reads a cell in the lane; rays that read none are written
        // at once. Returns whether the lane is busy.
        let refill = |ray: &mut Ray, slot: &mut usize, next: &mut usize, out: &mut [f32]| {
            while *next < n {
                let i = *next;
                *next += 1;
                let Some(&[ux, uy]) = dirs.get(i) else {
                    break;
                };
                match Ray::start(self, ox, oy, ux, uy, range_cells) {
                    Ok(r) => {
                        *ray = r;
                        *slot = i;
                        return true;
                    }
                    Err(done) => {
                        if let Some(o) = out.get_mut(i) {
                            *o = to_m(done);
                        }
                    }
                }
            }
            *slot = usize::MAX;
            false
        };
        for (ray, slot) in rays.iter_mut().zip(slots.iter_mut()) {
            if refill(ray, slot, &mut next, out) {
                busy += 1;
            }
        }
        while busy > 0 {
            for (ray, slot) in rays.iter_mut().zip(slots.iter_mut()) {
                if *slot == usize::MAX {
                    continue;
                }
                // This lane's cell steps up to its next jump (or its end).
                let done = match ray.run(self, &mut NoProbe) {
                    Run::Jump(t) => {
                        ray.walk = ray.restart(self, t);
                        None
                    }
                    Run::Done(done) => Some(done),
                };
                if let Some(done) = done {
                    if let Some(o) = out.get_mut(*slot) {
                        *o = to_m(done);
                    }
                    if !refill(ray, slot, &mut next, out) {
                        busy -= 1;
                    }
                }
            }
        }
    }

    #[inline(always)]
    fn cast_dir_probed<P: Probe>(
        &self,
        x_m: f32,
        y_m: f32,
        ux: f32,
        uy: f32,
        max_range_m: f32,
        probe: &mut P,
    ) -> f32 {
        let (ox, oy) = self.view.to_grid(x_m, y_m);
        let range_cells = max_range_m * self.view.inv_cell_size();
        match self.cast_grid(ox, oy, ux, uy, range_cells, probe) {
            Some(t) => (t * self.view.cell_size_m()).min(max_range_m),
            None => max_range_m,
        }
    }

    /// The traversal in grid units: the entry distance (cells) of the first occupied cell, or
    /// `None`.
    #[inline(always)]
    fn cast_grid<P: Probe>(
        &self,
        ox: f32,
        oy: f32,
        ux: f32,
        uy: f32,
        range_cells: f32,
        probe: &mut P,
    ) -> Option<f32> {
        let mut ray = match Ray::start(self, ox, oy, ux, uy, range_cells) {
            Ok(ray) => ray,
            Err(done) => return done,
        };
        loop {
            match ray.run(self, probe) {
                Run::Jump(t) => ray.walk = ray.restart(self, t),
                Run::Done(done) => return done,
            }
        }
    }
}

/// One ray's traversal, in grid units: its constants and where it is. [`RayCaster::cast_grid`]
/// drives one to the end; [`RayCaster::cast_dirs`] interleaves several, switching rays at each
/// jump. Both run the same [`Ray::run`] and [`Ray::restart`], so their results are identical
/// bit for bit.
#[derive(Clone, Copy, Debug)]
struct Ray {
    ox: f32,
    oy: f32,
    ux: f32,
    uy: f32,
    inv_x: f32,
    inv_y: f32,
    /// Where the ray leaves the map or reaches the range limit, cells.
    t_end: f32,
    /// Per step along x (y): the boundary coordinate moves by `dbx` (`dby`) and the index by
    /// `dix` (`diy`); from cell `i` the next boundary is `i + bx_off` (`i + by_off`).
    dbx: f32,
    dby: f32,
    bx_off: f32,
    by_off: f32,
    dix: isize,
    diy: isize,
    live_x: bool,
    live_y: bool,
    pos_x: bool,
    pos_y: bool,
    walk: Walk,
}

/// Where a ray's traversal is.
#[derive(Clone, Copy, Debug)]
struct Walk {
    /// Where the ray enters the current cell (or starts, or lands after a jump), cells.
    t: f32,
    /// The current cell's index into the payload.
    idx: usize,
    /// The next cell boundary along x (y), grid coordinates, and the ray's time to reach it.
    bx: f32,
    by: f32,
    t_x: f32,
    t_y: f32,
    /// Steps left along each axis before the traversal would leave the map.
    left_x: u32,
    left_y: u32,
}

impl Walk {
    const ZERO: Self = Self {
        t: 0.0,
        idx: 0,
        bx: 0.0,
        by: 0.0,
        t_x: 0.0,
        t_y: 0.0,
        left_x: 0,
        left_y: 0,
    };
}

impl Ray {
    /// A ray that reads cell 0 and stops there: the state of an idle lane.
    const IDLE: Self = Self {
        ox: 0.0,
        oy: 0.0,
        ux: 0.0,
        uy: 0.0,
        inv_x: 0.0,
        inv_y: 0.0,
        t_end: 0.0,
        dbx: 0.0,
        dby: 0.0,
        bx_off: 0.0,
        by_off: 0.0,
        dix: 0,
        diy: 0,
        live_x: false,
        live_y: false,
        pos_x: false,
        pos_y: false,
        walk: Walk::ZERO,
    };

    /// Clips the ray `o + t·u` (grid units) to the map and the range and places it in its first
    /// cell; `Err` with the cast's result when it reads no cell at all (`None`: off the map,
    /// non-finite input, or nothing within range).
    #[inline(always)]
    fn start(
        rc: &RayCaster<'_>,
        ox: f32,
        oy: f32,
        ux: f32,
        uy: f32,
        range_cells: f32,
    ) -> Result<Self, Option<f32>> {
        // `max`/`min` below drop NaNs, so non-finite input is turned away here.
        if !(ox.is_finite() && oy.is_finite() && ux.is_finite() && uy.is_finite()) {
            return Err(None);
        }
        let inv_x = 1.0 / ux;
        let inv_y = 1.0 / uy;
        // Clip to the map rectangle [0, W] × [0, H] (slab method). A zero component gives
        // infinite slab times; `min`/`max` drop the NaN of 0·∞ for an origin on the slab edge.
        let (tx0, tx1) = slab(ox, inv_x, rc.width_f);
        let (ty0, ty1) = slab(oy, inv_y, rc.height_f);
        let t_in = tx0.max(ty0).max(0.0);
        let t_end = tx1.min(ty1).min(range_cells);
        // Finite inputs (checked above) give no NaN here: an infinite `inv` takes the branch in `slab`.
        if t_in >= t_end {
            return Err(None);
        }
        // An axis whose `1/u` is infinite (a zero or subnormal component) never steps: its
        // boundary times stay at +∞. Otherwise `(b − o)·inv` is finite or ±∞, never NaN.
        let pos_x = ux > 0.0;
        let pos_y = uy > 0.0;
        // From cell `i` the next boundary is `i + 1` going up, `i` going down.
        let (dbx, bx_off, dix) = if pos_x {
            (1.0f32, 1.0f32, 1isize)
        } else {
            (-1.0, 0.0, -1)
        };
        let stride = rc.stride as isize;
        let (dby, by_off, diy) = if pos_y {
            (1.0f32, 1.0f32, stride)
        } else {
            (-1.0, 0.0, -stride)
        };
        let mut ray = Self {
            ox,
            oy,
            ux,
            uy,
            inv_x,
            inv_y,
            t_end,
            dbx,
            dby,
            bx_off,
            by_off,
            dix,
            diy,
            live_x: inv_x.is_finite(),
            live_y: inv_y.is_finite(),
            pos_x,
            pos_y,
            walk: Walk::ZERO,
        };
        ray.walk = ray.restart(rc, t_in);
        Ok(ray)
    }

    /// The traversal (re)started at `t`: the cell holding the point, clamped into the map (the
    /// point is on the rectangle up to rounding). `as u32` saturates, so a point a rounding
    /// error below 0 reads cell 0, and for `p ≥ 0` truncation is `floor`.
    #[inline(always)]
    fn restart(&self, rc: &RayCaster<'_>, t: f32) -> Walk {
        let px = self.ox + t * self.ux;
        let py = self.oy + t * self.uy;
        let ix = (px as u32).min(rc.last_ix);
        let iy = (py as u32).min(rc.last_iy);
        let bx = ix as f32 + self.bx_off;
        let by = iy as f32 + self.by_off;
        Walk {
            t,
            idx: (iy as usize)
                .wrapping_mul(rc.stride)
                .wrapping_add(ix as usize),
            bx,
            by,
            t_x: if self.live_x {
                (bx - self.ox) * self.inv_x
            } else {
                f32::INFINITY
            },
            t_y: if self.live_y {
                (by - self.oy) * self.inv_y
            } else {
                f32::INFINITY
            },
            left_x: if self.pos_x { rc.last_ix - ix } else { ix },
            left_y: if self.pos_y { rc.last_iy - iy } else { iy },
        }
    }

    /// Reads cells from the current one on, stepping cell by cell, until a cell allows a
    /// sphere-tracing jump ([`Run::Jump`] with where it lands, before the end of the ray; the
    /// caller restarts the traversal there) or the cast is over ([`Run::Done`]).
    #[inline(always)]
    fn run<P: Probe>(&self, rc: &RayCaster<'_>, probe: &mut P) -> Run {
        let Walk {
            mut t,
            mut idx,
            mut bx,
            mut by,
            mut t_x,
            mut t_y,
            mut left_x,
            mut left_y,
        } = self.walk;
        loop {
            // Encoding 1 reads the slice; a miss (past the map, or a tiled blob) asks the view,
            // which gives `None` past the map in both encodings. Without `tiled-field` a miss can
            // only be past the map: `None` in line, no call in the loop (a call site there, even
            // a cold one, costs the loop registers; docs/firmware.md).
            let code = match rc.codes.get(idx) {
                Some(&c) => c,
                #[cfg(not(feature = "tiled-field"))]
                None => return Run::Done(None),
                #[cfg(feature = "tiled-field")]
                None => match rc.code_slow(idx) {
                    Some(c) => c,
                    None => return Run::Done(None),
                },
            };
            if u16::from(code) >= rc.jump_code {
                probe.jump();
                t += f32::from(code) * rc.step_cells - rc.jump_margin_cells;
                if t >= self.t_end {
                    return Run::Done(None);
                }
                return Run::Jump(t);
            }
            if code == 0 {
                return Run::Done(Some(t));
            }
            probe.step();
            if t_x < t_y {
                let Some(left) = left_x.checked_sub(1) else {
                    return Run::Done(None);
                };
                left_x = left;
                t = t_x;
                bx += self.dbx;
                t_x = (bx - self.ox) * self.inv_x;
                idx = idx.wrapping_add_signed(self.dix);
            } else if t_y < t_x {
                let Some(left) = left_y.checked_sub(1) else {
                    return Run::Done(None);
                };
                left_y = left;
                t = t_y;
                by += self.dby;
                t_y = (by - self.oy) * self.inv_y;
                idx = idx.wrapping_add_signed(self.diy);
            } else {
                // Exactly through a corner: a diagonal step, like the host reference.
                let (Some(lx), Some(ly)) = (left_x.checked_sub(1), left_y.checked_sub(1)) else {
                    return Run::Done(None);
                };
                left_x = lx;
                left_y = ly;
                t = t_x;
                bx += self.dbx;
                by += self.dby;
                t_x = (bx - self.ox) * self.inv_x;
                t_y = (by - self.oy) * self.inv_y;
                idx = idx
                    .wrapping_add_signed(self.dix)
                    .wrapping_add_signed(self.diy);
            }
            if t >= self.t_end {
                return Run::Done(None);
            }
        }
    }
}

/// How a run of cell steps ([`Ray::run`]) ended.
enum Run {
    /// A jump to this distance, cells (before the end of the ray).
    Jump(f32),
    /// The cast's result: the entry distance of the first occupied cell, or `None`.
    Done(Option<f32>),
}

/// The smallest code whose safe jump `code·step − margin` (cells) exceeds `min_cells`, or 256
/// when none does: the traversal's per-cell test `safe > min_cells`, tabulated (monotone in
/// the code).
fn jump_code(step_cells: f32, margin_cells: f32, min_cells: f32) -> u16 {
    (0..=u8::MAX)
        .find(|&c| f32::from(c) * step_cells - margin_cells > min_cells)
        .map_or(256, u16::from)
}

/// Entry and exit times of a ray `o + t·u` through the slab `[0, size]` along one axis, with
/// `inv = 1/u` (`±∞` for `u = 0`: the whole line, or nothing, depending on `o`).
#[inline(always)]
fn slab(o: f32, inv: f32, size: f32) -> (f32, f32) {
    if inv.is_infinite() {
        return if (0.0..=size).contains(&o) {
            (f32::NEG_INFINITY, f32::INFINITY)
        } else {
            (f32::INFINITY, f32::NEG_INFINITY)
        };
    }
    let a = (0.0 - o) * inv;
    let b = (size - o) * inv;
    if a <= b {
        (a, b)
    } else {
        (b, a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{emit_blob, FieldHeader};

    /// 10 × 10 cells of 0.1 m at (−0.5, −0.5): a wall ring and one pillar at (5, 5), codes
    /// from a brute-force distance (independent of the crate's EDT).
    fn room_blob() -> Vec<u8> {
        let occupied = |c: i32, r: i32| c == 0 || r == 0 || c == 9 || r == 9 || (c == 5 && r == 5);
        let h = FieldHeader::new(10, 10, 0.1, -0.5, -0.5);
        let mut codes = vec![0u8; 100];
        for r in 0..10 {
            for c in 0..10 {
                let mut best = f64::INFINITY;
                for rr in 0..10 {
                    for cc in 0..10 {
                        if occupied(cc, rr) {
                            let d = f64::from((cc - c).pow(2) + (rr - r).pow(2)).sqrt() * 0.1;
                            best = best.min(d);
                        }
                    }
                }
                codes[(r * 10 + c) as usize] = h.encode_distance_m(best);
            }
        }
        let mut out = vec![0; h.required_len().unwrap()];
        emit_blob(&h, &codes, &mut out).unwrap();
        out
    }

    #[test]
    fn hand_made_room_known_answers() {
        let b = room_blob();
        let rc = RayCaster::new(FieldView::parse(&b).unwrap()).unwrap();
        // Centre of cell (2, 2) is (−0.25, −0.25).
        let (x, y) = (-0.25f32, -0.25f32);
        let pi = core::f32::consts::PI;
        let cases = [
            (x, y, 0.0, 0.65),
            (x, y, pi, 0.15),
            (x, y, pi / 2.0, 0.65),
            (x, y, -pi / 2.0, 0.15),
            // Into the pillar's corner (5, 5): 2.5·√2 cells.
            (x, y, pi / 4.0, 0.25 * core::f32::consts::SQRT_2),
            // Inside a wall cell.
            (-0.45, 0.0, 0.3, 0.0),
            // From off the map, entering the west wall at x = −0.5.
            (-1.0, 0.0, 0.0, 0.5),
            // From off the map, pointing away: max range.
            (-1.0, 0.0, pi, 5.0),
            // Range limit shorter than the wall.
            (x, y, 0.0, 0.3),
        ];
        // Any jump threshold gives the same answers (every jump is safe); NaN reads as 0.
        for min_jump in [JUMP_MIN_CELLS, 0.0, 0.5, 8.0, f32::NAN, -1.0] {
            let rc = rc.with_min_jump_cells(min_jump);
            for (i, (x, y, a, want)) in cases.into_iter().enumerate() {
                let limit = if i == 8 { 0.3 } else { 5.0 };
                let got = rc.cast(x, y, a, limit);
                assert!(
                    (got - want).abs() < 1e-5,
                    "min jump {min_jump}, case {i}: {got} vs {want}"
                );
            }
        }
        assert_eq!(rc.cast(f32::NAN, 0.0, 0.0, 5.0), 5.0);
        assert_eq!(rc.cast(0.0, 0.0, f32::NAN, 5.0), 5.0);
    }

    #[test]
    fn coarse_step_is_refused() {
        // d_max = 60 m on 0.1 m cells: step ≈ 0.235 m > 0.2 m.
        let mut h = FieldHeader::new(2, 2, 0.1, 0.0, 0.0);
        h.max_dist_m = 60.0;
        let mut out = vec![0; h.required_len().unwrap()];
        emit_blob(&h, &[0, 0, 0, 0], &mut out).unwrap();
        let v = FieldView::parse(&out).unwrap();
        assert_eq!(RayCaster::new(v).err(), Some(RayCastError::StepTooCoarse));
    }
}
