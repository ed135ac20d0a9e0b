//! κ calibration (docs/models.md#tempering): smallest tempering exponent whose credible sets contain
//! the true pose at the requested rate.
//!
//! For each scan with a known pose, the caller scores a local grid of poses around it (the true
//! pose is one grid cell) with the *untempered* model. Tempering by κ divides every
//! log-likelihood by κ, which keeps the order of the cells and only flattens the posterior, so
//! one grid of scores serves every κ. The truth lies inside the highest-posterior-density set of
//! level α exactly when the posterior mass of the cells strictly more probable than the truth is
//! below α ([`mass_above_truth`]). Coverage at κ is the fraction of scans for which it does.

/// The untempered log-likelihoods of one scan over a pose grid, and which cell is the truth.
#[derive(Clone, Debug)]
pub struct GridScores {
    /// `ln p(z | x_j, m)` for each grid pose `x_j`, nats.
    pub log_likelihood: Vec<f64>,
    /// Index of the true (logged) pose in `log_likelihood`.
    pub truth: usize,
}

/// Posterior mass, at tempering κ and a flat prior over the grid, of the cells strictly more
/// probable than the truth. 0 when the truth is the peak.
pub fn mass_above_truth(g: &GridScores, kappa: f64) -> f64 {
    let Some(&lt) = g.log_likelihood.get(g.truth) else {
        return 1.0;
    };
    let max = g
        .log_likelihood
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let (mut total, mut above) = (0.0, 0.0);
    for &l in &g.log_likelihood {
        let w = ((l - max) / kappa).exp();
        total += w;
        if l > lt {
            above += w;
        }
    }
    if total > 0.0 {
        above / total
    } else {
        1.0
    }
}

/// Fraction of scans whose truth lies inside the credible set of level `level` at κ.
pub fn coverage(scans: &[GridScores], kappa: f64, level: f64) -> f64 {
    if scans.is_empty() {
        return 0.0;
    }
    let inside = scans
        .iter()
        .filter(|g| mass_above_truth(g, kappa) < level)
        .count();
    inside as f64 / scans.len() as f64
}

/// The κ values searched: 1 to 1000, twelve per decade (log-spaced), so the answer is within
/// 21 % of the true smallest κ.
pub fn kappa_grid() -> Vec<f64> {
    (0..=36).map(|i| 10f64.powf(i as f64 / 12.0)).collect()
}

/// The result of a calibration.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Calibration {
    /// The smallest κ of the grid reaching the requested coverage; `None` if none does.
    pub kappa: Option<f64>,
    /// Coverage achieved at κ = 1 (the raw product of beams).
    pub coverage_at_1: f64,
    /// Coverage achieved at the chosen κ.
    pub coverage_at_kappa: Option<f64>,
    /// The whole curve `(κ, coverage)`.
    pub curve: Vec<(f64, f64)>,
    /// Requested coverage.
    pub level: f64,
    /// Scans used.
    pub scans: usize,
}

/// Finds the smallest κ of [`kappa_grid`] whose coverage reaches `level`.
pub fn calibrate(scans: &[GridScores], level: f64) -> Calibration {
    let curve: Vec<(f64, f64)> = kappa_grid()
        .into_iter()
        .map(|k| (k, coverage(scans, k, level)))
        .collect();
    let chosen = curve.iter().find(|(_, c)| *c >= level).copied();
    Calibration {
        kappa: chosen.map(|c| c.0),
        coverage_at_1: coverage(scans, 1.0, level),
        coverage_at_kappa: chosen.map(|c| c.1),
        curve,
        level,
        scans: scans.len(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1-D grid whose log-likelihood is a parabola peaked `offset` cells from the truth
    /// (cell 50), with curvature `c` nats per cell².
    fn parabola(offset: f64, c: f64) -> GridScores {
        let ll = (0..101)
            .map(|i| -c * (i as f64 - 50.0 - offset).powi(2))
            .collect();
        GridScores {
            log_likelihood: ll,
            truth: 50,
        }
    }

    #[test]
    fn truth_at_peak_is_always_inside() {
        let g = parabola(0.0, 10.0);
        assert_eq!(mass_above_truth(&g, 1.0), 0.0);
        assert_eq!(coverage(&[g], 1.0, 0.95), 1.0);
    }

    #[test]
    fn biased_sharp_posterior_needs_tempering() {
        // Peak 4 cells away, sharp: the truth is outside at κ = 1. The posterior is a sampled
        // Gaussian with σ² = κ/(2c) cells². The cells strictly more probable than the truth are
        // the 7 with |i − peak| ≤ 3, whose mass is (midpoint rule, σ ≳ 1.5 cells) the normal mass
        // of (−3.5, 3.5): below 0.95 once 3.5 < 1.96·σ, i.e. κ > 2c·(3.5/1.96)² = 6.38 for c = 1.
        // The grid has 12 points per decade, so the answer is the first one above 6.38 (≤ ×1.21).
        let g = parabola(4.0, 1.0);
        assert!(mass_above_truth(&g, 1.0) > 0.99);
        let cal = calibrate(&[g], 0.95);
        let k = cal.kappa.unwrap();
        assert!(k > 6.38 * 0.99 && k < 6.38 * 1.22, "κ = {k}");
        assert_eq!(cal.coverage_at_1, 0.0);
    }

    #[test]
    fn coverage_counts_scans() {
        let scans = [
            parabola(0.0, 1.0),
            parabola(6.0, 1.0),
            parabola(-6.0, 1.0),
            parabola(0.0, 3.0),
        ];
        assert!((coverage(&scans, 1.0, 0.95) - 0.5).abs() < 1e-12);
        assert!((coverage(&scans, 1000.0, 0.95) - 1.0).abs() < 1e-12);
    }
}
