//! The exact squared Euclidean distance transform of an occupancy grid (docs/models.md#field).
//!
//! Felzenszwalb & Huttenlocher, *Distance Transforms of Sampled Functions* (Theory of Computing
//! 8, 2012): the squared transform is separable, so a 1-D transform runs down every column and
//! then along every row, and each 1-D transform is the lower envelope of the parabolas
//! `(q − p)² + f(p)`, found in O(n).
//!
//! Everything is integer: inputs and outputs are squared distances in **cell units** (a `u32`),
//! and the parabola intersections are exact rationals compared by cross-multiplication in
//! `i64` (see [`squared_edt`]). The result equals the brute-force definition
//! `min over occupied (i', j') of (i − i')² + (j − j')²` bit for bit
//! (`host-tests/tests/field_edt.rs` checks it on random grids and real maps).
//!
//! On a plain occupancy grid the column pass is two sweeps over whole rows, and a row is first
//! tried with a bounded window search in saturating byte arithmetic (16 cells per 128-bit
//! register) that is exact whenever its results are small enough (see [`squared_edt`]); the
//! envelope handles every other row.
//!
//! Memory belongs to the caller: the grid is transformed in place and three scratch slices of
//! [`edt_scratch_len`] elements are passed in. No allocation, no panic.

/// Marks a cell with no occupied cell anywhere in the grid (input: "not occupied").
///
/// On input, a cell holds `0` if it is occupied (a seed) and [`EDT_INFINITY`] otherwise. On
/// output it holds the squared distance to the nearest seed, or [`EDT_INFINITY`] when the grid
/// has no seed at all. Any other input value `f` is treated as a seed at squared height `f`
/// (the general sampled-function transform); values must stay below [`EDT_INFINITY`].
pub const EDT_INFINITY: u32 = u32::MAX;

/// The largest width or height [`squared_edt`] accepts, cells.
///
/// It keeps every squared distance `(w − 1)² + (h − 1)²` below 2³¹, far from [`EDT_INFINITY`].
pub const EDT_MAX_SIDE: usize = 32_768;

/// Why [`squared_edt`] refused to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EdtError {
    /// `grid.len()` is not `width · height` (or the product overflows).
    GridSizeMismatch,
    /// A side is larger than [`EDT_MAX_SIDE`].
    TooLarge,
    /// A scratch slice is shorter than [`edt_scratch_len`].
    ScratchTooSmall,
}

impl core::fmt::Display for EdtError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::GridSizeMismatch => "grid length is not width times height",
            Self::TooLarge => "grid side exceeds the transform's limit",
            Self::ScratchTooSmall => "scratch buffer too small",
        })
    }
}

impl core::error::Error for EdtError {}

/// The length each of the three scratch slices of [`squared_edt`] needs: `max(width, height) + 1`.
pub const fn edt_scratch_len(width: usize, height: usize) -> usize {
    if width > height {
        width + 1
    } else {
        height + 1
    }
}

/// Caller-owned scratch memory for [`squared_edt`]: the lower envelope of one row or column.
///
/// Each slice must hold at least [`edt_scratch_len`]`(width, height)` elements (one more than
/// the longest line, for a sentinel); longer is fine.
#[derive(Debug)]
pub struct EdtScratch<'a> {
    /// Positions of the parabolas of the lower envelope (F&H's `v`), cells.
    pub sites: &'a mut [u32],
    /// Numerators of the envelope's breakpoints (F&H's `z`, as exact rationals), squared cells.
    pub bounds: &'a mut [i64],
    /// Each envelope parabola's own value `f(p)` at its site, squared cells.
    pub heights: &'a mut [u32],
}

/// Transforms `grid` in place into exact squared Euclidean distances, in cell units.
///
/// `grid` is row-major, `width` cells per row, `height` rows (the row order does not matter to
/// the transform). See [`EDT_INFINITY`] for the input and output conventions. An empty grid
/// (`width` or `height` 0, `grid` empty) is accepted and left as it is.
///
/// A plain occupancy grid (every cell 0 or [`EDT_INFINITY`]) takes a fast path that reads and
/// writes the grid in memory order: the distance down each column comes from two sweeps over
/// whole rows, and each row, as soon as the upward sweep has finished it, is first tried with a
/// branch-free search of the 12 cells on either side, which is exact when every result is at
/// most 13² (nothing farther can do better). The search works on squares saturated at 255 in
/// bytes (saturation cannot hide a result ≤ 13²), 256 cells at a time in two stack buffers
/// (about 0.5 KiB); a row it does not settle goes to the envelope. Timings:
/// `host-tests/benches/field.rs`.
///
/// # Exactness
/// All arithmetic is integer: parabola intersections are rationals compared by
/// cross-multiplication in `i64` (no division, no rounding), so the lower envelope is the exact
/// one and every output is the exact minimum.
///
/// # Errors
/// [`EdtError::GridSizeMismatch`], [`EdtError::TooLarge`], [`EdtError::ScratchTooSmall`]; the
/// grid is untouched when an error is returned.
pub fn squared_edt(
    grid: &mut [u32],
    width: usize,
    height: usize,
    scratch: EdtScratch<'_>,
) -> Result<(), EdtError> {
    if width.checked_mul(height) != Some(grid.len()) {
        return Err(EdtError::GridSizeMismatch);
    }
    if width > EDT_MAX_SIDE || height > EDT_MAX_SIDE {
        return Err(EdtError::TooLarge);
    }
    let need = edt_scratch_len(width, height);
    if scratch.sites.len() < need || scratch.bounds.len() < need || scratch.heights.len() < need {
        return Err(EdtError::ScratchTooSmall);
    }
    if grid.is_empty() {
        return Ok(());
    }
    let mut env = Envelope {
        sites: scratch.sites,
        bounds: scratch.bounds,
        heights: scratch.heights,
    };
    // Whether every cell is 0 or EDT_INFINITY (both map to 0 or 1 under `v + 1`), checked a
    // block at a time without an early exit inside a block, so the check vectorizes.
    let binary = grid
        .chunks(256)
        .all(|b| b.iter().fold(true, |ok, &v| ok & (v.wrapping_add(1) <= 1)));
    if binary {
        binary_transform(grid, width, &mut env);
    } else {
        // General sampled function: the envelope down every column x, x + w, x + 2w, …
        for x in 0..width {
            let count = env.build(grid.iter().skip(x).step_by(width).copied());
            env.write(count, grid.iter_mut().skip(x).step_by(width));
        }
        for row in grid.chunks_exact_mut(width) {
            let count = env.build(row.iter().copied());
            env.write(count, row.iter_mut());
        }
    }
    Ok(())
}

/// A cell's column distance during the binary path when its column has no seed at all,
/// cells. Above every real column distance (those are below [`EDT_MAX_SIDE`]), and low enough
/// that adding a column's length to it stays below 2³¹, so the sweeps can compare as `i32`.
const NO_SEED: u32 = 1 << 30;

/// The transform of a plain occupancy grid, in memory order. Every cell must be 0 or
/// [`EDT_INFINITY`] on entry (the down-sweep relies on it; [`squared_edt`] checks it).
///
/// Column pass: a downward sweep over whole rows gives each cell its distance in cells to the
/// nearest seed at or above it in its column; an upward sweep takes the minimum with the one
/// below. Each row is final as soon as the upward sweep has used it for the row above, and
/// then takes its row pass at once (while it is still in cache): [`window_row`], or the
/// envelope over the squared column distances when the window does not settle it.
fn binary_transform(grid: &mut [u32], width: usize, env: &mut Envelope<'_>) {
    // Down: a seed stays 0, any other cell is one farther than the cell above it; row 0 has
    // only seeds and "no seed".
    let mut above: Option<&mut [u32]> = None;
    for row in grid.chunks_exact_mut(width) {
        match above {
            Some(a) => {
                for (c, &up) in row.iter_mut().zip(a.iter()) {
                    // `*c` is 0 or all ones, so the AND is 0 or `up + 1` (`up` ≤ NO_SEED +
                    // height: no overflow).
                    *c &= up + 1;
                }
            }
            None => {
                for c in row.iter_mut() {
                    *c &= NO_SEED;
                }
            }
        }
        above = Some(row);
    }
    // Up, with each finished row's row pass.
    let mut misses = RowPass::default();
    let mut below: Option<&mut [u32]> = None;
    for row in grid.chunks_exact_mut(width).rev() {
        if let Some(b) = below {
            for (c, &down) in row.iter_mut().zip(b.iter()) {
                // Every value is below 2³¹ (see NO_SEED), so a signed minimum is exact.
                *c = (*c as i32).min(down as i32 + 1) as u32;
            }
            misses.run(b, env);
        }
        below = Some(row);
    }
    if let Some(top) = below {
        misses.run(top, env);
    }
}

/// The row pass of the binary path, with its memory of recent rows the window did not settle.
#[derive(Default)]
struct RowPass {
    /// Rows still to send straight to the envelope after a miss.
    envelope_rows: usize,
}

impl RowPass {
    /// Replaces `row`'s column distances (cells, [`NO_SEED`] or more for none) with the
    /// squared distances to the nearest seed of the grid.
    fn run(&mut self, row: &mut [u32], env: &mut Envelope<'_>) {
        if self.envelope_rows == 0 {
            if let Some(out) = env.heights.get_mut(..row.len()) {
                if window_row(row, out) {
                    for (c, &v) in row.iter_mut().zip(out.iter()) {
                        *c = v;
                    }
                    return;
                }
            }
            // The window did not settle this row: the next rows, likely as sparse, go
            // straight to the envelope (a speed choice only; both give the same values).
            self.envelope_rows = ENVELOPE_ROWS_AFTER_MISS;
        } else {
            self.envelope_rows -= 1;
        }
        let count = env.build(row.iter().map(|&g| square_or_none(g)));
        env.write(count, row.iter_mut());
    }
}

/// `g²` for a column distance `g < EDT_MAX_SIDE`, [`EDT_INFINITY`] for "no seed" (any larger
/// value), squared cells.
fn square_or_none(g: u32) -> u32 {
    if (g as usize) < EDT_MAX_SIDE {
        g * g
    } else {
        EDT_INFINITY
    }
}

/// The half-width, in cells, of the window [`window_row`] searches.
const WINDOW: usize = 12;

/// A windowed minimum at most this is exact: every cell more than [`WINDOW`] columns away adds
/// at least `(WINDOW + 1)²` on its own. Squared cells; below `u8::MAX`, which the window's
/// byte arithmetic saturates at.
const WINDOW_EXACT_UP_TO: u8 = ((WINDOW + 1) * (WINDOW + 1)) as u8;

/// How many rows skip the window and go to the envelope after a row the window did not settle.
const ENVELOPE_ROWS_AFTER_MISS: usize = 8;

/// How many cells of a row [`window_row`] handles at once (its two stack buffers hold
/// `2 · TILE + 2 · WINDOW` bytes).
const TILE: usize = 256;

/// A column distance's square as a byte, saturated: `min(g, 16)²`, then at most 255. Every
/// value the window computes from it is then `min(true value, 255)`: saturation commutes with
/// adding a non-negative square and with taking minima.
fn saturated_square(g: u32) -> u8 {
    // Written as a signed 16-bit clamp, a 16-bit minimum and product and an unsigned byte
    // clamp, the forms SSE2 has single instructions for (`g` is below 2³¹, see `NO_SEED`).
    let g16 = (g as i32).clamp(i32::from(i16::MIN), i32::from(i16::MAX)) as i16;
    let m = g16.min(16);
    (m * m).clamp(0, 255) as u8
}

/// The row pass by a bounded search: `out[x] = min over |d| ≤ WINDOW of row[x + d]² + d²`, with
/// `row` the column distances. Returns whether every `out[x]` is at most
/// [`WINDOW_EXACT_UP_TO`]; then every `out[x]` is the exact row minimum (cells outside the
/// window cannot beat it). Otherwise `out` is not the answer and the caller runs the envelope.
///
/// The search runs on saturated byte squares (see [`saturated_square`]), [`TILE`] cells at a
/// time, in branch-free loops over whole slices, so it vectorizes 16 cells to a 128-bit
/// register. `out` is as long as `row` (the caller passes a scratch slice cut to the row's
/// length).
fn window_row(row: &[u32], out: &mut [u32]) -> bool {
    let mut start = 0usize;
    for out_tile in out.chunks_mut(TILE) {
        let n = out_tile.len();
        // `padded[i]` holds cell `start + i − WINDOW`; cells off the row stay saturated.
        let mut padded = [u8::MAX; TILE + 2 * WINDOW];
        let lo = start.saturating_sub(WINDOW);
        let hi = (start + n + WINDOW).min(row.len());
        let first = WINDOW - (start - lo);
        let src = row.get(lo..hi).unwrap_or(&[]);
        let dst = padded.get_mut(first..first + src.len()).unwrap_or(&mut []);
        for (p, &g) in dst.iter_mut().zip(src.iter()) {
            *p = saturated_square(g);
        }
        // `best[i]` for cell `start + i`: the cell itself, then offsets 1 to WINDOW, each a
        // vectorized pass over the tile with its square as a constant.
        let mut best = [0u8; TILE];
        let best = best.get_mut(..n).unwrap_or(&mut []);
        for (b, &v) in best.iter_mut().zip(padded.get(WINDOW..).unwrap_or(&[])) {
            *b = v;
        }
        window_step::<1>(best, &padded);
        window_step::<2>(best, &padded);
        window_step::<3>(best, &padded);
        window_step::<4>(best, &padded);
        window_step::<5>(best, &padded);
        window_step::<6>(best, &padded);
        window_step::<7>(best, &padded);
        window_step::<8>(best, &padded);
        window_step::<9>(best, &padded);
        window_step::<10>(best, &padded);
        window_step::<11>(best, &padded);
        window_step::<12>(best, &padded);
        if best.iter().fold(0u8, |m, &v| m.max(v)) > WINDOW_EXACT_UP_TO {
            return false;
        }
        for (o, &b) in out_tile.iter_mut().zip(best.iter()) {
            *o = u32::from(b);
        }
        start += n;
    }
    true
}

// `window_row` makes one `window_step` call per offset, written out.
const _: () = assert!(WINDOW == 12);

/// One offset `D` of [`window_row`]'s search over a tile: `best[i]` takes the minimum with
/// `min(padded[WINDOW + i − D], padded[WINDOW + i + D]) + D²` (saturating). A const
/// parameter, so that `D²` and the offsets are constants in each call.
#[inline(always)]
fn window_step<const D: usize>(best: &mut [u8], padded: &[u8]) {
    let d2 = (D * D) as u8;
    let left = padded.get(WINDOW - D..).unwrap_or(&[]);
    let right = padded.get(WINDOW + D..).unwrap_or(&[]);
    for (b, (&l, &r)) in best.iter_mut().zip(left.iter().zip(right.iter())) {
        *b = (*b).min(l.min(r).saturating_add(d2));
    }
}

/// The lower envelope of the parabolas `(x − p)² + f(p)` of one line (F&H's 1-D transform),
/// kept as a stack in the caller's scratch: parabola `k` sits at `sites[k]` with value
/// `heights[k]` there, and for `k ≥ 1` becomes the lowest at the real abscissa
/// `s_k = bounds[k] / (2·(sites[k] − sites[k−1]))` (its intersection with parabola `k − 1`;
/// `s_0 = −∞`). Numerators stay below 2³² in magnitude and denominators below 2¹⁷, so the
/// cross-multiplied comparisons are exact in `i64`.
///
/// Every slice holds at least one more element than the line is long (checked by
/// [`squared_edt`]); the `get` fallbacks below are never taken.
struct Envelope<'a> {
    sites: &'a mut [u32],
    bounds: &'a mut [i64],
    heights: &'a mut [u32],
}

/// The top parabola of the envelope while it is built: site `p`, `h = f(p) + p²`, and its
/// breakpoint `num / den` against the parabola below it (meaningless for the bottom one).
#[derive(Clone, Copy)]
struct Top {
    p: i64,
    h: i64,
    num: i64,
    den: i64,
}

impl Envelope<'_> {
    fn site(&self, k: usize) -> i64 {
        i64::from(self.sites.get(k).copied().unwrap_or(0))
    }

    fn height(&self, k: usize) -> i64 {
        i64::from(self.heights.get(k).copied().unwrap_or(0))
    }

    /// Parabola `k` as the top of the stack (`k ≥ 1`, so it has one below it).
    fn top(&self, k: usize) -> Top {
        let p = self.site(k);
        Top {
            p,
            h: self.height(k) + p * p,
            num: self.bounds.get(k).copied().unwrap_or(0),
            den: 2 * (p - self.site(k.wrapping_sub(1))),
        }
    }

    fn set(&mut self, k: usize, site: u32, height: u32, bound: i64) {
        if let Some(v) = self.sites.get_mut(k) {
            *v = site;
        }
        if let Some(v) = self.heights.get_mut(k) {
            *v = height;
        }
        if let Some(v) = self.bounds.get_mut(k) {
            *v = bound;
        }
    }

    /// Builds the envelope of `values` (item `q` is `f(q)`; [`EDT_INFINITY`] = no parabola)
    /// and returns how many parabolas it holds.
    fn build(&mut self, values: impl Iterator<Item = u32>) -> usize {
        let mut count = 0usize;
        let mut top = Top {
            p: 0,
            h: 0,
            num: 0,
            den: 1,
        };
        for (q, fq) in values.enumerate() {
            if fq == EDT_INFINITY {
                continue;
            }
            let qi = q as i64;
            let hq = i64::from(fq) + qi * qi;
            // The new parabola meets the top one at num / den; the top one is popped when
            // that is no later than where it took over itself (it is then never the lowest).
            let (mut num, mut den) = (0i64, 1i64);
            while count > 0 {
                num = hq - top.h;
                den = 2 * (qi - top.p);
                if count > 1 && num * top.den <= top.num * den {
                    count -= 1;
                    if count > 1 {
                        top = self.top(count - 1);
                    } else {
                        top.p = self.site(0);
                        top.h = self.height(0) + top.p * top.p;
                    }
                } else {
                    break;
                }
            }
            self.set(count, q as u32, fq, num);
            top = Top {
                p: qi,
                h: hq,
                num,
                den,
            };
            count += 1;
        }
        count
    }

    /// Writes the envelope's value at `q = 0, 1, …` to `out` ([`EDT_INFINITY`] everywhere
    /// when it is empty).
    fn write<'o>(&mut self, count: usize, out: impl Iterator<Item = &'o mut u32>) {
        let Some(last) = count.checked_sub(1) else {
            for o in out {
                *o = EDT_INFINITY;
            }
            return;
        };
        // A sentinel breakpoint after the last parabola that no q reaches.
        let after = self.sites.get(last).copied().unwrap_or(0).saturating_add(1);
        self.set(count, after, 0, i64::MAX);
        let mut k = 0usize;
        let mut p = self.site(0);
        let mut f = self.height(0);
        let mut next_num = self.bounds.get(1).copied().unwrap_or(i64::MAX);
        let mut next_den = 2 * (self.site(1) - p);
        for (q, o) in out.enumerate() {
            let qi = q as i64;
            // Move on while the next parabola takes over strictly before q.
            while next_num < qi * next_den {
                k += 1;
                p = self.site(k);
                f = self.height(k);
                next_num = self.bounds.get(k + 1).copied().unwrap_or(i64::MAX);
                next_den = 2 * (self.site(k + 1) - p);
            }
            let d = qi - p;
            *o = u32::try_from(f + d * d).unwrap_or(EDT_INFINITY);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(seeds: &[u32], w: usize, h: usize) -> Vec<u32> {
        let mut out = vec![EDT_INFINITY; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut best = u64::MAX;
                for sy in 0..h {
                    for sx in 0..w {
                        if seeds[sy * w + sx] == 0 {
                            let d = (x.abs_diff(sx) as u64).pow(2) + (y.abs_diff(sy) as u64).pow(2);
                            best = best.min(d);
                        }
                    }
                }
                if best != u64::MAX {
                    out[y * w + x] = best as u32;
                }
            }
        }
        out
    }

    fn run(grid: &mut [u32], w: usize, h: usize) {
        let n = edt_scratch_len(w, h);
        let (mut a, mut b, mut c) = (vec![0u32; n], vec![0i64; n], vec![0u32; n]);
        squared_edt(
            grid,
            w,
            h,
            EdtScratch {
                sites: &mut a,
                bounds: &mut b,
                heights: &mut c,
            },
        )
        .unwrap();
    }

    #[test]
    fn small_table_against_brute_force() {
        let i = EDT_INFINITY;
        let cases: [(usize, usize, Vec<u32>); 4] = [
            (3, 3, vec![i, i, i, i, 0, i, i, i, i]),
            (4, 2, vec![0, i, i, i, i, i, i, 0]),
            (5, 1, vec![i, i, i, i, 0]),
            (2, 2, vec![i, i, i, i]),
        ];
        for (w, h, seeds) in cases {
            let mut g = seeds.clone();
            run(&mut g, w, h);
            assert_eq!(g, brute(&seeds, w, h), "{w}×{h}");
        }
    }

    /// The general sampled-function path (values other than 0 and ∞), against its brute-force
    /// definition `min over (x', y') of f(x', y') + (x − x')² + (y − y')²`.
    #[test]
    fn general_values_against_brute_force() {
        let mut rng = crate::mcl::XorShift64::new(0x2545_F491_4F6C_DD1Du64);
        let mut next = || rng.next_word();
        for _ in 0..300 {
            let w = (next() % 13) as usize + 1;
            let h = (next() % 13) as usize + 1;
            let f: Vec<u32> = (0..w * h)
                .map(|_| match next() % 4 {
                    0 => (next() % 200) as u32,
                    1 => 0,
                    _ => EDT_INFINITY,
                })
                .collect();
            let mut want = vec![EDT_INFINITY; w * h];
            for y in 0..h {
                for x in 0..w {
                    for sy in 0..h {
                        for sx in 0..w {
                            let v = f[sy * w + sx];
                            if v != EDT_INFINITY {
                                let d = v + (x.abs_diff(sx).pow(2) + y.abs_diff(sy).pow(2)) as u32;
                                want[y * w + x] = want[y * w + x].min(d);
                            }
                        }
                    }
                }
            }
            let mut g = f.clone();
            run(&mut g, w, h);
            assert_eq!(g, want, "{w}×{h} {f:?}");
        }
    }

    /// The byte square saturates exactly: `min(g², 255)`, and "no seed" gives 255.
    #[test]
    fn saturated_square_is_clamped_square() {
        for g in (0u32..300).chain([EDT_MAX_SIDE as u32 - 1, NO_SEED, NO_SEED + 40_000]) {
            let want = u64::from(g).pow(2).min(255) as u8;
            assert_eq!(saturated_square(g), want, "g = {g}");
        }
    }

    /// The window search on rows longer than a tile (cells near tile edges see across them):
    /// whenever it reports success, every output is the exact 1-D minimum; a row whose every
    /// minimum is within WINDOW² must succeed (and many do, so the comparison is made); a row
    /// with a cell 14 columns from every seed must not.
    #[test]
    fn window_row_against_brute_force() {
        let mut rng = crate::mcl::XorShift64::new(0x9E37_79B9_7F4A_7C15u64);
        let mut next = || rng.next_word();
        let mut settled = 0;
        for len in [
            1usize, 15, 16, 17, 255, 256, 257, 280, 511, 512, 513, 700, 1030,
        ] {
            for i in 0..40 {
                // Column distances: dense rows (mostly small, some large, some "no seed"), and
                // sparse rows whose minima are often just beyond the window's reach.
                let row: Vec<u32> = (0..len)
                    .map(|_| {
                        if i % 2 == 0 {
                            match next() % 10 {
                                0..=5 => (next() % 12) as u32,
                                6 | 7 => (next() % 40) as u32,
                                8 => NO_SEED,
                                _ => (next() % 20_000) as u32,
                            }
                        } else if next() % 13 == 0 {
                            (next() % 16) as u32
                        } else {
                            NO_SEED
                        }
                    })
                    .collect();
                let want: Vec<u32> = (0..len)
                    .map(|x| {
                        (0..len)
                            .filter(|&p| (row[p] as usize) < EDT_MAX_SIDE)
                            .map(|p| row[p].pow(2) + (x.abs_diff(p) as u32).pow(2))
                            .min()
                            .unwrap_or(EDT_INFINITY)
                    })
                    .collect();
                let mut out = vec![0u32; len];
                let ok = window_row(&row, &mut out);
                // Every minimum within WINDOW² comes from inside the window: settled.
                let near = (WINDOW * WINDOW) as u32;
                assert!(ok || want.iter().any(|&v| v > near), "len {len}");
                if ok {
                    assert_eq!(out, want, "len {len}");
                    settled += 1;
                }
            }
        }
        assert!(settled > 100, "only {settled} rows settled by the window");
        // One cell 14 columns from every seed: 14² > 13², not settled.
        let mut row = vec![0u32; 600];
        for v in &mut row[286..=314] {
            *v = NO_SEED;
        }
        let mut out = vec![0u32; 600];
        assert!(!window_row(&row, &mut out));
    }

    #[test]
    fn errors() {
        let mut g = [0u32; 6];
        let mut a = [0u32; 4];
        let mut b = [0i64; 4];
        let mut c = [0u32; 4];
        assert_eq!(
            squared_edt(
                &mut g,
                4,
                2,
                EdtScratch {
                    sites: &mut a,
                    bounds: &mut b,
                    heights: &mut c
                }
            ),
            Err(EdtError::GridSizeMismatch)
        );
        assert_eq!(
            squared_edt(
                &mut g,
                6,
                1,
                EdtScratch {
                    sites: &mut a,
                    bounds: &mut b,
                    heights: &mut c
                }
            ),
            Err(EdtError::ScratchTooSmall)
        );
    }
}
