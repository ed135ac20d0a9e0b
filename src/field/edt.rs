//! The exact squared Euclidean distance transform of an occupancy grid (models.md §3).
//!
//! Felzenszwalb & Huttenlocher, *Distance Transforms of Sampled Functions* (Theory of Computing
//! 8, 2012): the squared transform is separable, so a 1-D transform runs down every column and
//! then along every row, and each 1-D transform is the lower envelope of the parabolas
//! `(q − p)² + f(p)`, found in O(n).
//!
//! Everything is integer: inputs and outputs are squared distances in **cell units** (a `u32`),
//! and the parabola intersections are kept as their floors in `i64`, which is exact on the
//! integer lattice (see [`squared_edt`]). The result equals the brute-force definition
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
    /// Floors of the envelope's breakpoints (F&H's `z`).
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
/// Parabolas are compared at integer positions only. With `s` the real abscissa where the
/// parabola from `q` starts to be no higher than the one from `p < q`, the new parabola wins at
/// every integer `x > ⌊s⌋` and the old one at every integer `x < s`; at `x = s` they tie. So
/// keeping `⌊s⌋` (an exact `i64` floor division) instead of `s` changes no output value.
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
    // Columns: cells x, x + w, x + 2w, …
    for x in 0..width {
        for (dst, &src) in line.iter_mut().zip(grid.iter().skip(x).step_by(width)) {
            *dst = src;
        }
        let input = line.get(..height).unwrap_or(&[]);
        transform_line(input, grid.iter_mut().skip(x).step_by(width), sites, bounds);
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

/// The 1-D transform of `f` (values, [`EDT_INFINITY`] = no seed), written to `out` in order.
///
/// `sites` and `bounds` hold at least `f.len() + 1` elements (checked by the caller).
fn transform_line<'o>(
    f: &[u32],
    out: impl Iterator<Item = &'o mut u32>,
    sites: &mut [u32],
    bounds: &mut [i64],
) {
    // Build the lower envelope: `count` parabolas, parabola k at sites[k] is lowest on the
    // integers of (bounds[k], bounds[k + 1]].
    let mut count = 0usize;
    for (q, &fq) in f.iter().enumerate() {
        if fq == EDT_INFINITY {
            continue;
        }
        let q = q as i64;
        let hq = i64::from(fq) + q * q;
        let mut s = i64::MIN;
        while count > 0 {
            let k = count - 1;
            let p = i64::from(sites.get(k).copied().unwrap_or(0));
            let fp = f.get(p as usize).copied().map_or(i64::MAX / 4, i64::from);
            let cand = floor_div(hq - (fp + p * p), 2 * (q - p));
            if cand <= bounds.get(k).copied().unwrap_or(i64::MIN) {
                count -= 1;
            } else {
                s = cand;
                break;
            }
        }
        if let Some(v) = sites.get_mut(count) {
            *v = q as u32;
        }
        if let Some(b) = bounds.get_mut(count) {
            *b = s;
        }
        count += 1;
        if let Some(b) = bounds.get_mut(count) {
            *b = i64::MAX;
        }
    }
    if count == 0 {
        for o in out {
            *o = EDT_INFINITY;
        }
        return;
    }
    // Read it back, parabola by parabola: parabola k is lowest on the integers of
    // (bounds[k], bounds[k + 1]], clipped to the line.
    let mut out = out;
    let mut q = 0i64;
    let envelope = sites.iter().zip(bounds.windows(2)).take(count);
    for (&p, b) in envelope {
        let hi = b.get(1).copied().unwrap_or(i64::MAX);
        let fp = f.get(p as usize).copied().map_or(i64::MAX / 4, i64::from);
        let p = i64::from(p);
        while q <= hi {
            let Some(o) = out.next() else {
                return;
            };
            let d = q - p;
            *o = u32::try_from(fp + d * d).unwrap_or(EDT_INFINITY);
            q += 1;
        }
    }
}

/// `⌊num / den⌋` for `den > 0`, exactly.
///
/// A 64-bit integer division costs 40–90 cycles on common x86 cores; an f64 division is several
/// times cheaper. The f64 quotient of these operands (below 2⁴⁰ in magnitude) is within 2⁻¹² of
/// the exact one, so its truncation is within one of the floor, and the integer corrections
/// below make the result exact.
#[inline]
fn floor_div(num: i64, den: i64) -> i64 {
    let mut s = (num as f64 / den as f64) as i64;
    while s.saturating_mul(den) > num {
        s -= 1;
    }
    while s.saturating_add(1).saturating_mul(den) <= num {
        s += 1;
    }
    s
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

    #[test]
    fn floor_div_matches_div_euclid() {
        let nums = [
            -1_000_000_007i64,
            -7,
            -6,
            -1,
            0,
            1,
            5,
            6,
            7,
            4_294_967_295,
            (1 << 40) - 3,
        ];
        for num in nums {
            for den in [1i64, 2, 3, 7, 64, 65_535, 131_070] {
                assert_eq!(floor_div(num, den), num.div_euclid(den), "{num}/{den}");
            }
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
