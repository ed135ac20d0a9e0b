//! One pass over the data, in f64: the E-step at the current parameters θ_t (responsibilities,
//! sufficient statistics, the data log-likelihood) and, optionally, the expected complete
//! log-likelihood of the two shape parameters at a probe point, with its first and second
//! derivatives (for the truncation-aware M-step of [`super`]).
//!
//! Nothing per datum is kept: a pass is a fold into [`PassStats`].

use crate::math;
use crate::scan::Reading;

/// `ln √(2π)` in f64.
const LN_SQRT_2PI_F64: f64 = 0.918_938_533_204_672_8;
/// `1/√(2π)` in f64.
const INV_SQRT_2PI_F64: f64 = 0.398_942_280_401_432_7;
/// `1/√2` in f64.
const FRAC_1_SQRT_2_F64: f64 = core::f64::consts::FRAC_1_SQRT_2;

/// Above this argument `erf` is exactly 1.0 in f64 (`erfc(6) ≈ 2.2e-17`, under half an ulp of 1),
/// so the call is skipped without changing a bit of the result.
const ERF_IS_ONE: f64 = 6.0;

/// Below this argument `exp` is exactly 0.0 in f64 (`e^−746` is under half the smallest
/// subnormal), so the call is skipped without changing a bit of the result.
const EXP_IS_ZERO: f64 = -746.0;

/// The current parameters with the constants derived from them, f64.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Theta<const G: usize> {
    /// `ln w_c` per group, `[hit, short, max, rand]` (−∞ for a zero weight).
    pub ln_w: [[f64; 4]; G],
    pub inv_sigma: f64,
    /// `−ln σ − ln √(2π)`.
    pub ln_peak: f64,
    pub lambda: f64,
    pub ln_lambda: f64,
    pub zmax: f64,
    pub zmax_f32: f32,
    /// `−ln z_max`.
    pub ln_inv_zmax: f64,
}

impl<const G: usize> Theta<G> {
    pub fn new(w: &[[f32; 4]; G], sigma_m: f32, lambda_per_m: f32, zmax_m: f32) -> Self {
        let mut ln_w = [[0.0f64; 4]; G];
        for (lg, wg) in ln_w.iter_mut().zip(w) {
            for (l, &x) in lg.iter_mut().zip(wg) {
                *l = math::ln_f64(f64::from(x));
            }
        }
        let sigma = f64::from(sigma_m);
        let lambda = f64::from(lambda_per_m);
        let zmax = f64::from(zmax_m);
        Self {
            ln_w,
            inv_sigma: 1.0 / sigma,
            ln_peak: -math::ln_f64(sigma) - LN_SQRT_2PI_F64,
            lambda,
            ln_lambda: math::ln_f64(lambda),
            zmax,
            zmax_f32: zmax_m,
            ln_inv_zmax: -math::ln_f64(zmax),
        }
    }
}

/// Where the shape parameters' expected complete log-likelihood is evaluated in a pass, with the
/// per-probe constants computed once.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Probe {
    hit: Option<HitProbe>,
    short: Option<ShortProbe>,
}

/// Constants of a hit probe at precision `τ = 1/σ²` (1/m²).
#[derive(Clone, Copy, Debug)]
struct HitProbe {
    tau: f64,
    sqrt_tau: f64,
    half_ln_tau: f64,
    inv_2tau: f64,
    inv_4tau2: f64,
}

/// Constants of a short probe at rate λ (1/m).
#[derive(Clone, Copy, Debug)]
struct ShortProbe {
    lambda: f64,
    ln_lambda: f64,
    inv_lambda: f64,
    inv_lambda2: f64,
}

impl Probe {
    /// A probe at `τ` (if any) and `λ` (if any).
    pub fn new(tau: Option<f64>, lambda: Option<f64>) -> Self {
        Self {
            hit: tau.map(|tau| HitProbe {
                tau,
                sqrt_tau: math::sqrt_f64(tau),
                half_ln_tau: 0.5 * math::ln_f64(tau),
                inv_2tau: 0.5 / tau,
                inv_4tau2: 0.25 / (tau * tau),
            }),
            short: lambda.map(|lambda| ShortProbe {
                lambda,
                ln_lambda: math::ln_f64(lambda),
                inv_lambda: 1.0 / lambda,
                inv_lambda2: 1.0 / (lambda * lambda),
            }),
        }
    }

    /// A probe at both `τ` and `λ`.
    pub fn at(tau: f64, lambda: f64) -> Self {
        Self::new(Some(tau), Some(lambda))
    }
}

/// `(Q, dQ/dx, d²Q/dx²)` summed over the data.
pub(crate) type Curve = [f64; 3];

/// Everything one pass accumulates. All sums in f64 (see the module docs of [`super`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PassStats<const G: usize> {
    /// Readings used per group.
    pub n: [u64; G],
    /// `Σ_i e_{i,c}` per group.
    pub e: [[f64; 4]; G],
    /// `Σ_i ln p(z_i | z*_i, θ_t)`.
    pub ll: f64,
    /// NaN or negative readings.
    pub invalid: u64,
    /// Readings no cause with non-zero weight explains.
    pub unexplained: u64,
    /// Readings whose group index is out of range.
    pub bad_group: u64,
    /// `Σ_i e_{i,hit}·(z_i − z*_i)²`.
    pub hit_sq: f64,
    /// `Σ_i e_{i,short}·z_i`.
    pub short_z: f64,
    /// Hit part of Q at the probe τ (constants dropped) and its τ-derivatives.
    pub hit_curve: Curve,
    /// Short part of Q at the probe λ and its λ-derivatives.
    pub short_curve: Curve,
}

impl<const G: usize> Default for PassStats<G> {
    fn default() -> Self {
        Self {
            n: [0; G],
            e: [[0.0; 4]; G],
            ll: 0.0,
            invalid: 0,
            unexplained: 0,
            bad_group: 0,
            hit_sq: 0.0,
            short_z: 0.0,
            hit_curve: [0.0; 3],
            short_curve: [0.0; 3],
        }
    }
}

impl<const G: usize> PassStats<G> {
    /// Readings used in all groups.
    pub fn used(&self) -> u64 {
        self.n.iter().sum()
    }

    /// `Σ_g Σ_i e_{i,c}` for component `c`.
    pub fn total(&self, c: usize) -> f64 {
        self.e.iter().filter_map(|g| g.get(c)).sum()
    }

    /// Folds one reading in: E-step at `th`, and the probe's Q terms if asked for.
    #[inline]
    pub fn visit(
        &mut self,
        th: &Theta<G>,
        probe: &Probe,
        group: usize,
        range_m: f32,
        z_star_m: f32,
    ) {
        let (Some(ln_w), Some(n), Some(e_acc)) = (
            th.ln_w.get(group),
            self.n.get_mut(group),
            self.e.get_mut(group),
        ) else {
            self.bad_group += 1;
            return;
        };
        let (z, is_max) = match Reading::classify(range_m, th.zmax_f32) {
            Reading::Invalid => {
                self.invalid += 1;
                return;
            }
            Reading::MaxRange => (th.zmax, true),
            Reading::Range(z) => (f64::from(z), false),
        };
        let s = if z_star_m.is_nan() {
            th.zmax
        } else {
            f64::from(z_star_m.clamp(0.0, th.zmax_f32))
        };
        let d = z - s;
        let u = d * th.inv_sigma;
        let l_hit = ln_w[0] + th.ln_peak - ln_hit_mass(s, th.zmax, th.inv_sigma) - 0.5 * u * u;
        let short_ok = s > 0.0 && z <= s;
        // The short normalizer at θ's λ, shared with the short probe when that is at the same λ
        // (the E-step pass of the default update): one expm1 and one ln per reading, not two.
        let short_norm = if short_ok {
            Some(ShortNorm::new(th.lambda, s))
        } else {
            None
        };
        let l_short = match &short_norm {
            Some(sn) => ln_w[1] + th.ln_lambda - th.lambda * z - sn.ln_one_minus,
            None => f64::NEG_INFINITY,
        };
        let (l_max, l_rand) = if is_max {
            (ln_w[2], f64::NEG_INFINITY)
        } else {
            (f64::NEG_INFINITY, ln_w[3] + th.ln_inv_zmax)
        };
        let l = [l_hit, l_short, l_max, l_rand];
        let m = l.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        if m == f64::NEG_INFINITY || m.is_nan() {
            self.unexplained += 1;
            return;
        }
        let mut r = [0.0f64; 4];
        for (ri, &li) in r.iter_mut().zip(&l) {
            *ri = if li == m {
                1.0
            } else if li - m < EXP_IS_ZERO {
                // exp would round to exactly 0 (this also covers li = −∞).
                0.0
            } else {
                math::exp_f64(li - m)
            };
        }
        let total: f64 = r.iter().sum();
        self.ll += m + math::ln_f64(total);
        *n += 1;
        let inv_total = 1.0 / total;
        for (acc, &ri) in e_acc.iter_mut().zip(&r) {
            *acc += ri * inv_total;
        }
        let e_hit = r[0] * inv_total;
        let e_short = r[1] * inv_total;
        self.hit_sq += e_hit * d * d;
        self.short_z += e_short * z;
        if let Some(hp) = &probe.hit {
            if e_hit > 0.0 {
                let c = hit_curve(hp, d, s, th.zmax);
                for (a, b) in self.hit_curve.iter_mut().zip(c) {
                    *a += e_hit * b;
                }
            }
        }
        if let Some(sp) = &probe.short {
            if e_short > 0.0 {
                let norm = match short_norm {
                    Some(sn) if sp.lambda == th.lambda => sn,
                    _ => ShortNorm::new(sp.lambda, s),
                };
                let c = short_curve(sp, z, s, &norm);
                for (a, b) in self.short_curve.iter_mut().zip(c) {
                    *a += e_short * b;
                }
            }
        }
    }
}

/// `½·erf(x/√2)` for `x ≥ 0`: the standard normal mass between 0 and `x`.
#[inline]
fn half_mass(x: f64) -> f64 {
    let y = x * FRAC_1_SQRT_2_F64;
    if y > ERF_IS_ONE {
        0.5
    } else {
        0.5 * math::erf_f64(y)
    }
}

/// `ln(Φ((z_max − z*)/σ) − Φ(−z*/σ))`, the log of `1/η_hit`. 0 (exactly) when both ends are
/// more than 8.5 σ away.
#[inline]
fn ln_hit_mass(s: f64, zmax: f64, inv_sigma: f64) -> f64 {
    let mass = half_mass((zmax - s) * inv_sigma) + half_mass(s * inv_sigma);
    if mass == 1.0 {
        0.0
    } else {
        math::ln_f64(mass)
    }
}

/// `(x·φ(x), x³·φ(x))`, standard normal density terms. Beyond |x| = 10 both are below 1e-19,
/// under an ulp of the terms (≈ 1 and ≈ 3) they are subtracted from, and are returned as 0.
#[inline]
fn phi_terms(x: f64) -> (f64, f64) {
    if x * x > 100.0 {
        return (0.0, 0.0);
    }
    let p = INV_SQRT_2PI_F64 * math::exp_f64(-0.5 * x * x);
    (x * p, x * x * x * p)
}

/// One reading's hit term of Q as a function of the precision `τ = 1/σ²` (the constant
/// `−ln √(2π)` dropped), with its first two τ-derivatives:
///
/// ```text
/// ℓ(τ)   = ½·ln τ − τ·d²/2 − ln M(τ),   M(τ) = Φ(β) − Φ(α), α = −z*·√τ, β = (z_max − z*)·√τ
/// ℓ'(τ)  = −d²/2 + E[u²]/(2τ)
/// ℓ''(τ) = −(E[u⁴] − E[u²]²)/(4τ²)  ≤ 0
/// ```
///
/// with `u` a standard normal truncated to `[α, β]`:
/// `E[u²] = 1 − (βφ(β) − αφ(α))/M`, `E[u⁴] = 3·E[u²] − (β³φ(β) − α³φ(α))/M`. The truncated
/// normal with a fixed mean is an exponential family along τ, which is why ℓ is concave in τ.
#[inline]
fn hit_curve(hp: &HitProbe, d: f64, s: f64, zmax: f64) -> Curve {
    let (tau, rt) = (hp.tau, hp.sqrt_tau);
    let alpha = -s * rt;
    let beta = (zmax - s) * rt;
    let mass = half_mass(beta) + half_mass(-alpha);
    let (a1, a3) = phi_terms(alpha);
    let (b1, b3) = phi_terms(beta);
    let (ln_mass, eu2, eu4) = if mass == 1.0 && a1 == 0.0 && b1 == 0.0 {
        (0.0, 1.0, 3.0)
    } else {
        let eu2 = 1.0 - (b1 - a1) / mass;
        (math::ln_f64(mass), eu2, 3.0 * eu2 - (b3 - a3) / mass)
    };
    let q = hp.half_ln_tau - 0.5 * tau * d * d - ln_mass;
    let g = -0.5 * d * d + eu2 * hp.inv_2tau;
    let h = -(eu4 - eu2 * eu2) * hp.inv_4tau2;
    [q, g, h]
}

/// One reading's short term of Q as a function of λ, with its first two λ-derivatives:
///
/// ```text
/// ℓ(λ)   = ln λ − λ·z − ln(1 − e^{−λz*})
/// ℓ'(λ)  = 1/λ − z − z*/(e^{λz*} − 1)
/// ℓ''(λ) = −1/λ² + z*²·e^{λz*}/(e^{λz*} − 1)²  ≤ 0
/// ```
///
/// (concave: with `x = λz*`, `x²e^x/(e^x − 1)² = ((x/2)/sinh(x/2))² ≤ 1`).
///
/// `norm` is [`ShortNorm`] at `(sp.lambda, s)`.
#[inline]
fn short_curve(sp: &ShortProbe, z: f64, s: f64, norm: &ShortNorm) -> Curve {
    let lambda = sp.lambda;
    let q = sp.ln_lambda - lambda * z - norm.ln_one_minus;
    let g = sp.inv_lambda - z - s / norm.em1;
    let h = -sp.inv_lambda2 + s * s / (norm.em1 * norm.one_minus);
    [q, g, h]
}

/// The truncation normalizer of the short component at rate λ and wall `z* > 0`:
/// `1 − e^{−λz*}`, formed as `(e^x − 1)/(e^x − 1 + 1)` with `x = λz*` (one `expm1`, no
/// cancellation; `1` once `e^x` overflows), its logarithm, and `e^x − 1` itself (which the
/// λ-derivatives of [`short_curve`] need).
#[derive(Clone, Copy, Debug)]
struct ShortNorm {
    em1: f64,
    one_minus: f64,
    ln_one_minus: f64,
}

impl ShortNorm {
    #[inline]
    fn new(lambda: f64, s: f64) -> Self {
        let em1 = math::expm1_f64(lambda * s);
        let one_minus = if em1.is_finite() {
            em1 / (em1 + 1.0)
        } else {
            1.0
        };
        Self {
            em1,
            one_minus,
            ln_one_minus: math::ln_f64(one_minus),
        }
    }
}
