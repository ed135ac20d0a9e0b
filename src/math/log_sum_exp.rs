//! Sums of probabilities kept as logarithms: `ln(e^a + e^b)` and `ln Σ e^{lᵢ}` of four terms,
//! the one family every model and the localizer use.
//!
//! Contract: `−∞` terms (probability 0) are allowed and contribute nothing; all `−∞` gives
//! `−∞`; the largest term is factored out, so no `exp` overflows and no term underflows before
//! it matters; `exp` and `ln` come from this module's parent (always libm). No panics.
//!
//! Not here: the n-term sums over a particle set (`mcl::filter`'s reweighting, `tempered`'s
//! normalization) fuse the sum with writing each weight `e^{lᵢ − max}` in one pass, which a
//! separate log-sum-exp would make two.

use super::{exp, ln};

/// `ln(e^a + e^b)`, either term may be `−∞`.
///
/// Computed as `hi + ln(1 + e^{lo − hi})` with `hi ≥ lo` the two terms: one `exp` and one `ln`.
/// When `lo` is `−∞` the result is `hi` itself (so `log_add_exp(−∞, −∞) = −∞`); a NaN term
/// gives NaN; `hi = +∞` gives `+∞` for any `lo` below it.
///
/// Accuracy: within one ulp of the result: 2.0e-6 absolute on `a, b ∈ [−40, 40]` (1.96e-6
/// measured, half an ulp of results near 40) against the f64 value of the same inputs
/// (host-tests `math_backend`).
#[inline]
pub fn log_add_exp(a: f32, b: f32) -> f32 {
    let (hi, lo) = if a >= b { (a, b) } else { (b, a) };
    if lo == f32::NEG_INFINITY {
        hi
    } else {
        hi + ln(1.0 + exp(lo - hi))
    }
}

/// `ln Σ e^{lᵢ}` of four log-terms, any of which may be `−∞`. All `−∞` gives `−∞`; a NaN term
/// gives NaN.
///
/// The maximum `m` is factored out (`m + ln Σ e^{lᵢ − m}`); `−∞` terms add 0 without an `exp`
/// call. The beam mixture's four components (`beam`).
///
/// Accuracy: within one ulp of the result: 2.0e-6 absolute on terms in `[−40, 40]` (any of
/// them possibly `−∞`; 2.0e-6 measured) against the f64 value of the same inputs (host-tests
/// `math_backend`).
pub fn log_sum_exp4(l: [f32; 4]) -> f32 {
    let m = l
        .iter()
        .fold(f32::NEG_INFINITY, |a, &b| if b > a { b } else { a });
    if m == f32::NEG_INFINITY {
        return m;
    }
    let s: f32 = l
        .iter()
        .map(|&x| {
            if x == f32::NEG_INFINITY {
                0.0
            } else {
                exp(x - m)
            }
        })
        .sum();
    m + ln(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    const NEG_INF: f32 = f32::NEG_INFINITY;

    #[test]
    fn special_values() {
        assert_eq!(log_add_exp(NEG_INF, NEG_INF), NEG_INF);
        assert_eq!(log_add_exp(NEG_INF, -3.0), -3.0);
        assert_eq!(log_add_exp(-3.0, NEG_INF), -3.0);
        assert_eq!(log_add_exp(f32::INFINITY, 1.0), f32::INFINITY);
        assert!(log_add_exp(f32::NAN, 1.0).is_nan());
        assert!(log_add_exp(1.0, f32::NAN).is_nan());
        assert_eq!(log_sum_exp4([NEG_INF; 4]), NEG_INF);
        assert_eq!(log_sum_exp4([NEG_INF, -2.0, NEG_INF, NEG_INF]), -2.0);
        assert!(log_sum_exp4([0.0, f32::NAN, 0.0, 0.0]).is_nan());
    }

    #[test]
    fn agree_where_both_apply() {
        // ln(e^0 + e^0) = ln 2 both ways.
        let ln2 = core::f32::consts::LN_2;
        assert!((log_add_exp(0.0, 0.0) - ln2).abs() <= 6e-8);
        assert!((log_sum_exp4([0.0, 0.0, NEG_INF, NEG_INF]) - ln2).abs() <= 6e-8);
        // Symmetric in its arguments, bit for bit.
        for (a, b) in [(-1.5f32, 2.25f32), (-30.0, -30.5), (7.0, -90.0)] {
            assert_eq!(log_add_exp(a, b).to_bits(), log_add_exp(b, a).to_bits());
        }
    }
}
