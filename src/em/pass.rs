//! One pass over the data, in f64: the E-step at the current parameters θ_t (responsibilities,
//! sufficient statistics, the data log-likelihood) and, optionally, the expected complete
//! log-likelihood of the two shape parameters at a probe point, with its first and second
//! derivatives (for the truncation-aware M-step of [`super`]).
//!
//! Nothing per datum is kept: a pass is a fold into [`PassStats`].

use super::exp::{self, LN2_HI, LN2_LO};
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

/// Range of a reading's density total (1/m) handled by the linear E-step of
/// [`PassStats::visit`] (`≈ 2⁻⁸⁹⁷` to `2⁸⁹⁷`); outside it, the log-domain E-step.
const LINEAR_MIN: f64 = 1e-270;
const LINEAR_MAX: f64 = 1e270;

/// The 52 fraction bits of an f64.
const MANTISSA_BITS: u64 = (1u64 << 52) - 1;
/// The bits of 1.0 (biased exponent 1023, fraction 0).
const ONE_BITS: u64 = 1023u64 << 52;

/// The current parameters with the constants derived from them, f64.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Theta<const G: usize> {
    /// `ln w_c` per group, `[hit, short, max, rand]` (−∞ for a zero weight).
    pub ln_w: [[f64; 4]; G],
    /// The per-reading constant factor of each component's density per group, for the linear
    /// E-step: `[w_hit/(σ·√(2π)) (1/m), w_short·λ (1/m), w_max, w_rand/z_max (1/m)]`.
    pub lin_w: [[f64; 4]; G],
    pub inv_sigma: f64,
    /// `−ln σ − ln √(2π)`.
    pub ln_peak: f64,
    pub lambda: f64,
    pub ln_lambda: f64,
    pub zmax: f64,
    pub zmax_f32: f32,
    /// `−ln z_max`.
    pub ln_inv_zmax: f64,
    /// `z*` strictly between these (metres) has a hit mass of exactly 1: see [`mass_one_margin`].
    pub mass_one: (f64, f64),
}

impl<const G: usize> Theta<G> {
    /// The E-step at `w` renormalized to sum to 1 in f64 (see [`normalized`]), `σ`, `λ`, `z_max`.
    pub fn new(w: &[[f32; 4]; G], sigma_m: f32, lambda_per_m: f32, zmax_m: f32) -> Self {
        let wn = w.map(|g| normalized(&g));
        let mut ln_w = [[0.0f64; 4]; G];
        for (lg, wg) in ln_w.iter_mut().zip(&wn) {
            for (l, &x) in lg.iter_mut().zip(wg) {
                *l = math::ln_f64(x);
            }
        }
        let sigma = f64::from(sigma_m);
        let lambda = f64::from(lambda_per_m);
        let zmax = f64::from(zmax_m);
        let mut lin_w = [[0.0f64; 4]; G];
        for (lg, wg) in lin_w.iter_mut().zip(&wn) {
            let [wh, ws, wm, wr] = *wg;
            *lg = [wh * INV_SQRT_2PI_F64 / sigma, ws * lambda, wm, wr / zmax];
        }
        Self {
            ln_w,
            lin_w,
            inv_sigma: 1.0 / sigma,
            ln_peak: -math::ln_f64(sigma) - LN_SQRT_2PI_F64,
            lambda,
            ln_lambda: math::ln_f64(lambda),
            zmax,
            zmax_f32: zmax_m,
            ln_inv_zmax: -math::ln_f64(zmax),
            mass_one: {
                let m = mass_one_margin(sigma);
                (m, zmax - m)
            },
        }
    }
}

/// Where the shape parameters' expected complete log-likelihood is evaluated in a pass, with the
/// per-probe constants computed once.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Probe {
    hit: Option<HitProbe>,
    short: Option<ShortProbe>,
    /// Whether the values of the terms (`Curve[0]` of [`PassStats::hit_curve`] and
    /// [`PassStats::short_curve`]) are wanted. Without them the pass skips one `ln` per
    /// short-range reading and one per hit reading near a truncation end, and leaves those
    /// entries 0; the derivatives are always computed.
    values: bool,
}
/// Constants of a hit probe at precision `τ = 1/σ²` (1/m²).
#[derive(Clone, Copy, Debug)]
struct HitProbe {
    tau: f64,
    /// `10·(1 + 10⁻⁶)/√τ`, metres: a `z*` farther than this from both ends is interior (see
    /// [`hit_curve_interior`]).
    interior_margin: f64,
    /// `√τ = 1/σ`; when it equals [`Theta::inv_sigma`] bit for bit, the probe's truncation
    /// mass is the E-step's (same formula, same operands) and is not recomputed.
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

impl HitProbe {
    fn new(tau: f64, sqrt_tau: f64) -> Self {
        Self {
            tau,
            interior_margin: 10.0 * (1.0 + 1e-6) / sqrt_tau,
            sqrt_tau,
            half_ln_tau: 0.5 * math::ln_f64(tau),
            inv_2tau: 0.5 / tau,
            inv_4tau2: 0.25 / (tau * tau),
        }
    }
}

impl Probe {
    /// A probe at `τ` (if any) and `λ` (if any), with the values.
    pub fn new(tau: Option<f64>, lambda: Option<f64>) -> Self {
        Self {
            hit: tau.map(|tau| HitProbe::new(tau, math::sqrt_f64(tau))),
            short: lambda.map(ShortProbe::new),
            values: true,
        }
    }

    /// A probe at the E-step's own `σ` (metres, as [`Theta`] holds it: `τ = 1/σ²`,
    /// `√τ = 1/σ` computed as [`Theta::new`] does, so the pass shares the truncation mass) and
    /// `λ` (1/m, which shares the short normalizer). `values`: see [`Probe::values`]; the
    /// one-step update of [`super::ShapeUpdate::Truncated`] needs only the derivatives.
    pub fn at_theta(sigma: f64, lambda: f64, values: bool) -> Self {
        Self {
            hit: Some(HitProbe::new(1.0 / (sigma * sigma), 1.0 / sigma)),
            short: Some(ShortProbe::new(lambda)),
            values,
        }
    }
}

impl ShortProbe {
    fn new(lambda: f64) -> Self {
        Self {
            lambda,
            ln_lambda: math::ln_f64(lambda),
            inv_lambda: 1.0 / lambda,
            inv_lambda2: 1.0 / (lambda * lambda),
        }
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
    /// `Σ_i ln p(z_i | z*_i, θ_t)` over the readings of the log-domain E-step (see
    /// [`PassStats::visit`]); the others are in `ll_mant`, `ll_exp`. Read the total with
    /// [`PassStats::log_likelihood`].
    ll: f64,
    /// Mantissa of `Π_i p(z_i | z*_i, θ_t)` over the readings of the linear E-step, in `[1, 2)`.
    ll_mant: f64,
    /// Binary exponent of that product: the product is `ll_mant · 2^ll_exp`.
    ll_exp: i64,
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
    /// Hit part of Q at the probe τ (constants dropped) and its τ-derivatives (complete only
    /// after [`PassStats::finish`]).
    pub hit_curve: Curve,
    /// `Σ e_hit` and `Σ e_hit·d²` over the readings whose hit term at the probe τ has the
    /// untruncated form (see [`hit_curve_interior`]), folded into `hit_curve` by `finish`.
    hit_interior: [f64; 2],
    /// Short part of Q at the probe λ and its λ-derivatives.
    pub short_curve: Curve,
}

impl<const G: usize> Default for PassStats<G> {
    fn default() -> Self {
        Self {
            n: [0; G],
            e: [[0.0; 4]; G],
            ll: 0.0,
            ll_mant: 1.0,
            ll_exp: 0,
            invalid: 0,
            unexplained: 0,
            bad_group: 0,
            hit_sq: 0.0,
            short_z: 0.0,
            hit_curve: [0.0; 3],
            hit_interior: [0.0; 2],
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

    /// `Σ_i ln p(z_i | z*_i, θ_t)` over all used readings, nats.
    pub fn log_likelihood(&self) -> f64 {
        // The product is ll_mant·2^ll_exp; ll_exp·ln 2 in two parts (see LN2_HI).
        let e = self.ll_exp as f64;
        self.ll + math::ln_f64(self.ll_mant) + e * LN2_LO + e * LN2_HI
    }

    /// Completes the pass's sums: adds the interior hit terms (see [`hit_curve_interior`]) at
    /// the pass's `probe`. Call once, after the last [`PassStats::visit`].
    pub fn finish(&mut self, probe: &Probe) {
        if let Some(hp) = &probe.hit {
            let [e, sq] = self.hit_interior;
            // Σ e·(½ln τ − τd²/2), Σ e·(−d²/2 + 1/(2τ)), Σ e·(−2/(4τ²)): E[u²] = 1, E[u⁴] = 3.
            if probe.values {
                self.hit_curve[0] += hp.half_ln_tau * e - 0.5 * hp.tau * sq;
            }
            self.hit_curve[1] += -0.5 * sq + hp.inv_2tau * e;
            self.hit_curve[2] += -2.0 * hp.inv_4tau2 * e;
        }
        self.hit_interior = [0.0; 2];
    }

    /// Folds one reading in: E-step at `th`, and the probe's Q terms if asked for.
    ///
    /// The E-step works on the component densities themselves (linear domain): one `exp` for
    /// the hit density, one `exp` and one `expm1` for the short one (only where `z ≤ z*`; one
    /// two-lane [`exp::exp_pair`] where `λz* ≥ ln 2`), none for max and rand, and no `ln` per reading: the reading's density is multiplied into a
    /// running product kept as a mantissa in `[1, 2)` and a binary exponent (exact integer
    /// bookkeeping, so it cannot under- or overflow), and [`PassStats::log_likelihood`] takes one
    /// `ln` per pass. This needs the density total to be a normal number well inside the
    /// range: a total outside `[LINEAR_MIN, LINEAR_MAX]` (or not finite) sends the reading to
    /// the log-domain E-step instead (log-sum-exp, exactly as before), which never underflows.
    /// Inside that range the two agree to f64 rounding: a component that underflows in the
    /// linear domain (below 2⁻¹⁰²²) has a responsibility below 2⁻¹⁰²²/`LINEAR_MIN` < 2⁻¹²⁵ in
    /// both, under the rounding of any responsibility sum it is added to.
    #[inline]
    pub fn visit(
        &mut self,
        th: &Theta<G>,
        probe: &Probe,
        group: usize,
        range_m: f32,
        z_star_m: f32,
    ) {
        let (Some(ln_w), Some(lin_w), Some(n), Some(e_acc)) = (
            th.ln_w.get(group),
            th.lin_w.get(group),
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
        let half_u2 = 0.5 * u * u;
        // Exactly 1 inside the interval (see mass_one_margin): no products, no erf tests.
        let mass = if s > th.mass_one.0 && s < th.mass_one.1 {
            1.0
        } else {
            hit_mass(s, th.zmax, th.inv_sigma)
        };
        let short_ok = s > 0.0 && z <= s;
        // The short normalizer at θ's λ, shared with the short probe when that is at the same λ
        // (the E-step pass of the truncated updates).
        let short_norm = if short_ok {
            Some(ShortNorm::with_density(th.lambda, s, z))
        } else {
            None
        };

        // Linear domain: the four component densities (1/m; the max one a point mass).
        let p_hit = if -half_u2 < EXP_IS_ZERO {
            0.0
        } else if mass == 1.0 {
            // The common case (z* more than 8.5 σ from both ends): no division.
            lin_w[0] * exp::exp(-half_u2)
        } else {
            lin_w[0] * exp::exp(-half_u2) / mass
        };
        let p_short = match &short_norm {
            Some(sn) => lin_w[1] * sn.exp_neg_lambda_z * sn.inv_one_minus(),
            None => 0.0,
        };
        let (p_max, p_rand) = if is_max {
            (lin_w[2], 0.0)
        } else {
            (0.0, lin_w[3])
        };
        let lin_total = p_hit + p_short + p_max + p_rand;
        let (r, inv_total) = if (LINEAR_MIN..=LINEAR_MAX).contains(&lin_total) {
            fold_density(&mut self.ll_mant, &mut self.ll_exp, lin_total);
            ([p_hit, p_short, p_max, p_rand], 1.0 / lin_total)
        } else {
            // Log domain (log-sum-exp), for totals the linear form cannot carry.
            let l_hit = ln_w[0] + th.ln_peak - ln_of_mass(mass) - half_u2;
            let l_short = match &short_norm {
                Some(sn) => ln_w[1] + th.ln_lambda - th.lambda * z - math::ln_f64(sn.one_minus()),
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
            (r, 1.0 / total)
        };
        *n += 1;
        for (acc, &ri) in e_acc.iter_mut().zip(&r) {
            *acc += ri * inv_total;
        }
        let e_hit = r[0] * inv_total;
        let e_short = r[1] * inv_total;
        self.hit_sq += e_hit * d * d;
        self.short_z += e_short * z;
        if let Some(hp) = &probe.hit {
            if e_hit > 0.0 {
                if hit_curve_interior(hp, s, th.zmax) {
                    // ℓ is a + b·d² with a, b fixed by τ: two sums, folded in by `finish`.
                    self.hit_interior[0] += e_hit;
                    self.hit_interior[1] += e_hit * d * d;
                } else {
                    // The E-step's mass when the probe is at θ's σ (see HitProbe::sqrt_tau).
                    let m = if hp.sqrt_tau == th.inv_sigma {
                        mass
                    } else {
                        hit_mass(s, th.zmax, hp.sqrt_tau)
                    };
                    let c = hit_curve(hp, d, s, th.zmax, m, probe.values);
                    for (a, b) in self.hit_curve.iter_mut().zip(c) {
                        *a += e_hit * b;
                    }
                }
            }
        }
        if let Some(sp) = &probe.short {
            if e_short > 0.0 {
                let norm = match short_norm {
                    Some(sn) if sp.lambda == th.lambda => sn,
                    _ => ShortNorm::new(sp.lambda, s),
                };
                let c = short_curve(sp, z, s, &norm, probe.values);
                for (a, b) in self.short_curve.iter_mut().zip(c) {
                    *a += e_short * b;
                }
            }
        }
    }
}

/// The f32 weights `w` as f64, divided by their f64 sum (exact: four f32 values sum exactly in
/// f64 up to one rounding), so that they sum to 1 to f64 rounding. f32 storage leaves the stored
/// weights' sum off 1 by up to `2⁻²⁴` (each of the four is rounded by at most half an ulp,
/// `2⁻²⁵·w_c`, relative), and since the mixture is linear in the weights that would shift every
/// reading's log-likelihood by `ln Σw`, up to `6·10⁻⁸` nats, differently after every M-step:
/// more than the late EM steps gain. The E-step's responsibilities do not depend on this
/// scaling; only the log-likelihood does. A zero sum (not on the simplex) is left as it is.
pub fn normalized(w: &[f32; 4]) -> [f64; 4] {
    let w = w.map(f64::from);
    let sum: f64 = w.iter().sum();
    if sum > 0.0 {
        w.map(|x| x / sum)
    } else {
        w
    }
}

/// Multiplies a reading's density `p ∈ [LINEAR_MIN, LINEAR_MAX]` into the running product
/// `mant·2^exp`. The mantissa stays in `[1, 2)`, so `mant·p` is a normal f64
/// (`2⁻⁸⁹⁷ ≤ · < 2⁸⁹⁸`) and splitting off its exponent is exact.
#[inline]
fn fold_density(mant: &mut f64, exp: &mut i64, p: f64) {
    let bits = (*mant * p).to_bits();
    // Biased exponent field (11 bits); the product is normal, so it is in 1..=2046.
    let biased = ((bits >> 52) & 0x7ff) as i64;
    *exp += biased - 1023;
    *mant = f64::from_bits((bits & MANTISSA_BITS) | ONE_BITS);
}

/// Distance from an end of `[0, z_max]` (metres) beyond which [`hit_mass`] is exactly 1 for a
/// `z*` at that distance from both ends, with the computed operands: `6·√2·σ·(1 + 10⁻⁶)`.
/// Proof: the computed `y = (x·(1/σ))·(1/√2)` in [`half_mass`] carries at most 4 roundings of
/// relative size 2⁻⁵³ (`1/σ`, the two products, the constant), and `x = z*` or `z_max − z*` is
/// exact or one correctly rounded subtraction, so `y > 6·(1 + 10⁻⁶)·(1 − 5·2⁻⁵³) > 6 =`
/// `ERF_IS_ONE` and both halves are exactly 0.5. The margin (`8.5e-6·σ`) also dwarfs the
/// rounding of the bounds themselves (≤ 2⁻⁵² z_max, and σ ≥ 10⁻⁶·z_max). Outside the interval
/// the mass is computed as before, so the shortcut changes no result.
fn mass_one_margin(sigma: f64) -> f64 {
    ERF_IS_ONE * core::f64::consts::SQRT_2 * sigma * (1.0 + 1e-6)
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

/// `Φ((z_max − z*)/σ) − Φ(−z*/σ)`, the hit component's mass on `[0, z_max]`, `1/η_hit`.
/// Exactly 1.0 (no `erf` call) when both ends are more than `ERF_IS_ONE·√2 ≈ 8.5` σ away.
#[inline]
fn hit_mass(s: f64, zmax: f64, inv_sigma: f64) -> f64 {
    half_mass((zmax - s) * inv_sigma) + half_mass(s * inv_sigma)
}

/// `ln(mass)`, 0 (exactly, no call) for a mass of 1.
#[inline]
fn ln_of_mass(mass: f64) -> f64 {
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
    let p = INV_SQRT_2PI_F64 * exp::exp(-0.5 * x * x);
    (x * p, x * x * x * p)
}

/// Whether a reading's hit term at the probe τ is untruncated to f64 precision: both ends
/// `α = −z*·√τ`, `β = (z_max − z*)·√τ` beyond 10 in magnitude. Then [`hit_curve`] takes its
/// first branch exactly (`x² > 100` zeroes both density terms, and `|x|/√2 > 7.07 > ERF_IS_ONE`
/// makes the mass exactly 1), so its value is `(½ln τ − τd²/2, −d²/2 + 1/(2τ), −2/(4τ²))`,
/// linear in `1` and `d²`: the pass sums `e_hit` and `e_hit·d²` instead (no `erf`, no `exp`).
///
/// Tested as `z*` and `z_max − z*` both above `10·(1 + 10⁻⁶)/√τ` (two comparisons per reading,
/// the bound computed once per probe): with at most a few roundings of relative size 2⁻⁵³ in
/// the bound, the subtraction and the products, that implies the computed `α² > 100` and
/// `β² > 100` that [`hit_curve`]'s first branch tests. A reading within the margin goes
/// through [`hit_curve`] itself, whose result there is the same closed form.
#[inline]
fn hit_curve_interior(hp: &HitProbe, s: f64, zmax: f64) -> bool {
    s > hp.interior_margin && zmax - s > hp.interior_margin
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
///
/// `mass` is `M(τ)`, [`hit_mass`] at `(s, zmax, hp.sqrt_tau)`. Without `value` the first entry
/// is 0 (and no `ln` is taken).
#[inline]
fn hit_curve(hp: &HitProbe, d: f64, s: f64, zmax: f64, mass: f64, value: bool) -> Curve {
    let (tau, rt) = (hp.tau, hp.sqrt_tau);
    let alpha = -s * rt;
    let beta = (zmax - s) * rt;
    let (a1, a3) = phi_terms(alpha);
    let (b1, b3) = phi_terms(beta);
    let (eu2, eu4) = if mass == 1.0 && a1 == 0.0 && b1 == 0.0 {
        (1.0, 3.0)
    } else {
        let eu2 = 1.0 - (b1 - a1) / mass;
        (eu2, 3.0 * eu2 - (b3 - a3) / mass)
    };
    let q = if value {
        hp.half_ln_tau - 0.5 * tau * d * d - ln_of_mass(mass)
    } else {
        0.0
    };
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
/// `norm` is [`ShortNorm`] at `(sp.lambda, s)`. Without `value` the first entry is 0 (and no
/// `ln` is taken).
#[inline]
fn short_curve(sp: &ShortProbe, z: f64, s: f64, norm: &ShortNorm, value: bool) -> Curve {
    let lambda = sp.lambda;
    let q = if value {
        sp.ln_lambda - lambda * z - math::ln_f64(norm.one_minus())
    } else {
        0.0
    };
    // z*/(e^x − 1) and z*²·e^x/(e^x − 1)² = z*²·(1/(e^x − 1))·(1 + 1/(e^x − 1)).
    let g = sp.inv_lambda - z - s * norm.inv_em1;
    let h = -sp.inv_lambda2 + s * s * norm.inv_em1 * norm.inv_one_minus();
    [q, g, h]
}

/// The truncation normalizer of the short component at rate λ and wall `z* > 0`,
/// `1 − e^{−λz*}`, through `e^x − 1` with `x = λz*` (no cancellation) and its reciprocal: one
/// `e^x − 1` and one division per reading. `1/(1 − e^{−x}) = 1 + 1/(e^x − 1)`; once `e^x`
/// overflows the reciprocal is 0 and the normalizer 1.
#[derive(Clone, Copy, Debug)]
struct ShortNorm {
    em1: f64,
    inv_em1: f64,
    /// `e^{−λz}` for the E-step's short density (only from [`ShortNorm::with_density`]).
    exp_neg_lambda_z: f64,
}

impl ShortNorm {
    #[inline]
    fn new(lambda: f64, s: f64) -> Self {
        let em1 = exp::expm1_nonneg(lambda * s);
        Self {
            em1,
            inv_em1: 1.0 / em1,
            exp_neg_lambda_z: 0.0,
        }
    }

    /// [`ShortNorm::new`] and `e^{−λz}` for a reading `z ≤ s`. Where `e^{λs} − 1` is `e^{λs}`
    /// minus 1 (`λs ≥ ln 2`, see [`exp::expm1_nonneg`]) the two exponentials are one
    /// [`exp::exp_pair`], with the same results.
    #[inline]
    fn with_density(lambda: f64, s: f64, z: f64) -> Self {
        let x = lambda * s;
        let (em1, e) = if x >= core::f64::consts::LN_2 {
            let [ex, e] = exp::exp_pair([x, -lambda * z]);
            (ex - 1.0, e)
        } else {
            (exp::expm1_nonneg(x), exp::exp(-lambda * z))
        };
        Self {
            em1,
            inv_em1: 1.0 / em1,
            exp_neg_lambda_z: e,
        }
    }

    /// `1/(1 − e^{−x})`.
    #[inline]
    fn inv_one_minus(&self) -> f64 {
        1.0 + self.inv_em1
    }

    /// `1 − e^{−x}`, as `(e^x − 1)/(e^x − 1 + 1)`.
    #[inline]
    fn one_minus(&self) -> f64 {
        if self.em1.is_finite() {
            self.em1 / (self.em1 + 1.0)
        } else {
            1.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The skipped `erf` of [`half_mass`] is the full formula bit for bit: `erfc(6) ≈ 2.2e-17`
    /// is under half an ulp of 1 (2⁻⁵⁴ ≈ 5.6e-17), so `erf(y)` rounds to exactly 1.0 from
    /// `y = 6` on (erf is increasing), and `0.5·1.0 = 0.5`.
    #[test]
    fn skipped_erf_is_exact_at_and_beyond_the_threshold() {
        let mut y = ERF_IS_ONE;
        while y < 40.0 {
            assert_eq!(math::erf_f64(y).to_bits(), 1.0f64.to_bits(), "erf({y})");
            y = y * 1.001 + 1e-3;
        }
        for y in [
            ERF_IS_ONE,
            f64::from_bits(ERF_IS_ONE.to_bits() + 1),
            1e3,
            1e300,
        ] {
            assert_eq!(math::erf_f64(y).to_bits(), 1.0f64.to_bits(), "erf({y})");
        }
        // half_mass with the skip against the formula, across the threshold x = 6·√2.
        for i in 0..20_000 {
            let x = 8.0 + f64::from(i) * 1e-4;
            assert_eq!(
                half_mass(x).to_bits(),
                (0.5 * math::erf_f64(x * FRAC_1_SQRT_2_F64)).to_bits(),
                "{x}"
            );
        }
        // And the hit mass is exactly 1 once both ends are past the threshold.
        assert_eq!(hit_mass(5.0, 30.0, 1.0 / 0.15).to_bits(), 1.0f64.to_bits());
        assert!(hit_mass(1.0, 30.0, 1.0 / 0.15) < 1.0);
    }

    /// The interval tests stand for the per-reading formulas they replace: inside
    /// `Theta::mass_one` the mass is exactly 1, and [`hit_curve_interior`] implies the
    /// computed `α² > 100 && β² > 100` of [`hit_curve`]; checked densely across both bounds
    /// for σ over eight decades (down to the 10⁻⁶·z_max floor).
    #[test]
    fn interval_shortcuts_imply_the_formulas() {
        let mut inside = 0u64;
        for zmax in [2.0f32, 8.0, 30.0, 81.83] {
            let zmax64 = f64::from(zmax);
            for rel in [1e-6f32, 1e-5, 1e-3, 0.004, 0.03, 0.1, 0.3] {
                let sigma = zmax * rel;
                let th = Theta::<1>::new(&[[0.7, 0.1, 0.1, 0.1]], sigma, 0.5, zmax);
                let probe = Probe::at_theta(f64::from(sigma), 0.5, true);
                let hp = probe.hit.unwrap();
                let (lo, hi) = th.mass_one;
                let ilo = hp.interior_margin;
                for base in [lo, hi, ilo, zmax64 - ilo] {
                    let mut s = base;
                    let mut t = base;
                    for _ in 0..3_000 {
                        for x in [s, t] {
                            if x > lo && x < hi {
                                inside += 1;
                                let m = hit_mass(x, zmax64, th.inv_sigma);
                                assert_eq!(m.to_bits(), 1.0f64.to_bits(), "{x} {sigma}");
                            }
                            if hit_curve_interior(&hp, x, zmax64) {
                                let a = -x * hp.sqrt_tau;
                                let b = (zmax64 - x) * hp.sqrt_tau;
                                assert!(a * a > 100.0 && b * b > 100.0, "{x} {sigma}");
                            }
                        }
                        s = f64::from_bits(s.to_bits() + 1);
                        t = f64::from_bits(t.to_bits() - 1);
                    }
                }
            }
        }
        assert!(inside > 50_000, "{inside}");
    }

    /// Where [`hit_curve_interior`] holds, [`hit_curve`] is exactly the closed form that
    /// [`PassStats::finish`] sums (so the interior shortcut only reassociates the sum).
    #[test]
    fn interior_hit_curve_is_the_closed_form() {
        let zmax = 30.0;
        let mut interior = 0;
        for sigma in [0.01, 0.15, 1.0, 3.0] {
            let probe = Probe::new(Some(1.0 / (sigma * sigma)), None);
            let hp = probe.hit.unwrap();
            for i in 0..=3_000 {
                let s = zmax * f64::from(i) / 3_000.0;
                let d = 0.37 * sigma - 0.001 * f64::from(i % 7);
                let full = hit_curve(&hp, d, s, zmax, hit_mass(s, zmax, hp.sqrt_tau), true);
                if hit_curve_interior(&hp, s, zmax) {
                    interior += 1;
                    let closed = [
                        hp.half_ln_tau - 0.5 * hp.tau * d * d,
                        -0.5 * d * d + hp.inv_2tau,
                        -2.0 * hp.inv_4tau2,
                    ];
                    for (a, b) in full.iter().zip(closed) {
                        assert_eq!(a.to_bits(), b.to_bits(), "σ {sigma} z* {s}");
                    }
                } else {
                    // Near an end the truncation terms matter: not the closed form.
                    assert!(
                        s * s / (sigma * sigma) <= 100.0 + 1e-9
                            || (zmax - s) * (zmax - s) / (sigma * sigma) <= 100.0 + 1e-9
                    );
                }
            }
        }
        assert!(interior > 5_000, "{interior}");
    }
}
