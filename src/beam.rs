//! The beam model: Thrun's `beam_range_finder_model`, Table 6.1, in log space.
//!
//! Per beam, with `z` the reading and `z*` the ray-cast range (both metres):
//!
//! ```text
//! p(z | z*) = z_hit·p_hit + z_short·p_short + z_max·p_max + z_rand·p_rand
//! p_hit   = η_hit·N(z; z*, σ²)            on 0 ≤ z ≤ z_max,  η_hit = 1/(Φ((z_max−z*)/σ) − Φ(−z*/σ))
//! p_short = η_short·λ·e^(−λz)             on 0 ≤ z ≤ z*,     η_short = 1/(1 − e^(−λz*))
//! p_max   = 1 (a point mass, not a density) for a max-range reading
//! p_rand  = 1/z_max                       on 0 ≤ z < z_max
//! ```
//!
//! A max-range reading (`z ≥ z_max` or `+∞`, see [`crate::scan`]) is evaluated at `z = z_max`:
//! it takes the point mass and, like the chapter's worked example, the hit (and short) density
//! at `z_max`. NaN and negative readings are skipped and counted. `z*` is clamped into
//! `[0, z_max]`; a NaN `z*` is read as `z_max` (the ray met nothing).
//!
//! # Numerics
//! The per-beam log-likelihood is computed from the mixture in linear space when that sum is
//! above 1e-30, and otherwise from the component logarithms with a max-shifted log-sum-exp, so
//! no intermediate ever underflows to a spurious `−∞`. The result is clamped below at
//! [`BEAM_LOG_FLOOR`]; it is reached only by a reading that no component with non-zero weight
//! can explain (for example `z > z*` with `z_hit = z_rand = 0`). A scan log-likelihood is
//! therefore finite for every input and valid intrinsics, never NaN.

use crate::intrinsics::BeamIntrinsics;
use crate::math;
use crate::scan::{BeamLayout, Reading, Scan, ScanScore};

/// Lower clamp of one beam's log-likelihood, nats. See the module docs.
pub const BEAM_LOG_FLOOR: f32 = -1.0e4;

/// Below this mixture value the log is recomputed from component logarithms.
const LINEAR_SPACE_MIN: f32 = 1.0e-30;

/// The four unweighted component densities of one reading (per metre, except `max`, which is a
/// probability). Used by the E-step of EM.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Components {
    /// `p_hit(z)`, truncated-normal density with its normalizer η_hit, 1/m.
    pub hit: f32,
    /// `p_short(z)`, truncated-exponential density with η_short, 1/m.
    pub short: f32,
    /// `p_max(z)`: 1 for a max-range reading, else 0.
    pub max: f32,
    /// `p_rand(z)`: `1/z_max` below the range limit, else 0, 1/m.
    pub rand: f32,
}

impl Components {
    /// The mixture `Σ w_c·p_c` with the given weights `[z_hit, z_short, z_max, z_rand]`.
    pub fn mix(&self, w: [f32; 4]) -> f32 {
        w[0] * self.hit + w[1] * self.short + w[2] * self.max + w[3] * self.rand
    }
}

/// A beam model ready to score: intrinsics plus the constants derived from them once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BeamModel {
    intr: BeamIntrinsics,
    inv_sigma: f32,
    /// `1/(σ√(2π))`.
    hit_peak: f32,
    /// `ln(1/(σ√(2π)))`.
    ln_hit_peak: f32,
    inv_max_range: f32,
    ln_weights: [f32; 4],
    ln_lambda: f32,
    ln_inv_max_range: f32,
}

/// The per-reading quantities shared by the linear and the log path.
struct Prepared {
    z: f32,
    z_star: f32,
    is_max: bool,
}

impl BeamModel {
    /// Derives the per-parameter-set constants (a handful of logarithms), once.
    pub fn new(intr: BeamIntrinsics) -> Self {
        let sigma = intr.sigma_hit_m();
        let inv_sigma = 1.0 / sigma;
        let hit_peak = inv_sigma * math::INV_SQRT_2PI;
        let w = intr.weights();
        Self {
            intr,
            inv_sigma,
            hit_peak,
            ln_hit_peak: -math::ln(sigma) - math::LN_SQRT_2PI,
            inv_max_range: 1.0 / intr.max_range_m(),
            ln_weights: [
                math::ln(w[0]),
                math::ln(w[1]),
                math::ln(w[2]),
                math::ln(w[3]),
            ],
            ln_lambda: math::ln(intr.lambda_short_per_m()),
            ln_inv_max_range: -math::ln(intr.max_range_m()),
        }
    }

    /// The intrinsics this model was built from.
    pub fn intrinsics(&self) -> &BeamIntrinsics {
        &self.intr
    }

    fn prepare(&self, range_m: f32, z_star_m: f32) -> Option<Prepared> {
        let max = self.intr.max_range_m();
        // `clamp` written out: `f32::clamp` asserts `min <= max`, a panic path the compiler
        // cannot remove (it does not know that validated intrinsics have `max > 0`);
        // `cargo xtask nopanic` rejects it. Same result for every input.
        let z_star = if z_star_m.is_nan() || z_star_m > max {
            max
        } else if z_star_m < 0.0 {
            0.0
        } else {
            z_star_m
        };
        match Reading::classify(range_m, max) {
            Reading::Invalid => None,
            Reading::MaxRange => Some(Prepared {
                z: max,
                z_star,
                is_max: true,
            }),
            Reading::Range(z) => Some(Prepared {
                z,
                z_star,
                is_max: false,
            }),
        }
    }

    /// `1/η_hit`: the mass of N(z*, σ²) inside `[0, z_max]`.
    fn hit_mass(&self, z_star: f32) -> f32 {
        let max = self.intr.max_range_m();
        math::normal_mass_straddling_zero(-z_star * self.inv_sigma, (max - z_star) * self.inv_sigma)
    }

    /// `1 − e^(−λz*)`, the mass of the exponential before the wall (0 when z* = 0).
    fn short_mass(&self, z_star: f32) -> f32 {
        -math::expm1(-self.intr.lambda_short_per_m() * z_star)
    }

    fn components_prepared(&self, p: &Prepared) -> Components {
        let d = (p.z - p.z_star) * self.inv_sigma;
        let mass = self.hit_mass(p.z_star);
        let hit = if mass > 0.0 {
            self.hit_peak * math::exp(-0.5 * d * d) / mass
        } else {
            0.0
        };
        let short = if p.z_star > 0.0 && p.z <= p.z_star {
            let lambda = self.intr.lambda_short_per_m();
            let m = self.short_mass(p.z_star);
            if m > 0.0 {
                lambda * math::exp(-lambda * p.z) / m
            } else {
                0.0
            }
        } else {
            0.0
        };
        Components {
            hit,
            short,
            max: if p.is_max { 1.0 } else { 0.0 },
            rand: if p.is_max { 0.0 } else { self.inv_max_range },
        }
    }

    /// The four unweighted component densities for reading `range_m` against ray-cast `z_star_m`
    /// (metres). `None` for an invalid (NaN or negative) reading.
    pub fn components(&self, range_m: f32, z_star_m: f32) -> Option<Components> {
        self.prepare(range_m, z_star_m)
            .map(|p| self.components_prepared(&p))
    }

    /// The mixture likelihood `p(z | z*)` of one reading (1/m; a max-range reading's point mass is
    /// dimensionless). 0 for an invalid reading.
    pub fn beam_likelihood(&self, range_m: f32, z_star_m: f32) -> f32 {
        self.components(range_m, z_star_m)
            .map_or(0.0, |c| c.mix(self.intr.weights()))
    }

    /// `ln p(z | z*)` of one reading, nats, clamped below at [`BEAM_LOG_FLOOR`]; `None` for an
    /// invalid reading. Never NaN.
    pub fn beam_log_likelihood(&self, range_m: f32, z_star_m: f32) -> Option<f32> {
        let p = self.prepare(range_m, z_star_m)?;
        let linear = self.components_prepared(&p).mix(self.intr.weights());
        let l = if linear > LINEAR_SPACE_MIN {
            math::ln(linear)
        } else {
            self.log_mixture(&p)
        };
        Some(if l > BEAM_LOG_FLOOR {
            l
        } else {
            BEAM_LOG_FLOOR
        })
    }

    /// The log of the mixture from the component logarithms (max-shifted log-sum-exp).
    fn log_mixture(&self, p: &Prepared) -> f32 {
        let neg_inf = f32::NEG_INFINITY;
        let d = (p.z - p.z_star) * self.inv_sigma;
        let mass = self.hit_mass(p.z_star);
        let l_hit = if mass > 0.0 {
            self.ln_weights[0] + self.ln_hit_peak - math::ln(mass) - 0.5 * d * d
        } else {
            neg_inf
        };
        let l_short = if p.z_star > 0.0 && p.z <= p.z_star {
            let m = self.short_mass(p.z_star);
            if m > 0.0 {
                self.ln_weights[1] + self.ln_lambda
                    - self.intr.lambda_short_per_m() * p.z
                    - math::ln(m)
            } else {
                neg_inf
            }
        } else {
            neg_inf
        };
        let l_max = if p.is_max {
            self.ln_weights[2]
        } else {
            neg_inf
        };
        let l_rand = if p.is_max {
            neg_inf
        } else {
            self.ln_weights[3] + self.ln_inv_max_range
        };
        math::log_sum_exp4([l_hit, l_short, l_max, l_rand])
    }

    /// Scores a scan given the ray-cast range of each beam (`z_star_m[k]` for reading `k`).
    ///
    /// Readings are paired with `z_star_m` in order; readings without a partner are counted in
    /// [`ScanScore::unpaired`]. Every valid reading, max-range ones included, is scored.
    pub fn scan_log_likelihood<const N: usize>(
        &self,
        scan: &Scan<N>,
        z_star_m: &[f32],
    ) -> ScanScore {
        let mut score = ScanScore::default();
        let ranges = scan.ranges_m();
        let mut sum = 0.0f32;
        for (&z, &zs) in ranges.iter().zip(z_star_m) {
            match self.beam_log_likelihood(z, zs) {
                Some(l) => {
                    sum += l;
                    score.scored = score.scored.saturating_add(1);
                }
                None => score.invalid = score.invalid.saturating_add(1),
            }
        }
        score.unpaired = saturating_u16(ranges.len().saturating_sub(z_star_m.len()));
        score.log_likelihood = sum;
        score
    }

    /// As [`BeamModel::scan_log_likelihood`], with the layout's beam count checked: readings past
    /// the layout's last beam are counted as unpaired.
    pub fn scan_log_likelihood_in_layout<const N: usize>(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
        z_star_m: &[f32],
    ) -> ScanScore {
        let n = layout.len().min(z_star_m.len());
        let paired = z_star_m.get(..n).unwrap_or(&[]);
        self.scan_log_likelihood(scan, paired)
    }
}

pub(crate) fn saturating_u16(n: usize) -> u16 {
    u16::try_from(n).unwrap_or(u16::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toy() -> BeamModel {
        BeamModel::new(BeamIntrinsics::new(0.25, 0.25, 0.25, 0.25, 1.0, 0.5, 10.0).unwrap())
    }

    /// The chapter's worked example, component by component (docs/models.md#mixture).
    #[test]
    fn worked_example_components() {
        let m = toy();
        let c = m.components(4.5, 5.0).unwrap();
        assert!((c.hit - 0.352_066).abs() < 1e-6, "{}", c.hit);
        assert!((c.short - 0.057_412).abs() < 1e-6, "{}", c.short);
        assert_eq!(c.max, 0.0);
        assert!((c.rand - 0.1).abs() < 1e-7);
        assert!((m.beam_likelihood(4.5, 5.0) - 0.127_369).abs() < 1e-6);
        let c10 = m.components(10.0, 5.0).unwrap();
        assert_eq!((c10.max, c10.rand, c10.short), (1.0, 0.0, 0.0));
    }

    #[test]
    fn invalid_readings_are_skipped_and_counted() {
        let m = toy();
        let scan = Scan::<5>::from_ranges(&[f32::NAN, -1.0, f32::INFINITY, 4.0, 3.0]).unwrap();
        let s = m.scan_log_likelihood(&scan, &[5.0; 5]);
        assert_eq!((s.scored, s.invalid, s.unpaired), (3, 2, 0));
        assert!(s.log_likelihood.is_finite());
    }

    #[test]
    fn log_path_agrees_with_linear_path_where_both_work() {
        let m = toy();
        for &(z, zs) in &[(4.5, 5.0), (1.0, 9.0), (9.9, 0.5), (0.0, 0.0)] {
            let p = m.prepare(z, zs).unwrap();
            let lin = math::ln(m.components_prepared(&p).mix(m.intr.weights()));
            let log = m.log_mixture(&p);
            assert!((lin - log).abs() < 1e-5, "z={z} z*={zs}: {lin} vs {log}");
        }
    }

    #[test]
    fn far_reading_without_rand_stays_finite_and_exact() {
        let i = BeamIntrinsics::new(1.0, 0.0, 0.0, 0.0, 0.01, 1.0, 10.0).unwrap();
        let m = BeamModel::new(i);
        // d = 100 σ: the Gaussian is e^-5000, far below f32's range; the log is still exact.
        let l = m.beam_log_likelihood(6.0, 5.0).unwrap();
        let want = -5000.0 - (0.01f32).ln() - 0.918_938_5;
        assert!((l - want).abs() < 0.05, "{l} vs {want}");
    }
}
