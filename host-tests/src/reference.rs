//! An f64 reference of the beam mixture and the textbook EM step, written from Thrun Tables 6.1–6.2
//! (docs/models.md).
//!
//! Deliberately independent of the crate: its own erfc (a Taylor series near 0, a continued
//! fraction in the tails, both accurate to ~1e-14), std's f64 `exp`/`ln`, no shared code.

use std::f64::consts::PI;

/// The seven intrinsic parameters, f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Intrinsics {
    /// Weight of the hit component.
    pub z_hit: f64,
    /// Weight of the short component.
    pub z_short: f64,
    /// Weight of the max-range point mass.
    pub z_max: f64,
    /// Weight of the uniform component.
    pub z_rand: f64,
    /// Hit standard deviation, m.
    pub sigma_hit: f64,
    /// Short-reading rate, 1/m.
    pub lambda_short: f64,
    /// Sensor range limit, m.
    pub max_range: f64,
}

impl Intrinsics {
    /// The weights as an array.
    pub fn weights(&self) -> [f64; 4] {
        [self.z_hit, self.z_short, self.z_max, self.z_rand]
    }
}

/// erf(x) by its Maclaurin series; used for |x| < 2.5.
fn erf_series(x: f64) -> f64 {
    let mut term = x;
    let mut sum = x;
    let x2 = x * x;
    let mut n = 0.0;
    loop {
        n += 1.0;
        term *= -x2 / n;
        let add = term / (2.0 * n + 1.0);
        sum += add;
        if add.abs() <= 1e-17 * sum.abs() || n > 200.0 {
            break;
        }
    }
    2.0 / PI.sqrt() * sum
}

/// erfc(x) for x ≥ 2.5 by its continued fraction (modified Lentz).
fn erfc_cf(x: f64) -> f64 {
    // erfc(x) = exp(-x²)/√π · 1/(x + 1/2/(x + 1/(x + 3/2/(x + 2/(x + ...)))))
    let tiny = 1e-300;
    let mut f = x;
    let mut c = x;
    let mut d = 0.0;
    for k in 1..500 {
        let a = k as f64 / 2.0;
        d = x + a * d;
        if d.abs() < tiny {
            d = tiny;
        }
        c = x + a / c;
        if c.abs() < tiny {
            c = tiny;
        }
        d = 1.0 / d;
        let delta = c * d;
        f *= delta;
        if (delta - 1.0).abs() < 1e-16 {
            break;
        }
    }
    (-x * x).exp() / PI.sqrt() / f
}

/// Complementary error function, f64, independent of libm.
pub fn erfc(x: f64) -> f64 {
    if x < -2.5 {
        2.0 - erfc_cf(-x)
    } else if x < 2.5 {
        1.0 - erf_series(x)
    } else {
        erfc_cf(x)
    }
}

/// Standard normal CDF Φ(u) = ½·erfc(−u/√2).
pub fn phi(u: f64) -> f64 {
    0.5 * erfc(-u / std::f64::consts::SQRT_2)
}

/// Classification of a reading, as docs/models.md#mixture and the crate's policy define it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// NaN or negative.
    Invalid,
    /// ≥ max range or +∞, evaluated at z = max range.
    Max,
    /// An ordinary range.
    Range(f64),
}

/// Classifies reading `z` against `max_range`.
pub fn classify(z: f64, max_range: f64) -> Kind {
    if z.is_nan() || z < 0.0 {
        Kind::Invalid
    } else if z >= max_range {
        Kind::Max
    } else {
        Kind::Range(z)
    }
}

/// The unweighted components `[p_hit, p_short, p_max, p_rand]` of reading `z` given `z_star`.
/// `None` for an invalid reading.
pub fn components(p: &Intrinsics, z: f64, z_star: f64) -> Option<[f64; 4]> {
    let zmax = p.max_range;
    let zs = if z_star.is_nan() {
        zmax
    } else {
        z_star.clamp(0.0, zmax)
    };
    let (z, is_max) = match classify(z, zmax) {
        Kind::Invalid => return None,
        Kind::Max => (zmax, true),
        Kind::Range(z) => (z, false),
    };
    let s = p.sigma_hit;
    let eta_hit = 1.0 / (phi((zmax - zs) / s) - phi((0.0 - zs) / s));
    let gauss = (-0.5 * ((z - zs) / s).powi(2)).exp() / (s * (2.0 * PI).sqrt());
    let p_hit = if (0.0..=zmax).contains(&z) {
        eta_hit * gauss
    } else {
        0.0
    };
    let l = p.lambda_short;
    let p_short = if zs > 0.0 && z <= zs {
        (1.0 / (1.0 - (-l * zs).exp())) * l * (-l * z).exp()
    } else {
        0.0
    };
    let p_max = if is_max { 1.0 } else { 0.0 };
    let p_rand = if is_max { 0.0 } else { 1.0 / zmax };
    Some([p_hit, p_short, p_max, p_rand])
}

/// The component logarithms `[ln w·p_hit, …]`, exact even where the densities underflow.
pub fn log_weighted_components(p: &Intrinsics, z: f64, z_star: f64) -> Option<[f64; 4]> {
    let zmax = p.max_range;
    let zs = if z_star.is_nan() {
        zmax
    } else {
        z_star.clamp(0.0, zmax)
    };
    let (z, is_max) = match classify(z, zmax) {
        Kind::Invalid => return None,
        Kind::Max => (zmax, true),
        Kind::Range(z) => (z, false),
    };
    let s = p.sigma_hit;
    let mass = phi((zmax - zs) / s) - phi(-zs / s);
    let l_hit =
        p.z_hit.ln() - mass.ln() - (s * (2.0 * PI).sqrt()).ln() - 0.5 * ((z - zs) / s).powi(2);
    let lam = p.lambda_short;
    let l_short = if zs > 0.0 && z <= zs {
        p.z_short.ln() + lam.ln() - lam * z - (1.0 - (-lam * zs).exp()).ln()
    } else {
        f64::NEG_INFINITY
    };
    let l_max = if is_max {
        p.z_max.ln()
    } else {
        f64::NEG_INFINITY
    };
    let l_rand = if is_max {
        f64::NEG_INFINITY
    } else {
        p.z_rand.ln() - zmax.ln()
    };
    Some([l_hit, l_short, l_max, l_rand])
}

/// The crate's documented per-beam floor, nats.
pub const BEAM_LOG_FLOOR: f64 = -1.0e4;

/// ln p(z | z*), by log-sum-exp of the component logs, clamped at the documented floor.
pub fn beam_log_likelihood(p: &Intrinsics, z: f64, z_star: f64) -> Option<f64> {
    let l = log_weighted_components(p, z, z_star)?;
    let m = l.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let v = if m == f64::NEG_INFINITY {
        m
    } else {
        m + l.iter().map(|&x| (x - m).exp()).sum::<f64>().ln()
    };
    Some(v.max(BEAM_LOG_FLOOR))
}

/// Sum of ln p over the valid readings (invalid ones skipped).
pub fn scan_log_likelihood(p: &Intrinsics, z: &[f64], z_star: &[f64]) -> f64 {
    z.iter()
        .zip(z_star)
        .filter_map(|(&a, &b)| beam_log_likelihood(p, a, b))
        .sum()
}

/// One textbook EM step (Table 6.2, docs/models.md#em). Returns the new parameters and the mean
/// log-likelihood per reading *before* the step.
pub fn em_step_textbook(p: &Intrinsics, z: &[f64], z_star: &[f64]) -> (Intrinsics, f64) {
    let w = p.weights();
    let (mut e_sum, mut sq_hit, mut z_short, mut ll) = ([0.0f64; 4], 0.0, 0.0, 0.0);
    let mut n = 0usize;
    for (&zi, &si) in z.iter().zip(z_star) {
        let Some(c) = components(p, zi, si) else {
            continue;
        };
        n += 1;
        let wc: Vec<f64> = (0..4).map(|k| w[k] * c[k]).collect();
        let total: f64 = wc.iter().sum();
        if total <= 0.0 {
            continue;
        }
        ll += total.ln();
        let zc = match classify(zi, p.max_range) {
            Kind::Max => p.max_range,
            _ => zi,
        };
        for k in 0..4 {
            e_sum[k] += wc[k] / total;
        }
        sq_hit += wc[0] / total * (zc - si).powi(2);
        z_short += wc[1] / total * zc;
    }
    let nf = n as f64;
    let next = Intrinsics {
        z_hit: e_sum[0] / nf,
        z_short: e_sum[1] / nf,
        z_max: e_sum[2] / nf,
        z_rand: e_sum[3] / nf,
        sigma_hit: if e_sum[0] > 0.0 {
            (sq_hit / e_sum[0]).sqrt()
        } else {
            p.sigma_hit
        },
        lambda_short: if z_short > 0.0 {
            e_sum[1] / z_short
        } else {
            p.lambda_short
        },
        max_range: p.max_range,
    };
    (next, ll / nf)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erfc_known_values() {
        // Values from the defining integral (Abramowitz & Stegun table 7.1 and standard tables).
        let cases = [
            (0.0, 1.0),
            (0.5, 0.479_500_122_186_953_5),
            (1.0, 0.157_299_207_050_285_1),
            (2.0, 4.677_734_981_047_266e-3),
            (3.0, 2.209_049_699_858_544e-5),
            (5.0, 1.537_459_794_428_035e-12),
            (-1.0, 1.842_700_792_949_715),
        ];
        for (x, want) in cases {
            let got = erfc(x);
            assert!(
                ((got - want) / want).abs() < 1e-12,
                "erfc({x}) = {got}, want {want}"
            );
        }
        // Continuity where the two methods meet.
        assert!((erfc(2.5 - 1e-12) - erfc(2.5)).abs() < 1e-13);
    }
}
