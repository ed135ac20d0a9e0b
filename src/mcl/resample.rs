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
/// # Random numbers
/// One `next_u32`: `r = u/draws` with `u` from [`uniform_f32`].
///
/// Rounding: when the f32 cumulative sum stops short of a pointer `r + m/M` (a few ulps below
/// 1), the last particle with non-zero weight takes the remaining picks.
pub fn low_variance_counts<R: Rng + ?Sized>(
    weights: &[f32],
    counts: &mut [u16],
    draws: u16,
    rng: &mut R,
) {
    counts.iter_mut().for_each(|c| *c = 0);
    let n = weights.len().min(counts.len());
    if n == 0 || draws == 0 {
        return;
    }
    let step = 1.0 / f32::from(draws);
    let r = uniform_f32(rng) * step;
    let mut i = 0usize;
    let mut c = weights.first().copied().unwrap_or(0.0);
    let mut last_positive = 0usize;
    for m in 0..draws {
        let u = r + f32::from(m) * step;
        while u > c && i + 1 < n {
            i += 1;
            let w = weights.get(i).copied().unwrap_or(0.0);
            if w > 0.0 {
                last_positive = i;
            }
            c += w;
        }
        // Past the end by rounding: give the pick to the last particle that had weight.
        let pick = if u > c { last_positive } else { i };
        if let Some(k) = counts.get_mut(pick) {
            *k = k.saturating_add(1);
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
    for src in 0..n {
        let extra = counts.get(src).copied().unwrap_or(0).saturating_sub(1);
        if let Some(c) = counts.get_mut(src) {
            *c = (*c).min(1);
        }
        let pose = poses.get(src).copied().unwrap_or_default();
        for _ in 0..extra {
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
        }
    }
    counts.iter().take(n).filter(|&&c| c == 0).count()
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
}
