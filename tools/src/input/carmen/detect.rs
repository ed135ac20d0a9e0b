//! Detecting a log's max-range ("no return") value from its ranges.

use std::collections::HashMap;

/// A detected max-range value and the evidence for it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Detection {
    /// The value, metres.
    pub value_m: f32,
    /// Readings exactly equal to it.
    pub count: usize,
    /// The most repeated other value at or above half of it, and its count (the runner-up the
    /// dominance test compared against), if any.
    pub runner_up: Option<(f32, usize)>,
}

/// Smallest number of exact repeats for a detected max-range value.
pub const DETECT_MIN_REPEATS: usize = 3;
/// How many times more often the max-range value must occur than any other value at or above
/// half of it.
pub const DETECT_DOMINANCE: usize = 5;
/// The top band searched for the max-range value: readings at or above this quantile.
pub const DETECT_TOP_QUANTILE: f64 = 0.95;

/// Detects a log's max-range ("no return") value from its ranges.
///
/// A no-return sentinel is one exact number, written for every beam without an echo; real
/// returns are spread over many values (even at the log's 1 cm print resolution). The rule:
///
/// 1. Take the finite, non-negative readings; the top band is those at or above the
///    [`DETECT_TOP_QUANTILE`] (95 %) quantile.
/// 2. The candidate `v` is the most repeated exact value in the top band (ties: the larger).
/// 3. `v` is accepted when it occurs at least [`DETECT_MIN_REPEATS`] times and at least
///    [`DETECT_DOMINANCE`] (5) times as often as every other value `≥ v/2` (the runner-up).
///
/// Values above `v` (for example SICK error codes just above the sentinel) do not prevent
/// detection as long as `v` dominates them; the models treat them as max range too. A log with
/// no sentinel at all (every beam echoed) gives `None`: give the value instead.
///
/// On the Intel log: 81.83, 4,172 times; the runner-up in `[40.9, ∞)` does not exist (the largest
/// real return is 25.38 m).
pub fn detect_max_range(ranges_m: impl Iterator<Item = f32>) -> Option<Detection> {
    let mut values: Vec<f32> = ranges_m.filter(|r| r.is_finite() && *r >= 0.0).collect();
    if values.is_empty() {
        return None;
    }
    values.sort_by(f32::total_cmp);
    let q_index = ((values.len() - 1) as f64 * DETECT_TOP_QUANTILE).floor() as usize;
    let threshold = *values.get(q_index)?;
    let mut counts: HashMap<u32, usize> = HashMap::new();
    for v in &values {
        *counts.entry(v.to_bits()).or_insert(0) += 1;
    }
    let (candidate, count) = counts
        .iter()
        .map(|(&bits, &c)| (f32::from_bits(bits), c))
        .filter(|(v, _)| *v >= threshold)
        .max_by(|a, b| a.1.cmp(&b.1).then(a.0.total_cmp(&b.0)))?;
    let runner_up = counts
        .iter()
        .map(|(&bits, &c)| (f32::from_bits(bits), c))
        .filter(|(v, _)| *v >= 0.5 * candidate && *v != candidate)
        .max_by(|a, b| a.1.cmp(&b.1).then(a.0.total_cmp(&b.0)));
    let runner_count = runner_up.map_or(0, |r| r.1);
    if count >= DETECT_MIN_REPEATS && count >= DETECT_DOMINANCE.saturating_mul(runner_count) {
        Some(Detection {
            value_m: candidate,
            count,
            runner_up,
        })
    } else {
        None
    }
}
