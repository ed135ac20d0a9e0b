//! A safeguarded Newton maximizer of a concave function of one positive variable, driven from
//! outside: each evaluation is a pass over the data, so the solver proposes a point, the caller
//! evaluates `(Q, Q', Q'')` there and reports back.
//!
//! Safeguards: a bracket `[lo, hi]` known to contain the maximizer (shrunk by the sign of `Q'`
//! at every evaluated point); a Newton step that leaves the bracket, or is undefined (`Q'' ≥ 0`),
//! is replaced by a step of at most a factor [`MAX_FACTOR`] in the direction of ascent, or by the
//! geometric midpoint of the bracket. Candidates are rounded by the caller's `round` (to what the
//! result will be stored as), and the solver remembers the best evaluated point: only an
//! evaluated improvement is ever returned, so the result never has a lower `Q` than the start.

/// Largest factor between two consecutive candidates when Newton is not trusted.
const MAX_FACTOR: f64 = 4.0;

/// Relative Newton step below which the solver stops (the result is stored as f32, whose
/// relative spacing is 6e-8; 1e-9 is well below it).
const REL_STEP_TOL: f64 = 1e-9;

/// State of one 1-D maximization.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Solver {
    lo: f64,
    hi: f64,
    /// Last evaluated point and its derivatives.
    x: f64,
    g: f64,
    h: f64,
    best_x: f64,
    best_q: f64,
    done: bool,
}

impl Solver {
    /// Starts at `x0`, already evaluated as `curve`, inside the hard bounds `[lo, hi]`.
    pub fn new(x0: f64, curve: [f64; 3], lo: f64, hi: f64) -> Self {
        let mut s = Self {
            lo,
            hi,
            x: x0,
            g: 0.0,
            h: 0.0,
            best_x: x0,
            best_q: curve[0],
            done: false,
        };
        s.shrink(x0, curve);
        s
    }

    fn shrink(&mut self, x: f64, [_, g, h]: [f64; 3]) {
        self.x = x;
        self.g = g;
        self.h = h;
        if g > 0.0 {
            self.lo = self.lo.max(x);
        } else if g < 0.0 {
            self.hi = self.hi.min(x);
        } else {
            self.done = true;
        }
        if g.is_nan() || self.lo >= self.hi {
            self.done = true;
        }
    }

    /// Records the evaluation of the last proposed point.
    pub fn observe(&mut self, x: f64, curve: [f64; 3]) {
        if curve[0] > self.best_q {
            self.best_q = curve[0];
            self.best_x = x;
        }
        self.shrink(x, curve);
    }

    /// The next point to evaluate, already rounded; `None` when converged.
    pub fn propose(
        &mut self,
        round: impl Fn(f64) -> f64,
        lo_bound: f64,
        hi_bound: f64,
    ) -> Option<f64> {
        if self.done {
            return None;
        }
        let (x, g, h) = (self.x, self.g, self.h);
        let newton = if h < 0.0 { x - g / h } else { f64::NAN };
        let mut cand = if newton > self.lo && newton < self.hi {
            let step = newton - x;
            let step_abs = if step < 0.0 { -step } else { step };
            if step_abs <= REL_STEP_TOL * x {
                self.done = true;
                return None;
            }
            newton.clamp(x / MAX_FACTOR, x * MAX_FACTOR)
        } else if g > 0.0 {
            (x * MAX_FACTOR).min(self.geometric_mid_or(x * MAX_FACTOR))
        } else {
            (x / MAX_FACTOR).max(self.geometric_mid_or(x / MAX_FACTOR))
        };
        cand = round(cand.clamp(lo_bound, hi_bound));
        if cand == x || cand == self.best_x || !cand.is_finite() {
            self.done = true;
            return None;
        }
        Some(cand)
    }

    /// Midpoint of the bracket on a log scale, or `fallback` when the bracket is unbounded.
    fn geometric_mid_or(&self, fallback: f64) -> f64 {
        let m = crate::math::sqrt_f64(self.lo * self.hi);
        if m.is_finite() && m > 0.0 {
            m
        } else {
            fallback
        }
    }

    /// The best evaluated point.
    pub fn best(&self) -> f64 {
        self.best_x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `Q(x) = a·ln x − b·x`, concave, maximum at `a/b`: the solver reaches it from either side
    /// and far away, and never returns a point worse than its start.
    #[test]
    fn finds_the_maximum_of_a_concave_function() {
        let cases: [(f64, f64, f64); 4] = [
            (1.0, 2.0, 0.01),
            (1.0, 2.0, 40.0),
            (3.0, 0.5, 6.0),
            (5.0, 1e3, 1.0),
        ];
        for (a, b, x0) in cases {
            let curve = |x: f64| [a * x.ln() - b * x, a / x - b, -a / (x * x)];
            let mut s = Solver::new(x0, curve(x0), 1e-9, 1e9);
            for _ in 0..60 {
                match s.propose(|x| x, 1e-9, 1e9) {
                    Some(x) => s.observe(x, curve(x)),
                    None => break,
                }
            }
            let want = a / b;
            assert!(
                (s.best() - want).abs() < 1e-8 * want,
                "{a} {b} {x0}: {}",
                s.best()
            );
            assert!(curve(s.best())[0] >= curve(x0)[0]);
        }
    }
}
