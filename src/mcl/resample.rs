//! Low-variance resampling (Thrun Table 4.4), in place, with one `u16` count per particle as
//! the only scratch.
//!
//! The textbook draws one `r ~ U[0, 1/M)` and picks, for `m = 0 … M−1`, the particle whose
//! cumulative weight first reaches `r + m/M`: a particle of weight `w` is copied `⌊wM⌋` or
//! `⌈wM⌉` times, and a set whose weights are all equal is kept as it is. Instead of writing the
//! picks into a second particle buffer, this module counts the copies of each particle
//! ([`low_variance_counts`]) and then rewrites the set in place ([`apply_counts`]): a particle
//! picked at least once keeps its slot, and its extra copies overwrite slots of particles that
//! were never picked. The resulting set is the textbook's, in another order.

use crate::gaussian::uniform_f32;
use crate::pose::Pose;
use rand_core::Rng;

/// Counts how often Table 4.4 picks each particle when drawing `draws` particles from
/// `weights` (which sum to 1), into `counts` (same length). The counts add up to `draws`.
///
/// One pass over the particles rather than over the draws: with `r ~ U[0, 1/M)` the textbook's
/// pointers are `uₘ = r + m/M`, `m = 0 … M−1`, and particle `i` is picked by those with
/// `cᵢ₋₁ < uₘ ≤ cᵢ` (`cᵢ` the cumulative weight), so its count is `K(cᵢ) − K(cᵢ₋₁)` with
/// `K(c) = min(M, ⌊(c − r)·M⌋ + 1)` for `c ≥ r` and 0 below: the number of pointers at or
/// below `c`.
///
/// # Random numbers
/// One `next_u32`: `r = u/draws` with `u` from [`uniform_f32`].
///
/// Rounding: when the f32 cumulative sum stops short of the last pointers (a few ulps below
/// 1), the last particle with non-zero weight takes the remaining picks.
pub fn low_variance_counts<R: Rng + ?Sized>(
    weights: &[f32],
    counts: &mut [u16],
    draws: u16,
    rng: &mut R,
) {
    low_variance_counts_of_total(weights, 1.0, counts, draws, rng);
}

/// [`low_variance_counts`] for weights that sum to `total` (positive and finite) rather than
/// 1: the pointers are `total·uₘ`, so particle `i`'s count is `K(cᵢ)` − `K(cᵢ₋₁)` with
/// `K(c) = min(M, ⌊(c − r·total)·(M/total)⌋ + 1)`. With `total = 1` this is
/// [`low_variance_counts`] exactly. Same random numbers.
pub fn low_variance_counts_of_total<R: Rng + ?Sized>(
    weights: &[f32],
    total: f32,
    counts: &mut [u16],
    draws: u16,
    rng: &mut R,
) {
    let n = weights.len().min(counts.len());
    if n == 0 || draws == 0 {
        counts.iter_mut().for_each(|c| *c = 0);
        return;
    }
    let m = f32::from(draws);
    let r = uniform_f32(rng) / m;
    let start = r * total;
    let scale = m / total;
    let draws = u32::from(draws);
    let mut cumulative = 0.0f32;
    let mut below = 0u32;
    for (&w, c) in weights.iter().zip(counts.iter_mut()) {
        cumulative += w;
        let reached = (cumulative - start) * scale;
        // ⌊(c − r)·M⌋ + 1 for c ≥ r, else 0 (pointers at or below c), at most M. A NaN
        // (a NaN weight) counts as nothing reached.
        let k = if reached >= 0.0 {
            ((reached as u32).saturating_add(1)).min(draws)
        } else {
            below
        };
        let k = k.max(below);
        *c = (k - below) as u16;
        below = k;
    }
    counts.iter_mut().skip(n).for_each(|c| *c = 0);
    if below < draws {
        // Rounding left the last pointers past the cumulative sum: they go to the last
        // particle with positive weight (or the last one, if none has).
        let last = weights
            .iter()
            .take(n)
            .rposition(|&w| w > 0.0)
            .unwrap_or(n - 1);
        if let Some(c) = counts.get_mut(last) {
            *c = c.saturating_add((draws - below) as u16);
        }
    }
}

/// Rewrites `poses` in place so that particle `i` appears `counts[i]` times: slots of particles
/// counted at least once keep them, extra copies go to the lowest slots with count 0. Returns
/// the number of slots left over (`len − Σ counts`, when `Σ counts ≤ len`); they are marked with
/// count 0 in `counts` and still hold unpicked particles, for the caller to replace.
///
/// After the call `counts[i]` is 1 for every filled slot and 0 for every left-over slot.
pub fn apply_counts(poses: &mut [Pose], counts: &mut [u16]) -> usize {
    let n = poses.len().min(counts.len());
    let mut dest = 0usize;
    let mut filled = 0usize;
    for src in 0..n {
        let count = counts.get(src).copied().unwrap_or(0);
        if count == 0 {
            continue;
        }
        filled += 1;
        if count == 1 {
            continue;
        }
        if let Some(c) = counts.get_mut(src) {
            *c = 1;
        }
        let pose = poses.get(src).copied().unwrap_or_default();
        for _ in 1..count {
            while dest < n && counts.get(dest).copied().unwrap_or(1) != 0 {
                dest += 1;
            }
            if dest >= n {
                break;
            }
            if let Some(p) = poses.get_mut(dest) {
                *p = pose;
            }
            if let Some(c) = counts.get_mut(dest) {
                *c = 1;
            }
            // A slot ahead of `src` is counted when `src` reaches it.
            if dest < src {
                filled += 1;
            }
        }
    }
    n.saturating_sub(filled)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mcl::SplitMix64;

    #[test]
    fn counts_are_floor_or_ceil_of_weight_times_m() {
        let w = [0.5, 0.25, 0.125, 0.0, 0.125];
        let mut c = [0u16; 5];
        let mut rng = SplitMix64::new(9);
        for draws in [1u16, 5, 8, 13, 100] {
            low_variance_counts(&w, &mut c, draws, &mut rng);
            assert_eq!(
                c.iter().map(|&k| u32::from(k)).sum::<u32>(),
                u32::from(draws)
            );
            for (wi, ci) in w.iter().zip(c) {
                let e = wi * f32::from(draws);
                assert!(f32::from(ci) >= e.floor() - 1e-4 && f32::from(ci) <= e.ceil() + 1e-4);
            }
        }
    }

    #[test]
    fn equal_weights_keep_the_set() {
        let w = [0.25f32; 4];
        let mut c = [0u16; 4];
        low_variance_counts(&w, &mut c, 4, &mut SplitMix64::new(1));
        assert_eq!(c, [1; 4]);
    }

    #[test]
    fn in_place_copies_match_the_counts() {
        let mut poses: Vec<Pose> = (0..6).map(|i| Pose::new(i as f32, 0.0, 0.0)).collect();
        let mut counts = [3u16, 0, 0, 2, 0, 0];
        let left = apply_counts(&mut poses, &mut counts);
        assert_eq!(left, 1);
        let xs: Vec<f32> = poses.iter().map(|p| p.x_m).collect();
        // Slot 0 keeps 0 and copies it into 1 and 2; slot 3 keeps 3 and copies it into 4;
        // slot 5 is left over (still particle 5).
        assert_eq!(xs, [0.0, 0.0, 0.0, 3.0, 3.0, 5.0]);
        assert_eq!(counts, [1, 1, 1, 1, 1, 0]);
    }

    #[test]
    fn late_sources_fill_early_holes() {
        let mut poses: Vec<Pose> = (0..4).map(|i| Pose::new(i as f32, 0.0, 0.0)).collect();
        let mut counts = [0u16, 0, 0, 4];
        assert_eq!(apply_counts(&mut poses, &mut counts), 0);
        assert!(poses.iter().all(|p| p.x_m == 3.0));
    }

    #[test]
    fn counts_match_the_textbook_pointers_in_f64() {
        // Table 4.4 as written, one pointer at a time, in f64, with the same r.
        let mut rng = SplitMix64::new(21);
        let mut weight_rng = SplitMix64::new(22);
        for trial in 0..200u16 {
            let n = 1 + usize::from(trial % 61);
            let mut w: Vec<f32> = (0..n)
                .map(|_| {
                    let u = uniform_f32(&mut weight_rng);
                    if u < 0.2 {
                        0.0
                    } else {
                        u * u * u
                    }
                })
                .collect();
            w[n / 2] += 0.01;
            let total: f32 = w.iter().sum();
            w.iter_mut().for_each(|x| *x /= total);
            let draws = 1 + trial % 97;
            let mut probe = rng;
            let r = f64::from(uniform_f32(&mut probe) / f32::from(draws));
            let mut want = vec![0u16; n];
            let (mut i, mut c) = (0usize, f64::from(w[0]));
            for m in 0..draws {
                let u = r + f64::from(m) / f64::from(draws);
                while u > c && i + 1 < n {
                    i += 1;
                    c += f64::from(w[i]);
                }
                want[i] += 1;
            }
            let mut got = vec![0u16; n];
            low_variance_counts(&w, &mut got, draws, &mut rng);
            assert_eq!(rng, probe);
            assert_eq!(got, want, "trial {trial}");
        }
    }
}
