//! Learning the crosstalk model from logs (docs/models.md#sonar, "Learning").
//!
//! 1. [`GroupedWeightEm`]: EM for the four mixture weights of Thrun Table 6.1, run separately for
//!    each co-fired count `k` (0 = fired alone), **with σ_hit and λ_short held fixed**: the
//!    E-step uses the crate's [`BeamModel::components`](crate::BeamModel::components) of each
//!    reading, the M-step sets each group's weights to its mean responsibilities. Only sufficient
//!    statistics are kept (four sums and a count per group); the caller streams its readings
//!    once per pass. This is a small internal EM written for the weights only; the full
//!    six-parameter EM of Table 6.2 (docs/models.md#em) can replace it later — it must then be run
//!    with σ and λ shared across the groups, or the groups' `z_rand` stop being comparable.
//! 2. [`fit_constant_q`]: `z_rand(k) = z_rand,0 + (1 − z_rand,0)·(1 − (1 − q)^k)` is
//!    `ln(1 − z_rand(k)) = ln(1 − z_rand,0) + k·ln(1 − q)`, a straight line in `k`. It is fitted
//!    by **weighted least squares in that log space**, the weight of group `k` being its number
//!    of readings. Closed form, no iteration.
//! 3. [`fit_gaussian_q`]: the separation-dependent form `q(Δβ) = q0·exp(−Δβ²/(2w²))`, fitted by
//!    weighted least squares in the same log space over per-observation neighbour sets
//!    (`ln(1 − z_rand,o) = ln(1 − z_rand,0) + Σ_j ln(1 − w_oj·q(Δβ_oj))`): `ln(1 − z_rand,0)` in
//!    closed form for each `(q0, w)`, and `(q0, w)` by a coarse-to-fine grid search.

use crate::beam::Components;
use crate::math;

/// What one EM pass did.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PassReport {
    /// Largest absolute change of any weight of any group in this M-step.
    pub max_change: f32,
    /// Sum of `ln p(z)` of the readings under the weights *before* the M-step, nats.
    pub log_likelihood: f64,
    /// Readings used.
    pub used: u64,
    /// Readings skipped: co-fired count `≥ K`, or a mixture of 0 under the current weights.
    pub skipped: u64,
}

/// EM of the mixture weights per co-fired count `k < K`, σ and λ fixed. See the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupedWeightEm<const K: usize> {
    weights: [[f32; 4]; K],
    counts: [u64; K],
    acc: [[f64; 4]; K],
    n: [u64; K],
    ll: f64,
    skipped: u64,
}

impl<const K: usize> GroupedWeightEm<K> {
    /// Starts every group from the same weights `[z_hit, z_short, z_max, z_rand]` (take them
    /// from valid intrinsics; every weight should be > 0, or EM can never move it off 0).
    pub fn new(initial: [f32; 4]) -> Self {
        Self {
            weights: [initial; K],
            counts: [0; K],
            acc: [[0.0; 4]; K],
            n: [0; K],
            ll: 0.0,
            skipped: 0,
        }
    }

    /// E-step for one reading of co-fired count `k`, given its four component densities. Returns
    /// false (and counts the reading as skipped) when `k ≥ K` or its mixture is 0 or not finite.
    pub fn add(&mut self, k: usize, c: &Components) -> bool {
        let (Some(w), Some(acc), Some(n)) =
            (self.weights.get(k), self.acc.get_mut(k), self.n.get_mut(k))
        else {
            self.skipped += 1;
            return false;
        };
        let parts = [w[0] * c.hit, w[1] * c.short, w[2] * c.max, w[3] * c.rand];
        let p: f32 = parts.iter().sum();
        if !(p.is_finite() && p > 0.0) {
            self.skipped += 1;
            return false;
        }
        let inv = 1.0 / f64::from(p);
        for (a, &x) in acc.iter_mut().zip(&parts) {
            *a += f64::from(x) * inv;
        }
        *n += 1;
        self.ll += math::ln_f64(f64::from(p));
        true
    }

    /// M-step: every group with at least one reading takes its mean responsibilities as its new
    /// weights; the others keep theirs. Resets the statistics for the next pass.
    pub fn finish_pass(&mut self) -> PassReport {
        let mut max_change = 0.0f32;
        let mut used = 0u64;
        for ((w, acc), (n, count)) in self
            .weights
            .iter_mut()
            .zip(self.acc.iter_mut())
            .zip(self.n.iter_mut().zip(self.counts.iter_mut()))
        {
            if *n > 0 {
                let total: f64 = acc.iter().sum();
                for (wc, a) in w.iter_mut().zip(acc.iter()) {
                    let new = (*a / total) as f32;
                    max_change = max_change.max((new - *wc).abs());
                    *wc = new;
                }
            }
            used += *n;
            *count = *n;
            *acc = [0.0; 4];
            *n = 0;
        }
        let r = PassReport {
            max_change,
            log_likelihood: self.ll,
            used,
            skipped: self.skipped,
        };
        self.ll = 0.0;
        self.skipped = 0;
        r
    }

    /// The weights `[z_hit, z_short, z_max, z_rand]` of group `k`.
    pub fn weights(&self, k: usize) -> Option<[f32; 4]> {
        self.weights.get(k).copied()
    }

    /// `z_rand(k)`.
    pub fn z_rand(&self, k: usize) -> Option<f32> {
        self.weights.get(k).and_then(|w| w.get(3)).copied()
    }

    /// Readings of group `k` in the last finished pass.
    pub fn count(&self, k: usize) -> u64 {
        self.counts.get(k).copied().unwrap_or(0)
    }
}

/// Why a fit of `q` failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FitError {
    /// Fewer than two usable groups (distinct `k`, positive weight, `z_rand < 1`).
    TooFewGroups,
    /// All usable groups have the same co-fired count: the slope is undetermined.
    Degenerate,
}

impl core::fmt::Display for FitError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::TooFewGroups => f.write_str("need at least two usable groups"),
            Self::Degenerate => f.write_str("all groups have the same co-fired count"),
        }
    }
}

impl core::error::Error for FitError {}

/// A fitted crosstalk model.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct QFit {
    /// Base `z_rand,0` (a transducer fired alone), in `[0, 1]`.
    pub z_rand0: f32,
    /// `q` (constant form) or `q0` (Gaussian form), in `[0, 1]`.
    pub q: f32,
    /// Lobe width `w`, radians (Gaussian form); `+∞` for the constant form.
    pub width_rad: f32,
    /// Weighted sum of squared residuals in `ln(1 − z_rand)` space, divided by the total weight.
    pub mean_sq_residual: f32,
}

/// One group for [`fit_constant_q`]: co-fired count (may be fractional: the effective count),
/// the learnt `z_rand`, and a weight (its number of readings).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroupRate {
    /// Co-fired count `k` (or effective count `Σ w_ij`).
    pub k: f32,
    /// Learnt `z_rand(k)`.
    pub z_rand: f32,
    /// Weight, e.g. the group's number of readings; ≤ 0 ignores the group.
    pub weight: f32,
}

fn usable(z: f32, w: f32) -> bool {
    z.is_finite() && (0.0..1.0).contains(&z) && w.is_finite() && w > 0.0
}

/// Fits `z_rand,0` and a constant `q` to per-group rates by weighted least squares of
/// `ln(1 − z_rand)` on `k`. See the module docs.
///
/// # Errors
/// [`FitError::TooFewGroups`], [`FitError::Degenerate`].
pub fn fit_constant_q(groups: &[GroupRate]) -> Result<QFit, FitError> {
    let (mut sw, mut sx, mut sy, mut sxx, mut sxy) = (0.0f64, 0.0, 0.0, 0.0, 0.0);
    let mut n = 0usize;
    for g in groups
        .iter()
        .filter(|g| usable(g.z_rand, g.weight) && g.k.is_finite())
    {
        let w = f64::from(g.weight);
        let x = f64::from(g.k);
        let y = math::ln_f64(1.0 - f64::from(g.z_rand));
        sw += w;
        sx += w * x;
        sy += w * y;
        sxx += w * x * x;
        sxy += w * x * y;
        n += 1;
    }
    if n < 2 {
        return Err(FitError::TooFewGroups);
    }
    let den = sw * sxx - sx * sx;
    if den <= 1e-12 * sw * sw {
        return Err(FitError::Degenerate);
    }
    let b = (sw * sxy - sx * sy) / den;
    let a = (sy - b * sx) / sw;
    let mut ss = 0.0f64;
    for g in groups
        .iter()
        .filter(|g| usable(g.z_rand, g.weight) && g.k.is_finite())
    {
        let r = math::ln_f64(1.0 - f64::from(g.z_rand)) - a - b * f64::from(g.k);
        ss += f64::from(g.weight) * r * r;
    }
    Ok(QFit {
        z_rand0: (1.0 - math::exp_f64(a)).clamp(0.0, 1.0) as f32,
        q: (1.0 - math::exp_f64(b)).clamp(0.0, 1.0) as f32,
        width_rad: f32::INFINITY,
        mean_sq_residual: (ss / sw) as f32,
    })
}

/// One observation for [`fit_gaussian_q`]: a transducer's learnt `z_rand`, its weight, and its
/// co-fired neighbours as `(separation_rad, overlap_weight)` pairs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NeighbourRate<'a> {
    /// Learnt `z_rand` of this transducer (or group of like transducers).
    pub z_rand: f32,
    /// Weight, e.g. its number of readings; ≤ 0 ignores it.
    pub weight: f32,
    /// Co-fired neighbours: `(|Δβ| in radians, w_ij)`.
    pub neighbours: &'a [(f32, f32)],
}

/// `Σ_j ln(1 − w_j·q0·exp(−Δβ_j²/(2w²)))` for one observation.
fn log_clean(q0: f64, width: f64, neighbours: &[(f32, f32)]) -> f64 {
    neighbours
        .iter()
        .map(|&(d, ov)| {
            let u = f64::from(d) / width;
            let q = q0 * math::exp_f64(-0.5 * u * u) * f64::from(ov);
            math::ln_f64((1.0 - q).max(1e-12))
        })
        .sum()
}

/// (mean squared residual, intercept) for one `(q0, w)`.
fn gaussian_cost(q0: f64, width: f64, obs: &[NeighbourRate<'_>]) -> (f64, f64) {
    let (mut sw, mut s) = (0.0f64, 0.0f64);
    for o in obs.iter().filter(|o| usable(o.z_rand, o.weight)) {
        let w = f64::from(o.weight);
        let y = math::ln_f64(1.0 - f64::from(o.z_rand));
        sw += w;
        s += w * (y - log_clean(q0, width, o.neighbours));
    }
    if sw <= 0.0 {
        return (f64::INFINITY, 0.0);
    }
    let a = s / sw;
    let mut ss = 0.0f64;
    for o in obs.iter().filter(|o| usable(o.z_rand, o.weight)) {
        let y = math::ln_f64(1.0 - f64::from(o.z_rand));
        let r = y - a - log_clean(q0, width, o.neighbours);
        ss += f64::from(o.weight) * r * r;
    }
    (ss / sw, a)
}

/// Fits `z_rand,0` and `q(Δβ) = q0·exp(−Δβ²/(2w²))` by weighted least squares in
/// `ln(1 − z_rand)` space (module docs). `q0 ∈ [0, 1]`, `w ∈ [1°, 180°]`, searched on a
/// 41 × 36 grid refined three times around the best point (each time 4× finer).
///
/// # Errors
/// [`FitError::TooFewGroups`] with fewer than two usable observations; [`FitError::Degenerate`]
/// when no observation has a neighbour.
pub fn fit_gaussian_q(obs: &[NeighbourRate<'_>]) -> Result<QFit, FitError> {
    let n = obs.iter().filter(|o| usable(o.z_rand, o.weight)).count();
    if n < 2 {
        return Err(FitError::TooFewGroups);
    }
    if obs.iter().all(|o| o.neighbours.is_empty()) {
        return Err(FitError::Degenerate);
    }
    let deg = core::f64::consts::PI / 180.0;
    let (mut q_lo, mut q_hi) = (0.0f64, 1.0f64);
    let (mut w_lo, mut w_hi) = (1.0 * deg, 180.0 * deg);
    let mut best = (f64::INFINITY, 0.0f64, 0.0f64, w_hi);
    for _ in 0..4 {
        let (nq, nw) = (41usize, 36usize);
        for a in 0..nq {
            let q0 = q_lo + (q_hi - q_lo) * a as f64 / (nq - 1) as f64;
            for b in 0..nw {
                let w = w_lo + (w_hi - w_lo) * b as f64 / (nw - 1) as f64;
                let (cost, icpt) = gaussian_cost(q0, w, obs);
                if cost < best.0 {
                    best = (cost, icpt, q0, w);
                }
            }
        }
        let dq = (q_hi - q_lo) / 8.0;
        let dw = (w_hi - w_lo) / 8.0;
        q_lo = (best.2 - dq).max(0.0);
        q_hi = (best.2 + dq).min(1.0);
        w_lo = (best.3 - dw).max(0.5 * deg);
        w_hi = (best.3 + dw).min(180.0 * deg);
    }
    Ok(QFit {
        z_rand0: (1.0 - math::exp_f64(best.1)).clamp(0.0, 1.0) as f32,
        q: best.2 as f32,
        width_rad: best.3 as f32,
        mean_sq_residual: best.0 as f32,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_fit_recovers_exact_rates() {
        let (z0, q) = (0.05f32, 0.12f32);
        let groups: [GroupRate; 4] = core::array::from_fn(|i| {
            let k = [0.0, 1.0, 3.0, 7.0][i];
            GroupRate {
                k,
                z_rand: 1.0 - (1.0 - z0) * (1.0 - q).powf(k),
                weight: 100.0,
            }
        });
        let f = fit_constant_q(&groups).unwrap();
        assert!(
            (f.z_rand0 - z0).abs() < 1e-5 && (f.q - q).abs() < 1e-5,
            "{f:?}"
        );
        assert!(f.mean_sq_residual < 1e-10);
        assert_eq!(fit_constant_q(&groups[..1]), Err(FitError::TooFewGroups));
        let same = [groups[1], groups[1]];
        assert_eq!(fit_constant_q(&same), Err(FitError::Degenerate));
    }

    #[test]
    fn gaussian_fit_recovers_exact_rates() {
        let (z0, q0, w) = (0.05f64, 0.4f64, 0.6f64);
        let deg = core::f32::consts::PI / 180.0;
        let sets: [&[(f32, f32)]; 4] = [
            &[(15.0 * deg, 1.0), (15.0 * deg, 1.0)],
            &[(180.0 * deg, 1.0)],
            &[(90.0 * deg, 1.0), (90.0 * deg, 1.0), (180.0 * deg, 1.0)],
            &[(45.0 * deg, 1.0), (45.0 * deg, 0.5)],
        ];
        let obs: [NeighbourRate<'_>; 4] = core::array::from_fn(|i| {
            let lc = log_clean(q0, w, sets[i]);
            NeighbourRate {
                z_rand: (1.0 - (1.0 - z0) * lc.exp()) as f32,
                weight: 1.0,
                neighbours: sets[i],
            }
        });
        let f = fit_gaussian_q(&obs).unwrap();
        assert!((f.q as f64 - q0).abs() < 0.01, "{f:?}");
        assert!((f.width_rad as f64 - w).abs() < 0.02, "{f:?}");
        assert!((f.z_rand0 as f64 - z0).abs() < 0.002, "{f:?}");
    }

    #[test]
    fn em_moves_weight_to_the_explaining_component() {
        let mut em = GroupedWeightEm::<2>::new([0.25; 4]);
        let hit = Components {
            hit: 1.0,
            short: 0.0,
            max: 0.0,
            rand: 0.1,
        };
        let rnd = Components {
            hit: 0.0,
            short: 0.0,
            max: 0.0,
            rand: 0.1,
        };
        for _ in 0..50 {
            for _ in 0..9 {
                em.add(0, &hit);
                em.add(1, &hit);
            }
            em.add(0, &rnd);
            for _ in 0..3 {
                em.add(1, &rnd);
            }
            assert!(!em.add(2, &rnd));
            em.finish_pass();
        }
        // Closed form: readings only rand can explain are the floor of z_rand.
        assert!(em.z_rand(0).unwrap() >= 0.1 - 1e-4);
        assert!(em.z_rand(1).unwrap() > em.z_rand(0).unwrap());
        assert_eq!(em.count(1), 12);
    }
}
