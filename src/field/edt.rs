//! The exact squared Euclidean distance transform of an occupancy grid (models.md §3).
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

/// Caller-owned scratch memory for [`squared_edt`].
///
/// Each slice must hold at least [`edt_scratch_len`]`(width, height)` elements; longer is fine.
#[derive(Debug)]
pub struct EdtScratch<'a> {
    /// Positions of the parabolas of the lower envelope (F&H's `v`).
    pub sites: &'a mut [u32],
    /// Numerators of the envelope's breakpoints (F&H's `z`, as exact rationals).
    pub bounds: &'a mut [i64],
    /// One row or column of input values, copied out of the grid.
    pub line: &'a mut [u32],
}

/// Transforms `grid` in place into exact squared Euclidean distances, in cell units.
///
/// `grid` is row-major, `width` cells per row, `height` rows (the row order does not matter to
/// the transform). See [`EDT_INFINITY`] for the input and output conventions. An empty grid
/// (`width` or `height` 0, `grid` empty) is accepted and left as it is.
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
    if scratch.sites.len() < need || scratch.bounds.len() < need || scratch.line.len() < need {
        return Err(EdtError::ScratchTooSmall);
    }
    if grid.is_empty() {
        return Ok(());
    }
    let EdtScratch {
        sites,
        bounds,
        line,
    } = scratch;
    if grid.iter().all(|&v| v == 0 || v == EDT_INFINITY) {
        // A plain occupancy grid: the column pass is the distance to the nearest seed in the
        // same column, found by two sweeps over whole rows (cache-friendly, vectorizable).
        binary_columns(grid, width);
    } else {
        // General sampled function: the lower envelope down every column x, x + w, x + 2w, …
        for x in 0..width {
            for (dst, &src) in line.iter_mut().zip(grid.iter().skip(x).step_by(width)) {
                *dst = src;
            }
            let input = line.get(..height).unwrap_or(&[]);
            transform_line(input, grid.iter_mut().skip(x).step_by(width), sites, bounds);
        }
    }
    // Rows.
    for row in grid.chunks_exact_mut(width) {
        for (dst, &src) in line.iter_mut().zip(row.iter()) {
            *dst = src;
        }
        let input = line.get(..width).unwrap_or(&[]);
        transform_line(input, row.iter_mut(), sites, bounds);
    }
    Ok(())
}

/// The column pass for a grid of 0 (seed) and [`EDT_INFINITY`]: each cell gets the squared
/// distance to the nearest seed in its column, or [`EDT_INFINITY`] if the column has none.
///
/// A downward sweep keeps the distance (in cells) to the nearest seed at or below each row, an
/// upward sweep takes the minimum with the nearest seed above; then the distances are squared.
/// Distances stay below [`EDT_MAX_SIDE`], so `EDT_INFINITY` (saturating) marks "no seed".
fn binary_columns(grid: &mut [u32], width: usize) {
    // Down: rows in increasing order; row 0 keeps its value (0 or "none").
    let mut prev: Option<&mut [u32]> = None;
    for row in grid.chunks_exact_mut(width) {
        if let Some(p) = prev {
            for (c, &a) in row.iter_mut().zip(p.iter()) {
                if *c != 0 {
                    *c = a.saturating_add(1);
                }
            }
        }
        prev = Some(row);
    }
    // Up: rows in decreasing order.
    let mut next: Option<&mut [u32]> = None;
    for row in grid.chunks_exact_mut(width).rev() {
        if let Some(n) = next {
            for (c, &b) in row.iter_mut().zip(n.iter()) {
                *c = (*c).min(b.saturating_add(1));
            }
        }
        next = Some(row);
    }
    for c in grid.iter_mut() {
        *c = c.saturating_mul(*c);
    }
}

/// The 1-D transform of `f` (values, [`EDT_INFINITY`] = no seed), written to `out` in order.
///
/// The lower envelope is kept as `count` parabolas at `sites[0..count]`; parabola `k ≥ 1`
/// becomes the lowest at the real abscissa `s_k = bounds[k] / (2·(sites[k] − sites[k−1]))`
/// (the intersection with its left neighbour; `s_0 = −∞`). Intersections are compared by
/// cross-multiplication, exactly, in `i64`: numerators stay below 2³², denominators below 2¹⁷.
/// `sites` and `bounds` hold at least `f.len()` elements (checked by the caller).
fn transform_line<'o>(
    f: &[u32],
    out: impl Iterator<Item = &'o mut u32>,
    sites: &mut [u32],
    bounds: &mut [i64],
) {
    let height =
        |p: i64| -> i64 { f.get(p as usize).copied().map_or(i64::MAX / 4, i64::from) + p * p };
    let site = |sites: &[u32], k: usize| i64::from(sites.get(k).copied().unwrap_or(0));
    let mut count = 0usize;
    for (q, &fq) in f.iter().enumerate() {
        if fq == EDT_INFINITY {
            continue;
        }
        let q = q as i64;
        let hq = i64::from(fq) + q * q;
        let mut num = 0i64;
        while count > 0 {
            let k = count - 1;
            let p = site(sites, k);
            // Intersection of parabola p with the new one: num / (2·(q − p)).
            num = hq - height(p);
            if k == 0 {
                break;
            }
            let den = 2 * (q - p);
            let num_k = bounds.get(k).copied().unwrap_or(i64::MIN);
            let den_k = 2 * (p - site(sites, k - 1));
            // Pop p when the new parabola takes over no later than p did: s ≤ s_k.
            if num * den_k <= num_k * den {
                count -= 1;
            } else {
                break;
            }
        }
        if let Some(v) = sites.get_mut(count) {
            *v = q as u32;
        }
        if let Some(b) = bounds.get_mut(count) {
            *b = num;
        }
        count += 1;
    }
    if count == 0 {
        for o in out {
            *o = EDT_INFINITY;
        }
        return;
    }
    // Read it back: move to parabola k + 1 while s_{k+1} < q.
    let mut k = 0usize;
    let mut p = site(sites, 0);
    let mut fp = height(p) - p * p;
    for (q, o) in out.enumerate() {
        let q = q as i64;
        while k + 1 < count {
            let next = site(sites, k + 1);
            let num = bounds.get(k + 1).copied().unwrap_or(i64::MAX);
            if num < q * 2 * (next - p) {
                k += 1;
                p = next;
                fp = height(p) - p * p;
            } else {
                break;
            }
        }
        let d = q - p;
        *o = u32::try_from(fp + d * d).unwrap_or(EDT_INFINITY);
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
                line: &mut c,
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
        let mut s = 0x2545_F491_4F6C_DD1Du64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
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
                    line: &mut c
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
                    line: &mut c
                }
            ),
            Err(EdtError::ScratchTooSmall)
        );
    }
}
