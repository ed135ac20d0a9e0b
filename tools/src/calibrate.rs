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

/// The κ values of the coverage curve (for the plot): 1 to 1000, twelve per decade, log-spaced.
pub fn kappa_grid() -> Vec<f64> {
    (0..=36).map(|i| 10f64.powf(i as f64 / 12.0)).collect()
}

/// Relative precision of the calibrated κ: the smallest κ reaching the coverage lies in
/// `(kappa_below, kappa]` and `kappa / kappa_below ≤ 1 + KAPPA_REL_PRECISION`.
pub const KAPPA_REL_PRECISION: f64 = 1e-3;

/// The largest κ searched.
pub const KAPPA_MAX: f64 = 1e6;

/// The result of a calibration.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Calibration {
    /// The calibrated κ: coverage reaches `level` at this κ, and the smallest κ that does lies
    /// within [`KAPPA_REL_PRECISION`] below it. `None` if no κ ≤ [`KAPPA_MAX`] does.
    pub kappa: Option<f64>,
    /// The largest κ known to miss the requested coverage (the bracket's lower end); `None` when
    /// κ = 1 already reaches it.
    pub kappa_below: Option<f64>,
    /// The relative precision the search was run to ([`KAPPA_REL_PRECISION`]).
    pub relative_precision: f64,
    /// Coverage achieved at κ = 1 (the raw product of beams).
    pub coverage_at_1: f64,
    /// Coverage achieved at the chosen κ.
    pub coverage_at_kappa: Option<f64>,
    /// The coverage curve `(κ, coverage)` over [`kappa_grid`], for plotting.
    pub curve: Vec<(f64, f64)>,
    /// Requested coverage.
    pub level: f64,
    /// Scans used.
    pub scans: usize,
}

/// Finds the smallest κ ≥ 1 whose coverage reaches `level`, to [`KAPPA_REL_PRECISION`].
///
/// Tempering flattens the posterior, so the mass of the cells more probable than the truth
/// never grows with κ and coverage is a non-decreasing step function of κ. The search doubles
/// κ from 1 until the coverage is reached (at most [`KAPPA_MAX`]), then bisects the bracket in
/// log κ until its ends are within the stated relative precision.
pub fn calibrate(scans: &[GridScores], level: f64) -> Calibration {
    let curve: Vec<(f64, f64)> = kappa_grid()
        .into_iter()
        .map(|k| (k, coverage(scans, k, level)))
        .collect();
    let coverage_at_1 = coverage(scans, 1.0, level);
    let reaches = |k: f64| coverage(scans, k, level) >= level;
    let (kappa, kappa_below) = if scans.is_empty() {
        (None, None)
    } else if coverage_at_1 >= level {
        (Some(1.0), None)
    } else {
        let mut lo = 1.0;
        let mut hi = 2.0;
        while hi <= KAPPA_MAX && !reaches(hi) {
            lo = hi;
            hi *= 2.0;
        }
        if hi > KAPPA_MAX {
            if reaches(KAPPA_MAX) {
                hi = KAPPA_MAX;
            } else {
                return Calibration {
                    kappa: None,
                    kappa_below: Some(KAPPA_MAX),
                    relative_precision: KAPPA_REL_PRECISION,
                    coverage_at_1,
                    coverage_at_kappa: None,
                    curve,
                    level,
                    scans: scans.len(),
                };
            }
        }
        while hi / lo > 1.0 + KAPPA_REL_PRECISION {
            let mid = (lo * hi).sqrt();
            if reaches(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        (Some(hi), Some(lo))
    };
    Calibration {
        kappa,
        kappa_below,
        relative_precision: KAPPA_REL_PRECISION,
        coverage_at_1,
        coverage_at_kappa: kappa.map(|k| coverage(scans, k, level)),
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
        // of (−3.5, 3.5): below 0.95 once 3.5 < 1.96·σ, i.e. κ > 2c·(3.5/1.96)² = 6.38 for c = 1
        // (the midpoint rule makes this approximate, to a few percent).
        let g = parabola(4.0, 1.0);
        assert!(mass_above_truth(&g, 1.0) > 0.99);
        let cal = calibrate(&[g], 0.95);
        let k = cal.kappa.unwrap();
        assert!(k > 6.38 * 0.97 && k < 6.38 * 1.03, "κ = {k}");
        assert_eq!(cal.coverage_at_1, 0.0);
    }

    /// Two cells: one `a` nats above the truth. The mass above the truth is
    /// `e^{a/κ} / (e^{a/κ} + 1)`, below the level α exactly when `κ > a / ln(α / (1 − α))`.
    #[test]
    fn kappa_is_found_to_the_stated_precision() {
        let a = 20.0;
        let g = GridScores {
            log_likelihood: vec![a, 0.0],
            truth: 1,
        };
        for level in [0.6f64, 0.9, 0.95, 0.99] {
            let exact: f64 = a / (level / (1.0 - level)).ln();
            let cal = calibrate(std::slice::from_ref(&g), level);
            let k = cal.kappa.unwrap();
            let below = cal.kappa_below.unwrap();
            assert!(
                below <= exact && exact <= k,
                "{level}: {below} .. {k} misses {exact}"
            );
            assert!(
                k / below <= 1.0 + KAPPA_REL_PRECISION,
                "{level}: {below} .. {k}"
            );
            assert_eq!(cal.coverage_at_kappa, Some(1.0));
        }
    }

    #[test]
    fn coverage_at_kappa_1_needs_no_search_and_unreachable_coverage_is_none() {
        let peak = GridScores {
            log_likelihood: vec![0.0, -1.0],
            truth: 0,
        };
        let cal = calibrate(std::slice::from_ref(&peak), 0.95);
        assert_eq!((cal.kappa, cal.kappa_below), (Some(1.0), None));
        // Ten cells tied above the truth: their mass is at least 10/11 at every κ.
        let mut ll = vec![1.0; 10];
        ll.push(0.0);
        let tied = GridScores {
            log_likelihood: ll,
            truth: 10,
        };
        let cal = calibrate(std::slice::from_ref(&tied), 0.5);
        assert_eq!(cal.kappa, None);
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
