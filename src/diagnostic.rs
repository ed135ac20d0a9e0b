//! The overconfidence diagnostic: lag-1 autocorrelation of per-beam residuals in bearing order
//! (docs/models.md#tempering).
//!
//! With a correct map the residuals of neighbouring beams are nearly independent and the lag-1
//! correlation is near 0; a map that is wrong (shifted, scaled, a wall moved) biases whole runs of
//! neighbouring beams the same way, and the correlation is clearly positive. It needs no ground
//! truth, so a robot can compute it on every scan, in the same pass as the score.
//!
//! [`Lag1`] is a streaming accumulator: push residuals in bearing order, read the correlation.
//! No storage, five running sums. Residuals are shifted by the first one pushed before they are
//! squared, which keeps f32 cancellation small when residuals share a large offset.

/// Streaming lag-1 autocorrelation `r₁ = Σ_t (x_t − x̄)(x_{t+1} − x̄) / Σ_t (x_t − x̄)²`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Lag1 {
    n: u32,
    shift: f32,
    first: f32,
    last: f32,
    sum: f32,
    sum_sq: f32,
    sum_lag: f32,
}

impl Lag1 {
    /// An empty accumulator.
    pub const fn new() -> Self {
        Self {
            n: 0,
            shift: 0.0,
            first: 0.0,
            last: 0.0,
            sum: 0.0,
            sum_sq: 0.0,
            sum_lag: 0.0,
        }
    }

    /// Adds the next residual in bearing order. Non-finite values are ignored (the caller
    /// skips max-range and invalid beams before this point; a gap simply joins its neighbours).
    #[inline]
    pub fn push(&mut self, residual: f32) {
        if !residual.is_finite() {
            return;
        }
        if self.n == 0 {
            self.shift = residual;
        }
        let x = residual - self.shift;
        if self.n == 0 {
            self.first = x;
        } else {
            self.sum_lag += self.last * x;
        }
        self.last = x;
        self.sum += x;
        self.sum_sq += x * x;
        self.n = self.n.saturating_add(1);
    }

    /// Number of residuals pushed.
    pub fn len(&self) -> u32 {
        self.n
    }

    /// True when nothing was pushed.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The lag-1 autocorrelation, in `[−1, 1]` up to rounding; `None` with fewer than 3
    /// residuals or when they are all equal (no variance).
    pub fn correlation(&self) -> Option<f32> {
        if self.n < 3 {
            return None;
        }
        let n = self.n as f32;
        let mean = self.sum / n;
        let var = self.sum_sq - n * mean * mean;
        if var <= f32::EPSILON * self.sum_sq.max(f32::MIN_POSITIVE) {
            return None;
        }
        // Σ_{t<n-1} (x_t − m)(x_{t+1} − m)
        //   = Σ x_t x_{t+1} − m·(Σx − last) − m·(Σx − first) + (n − 1)·m².
        let cov = self.sum_lag - mean * (self.sum - self.last) - mean * (self.sum - self.first)
            + (n - 1.0) * mean * mean;
        Some((cov / var).clamp(-1.0, 1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn direct(x: &[f64]) -> f64 {
        let n = x.len() as f64;
        let m = x.iter().sum::<f64>() / n;
        let var: f64 = x.iter().map(|v| (v - m) * (v - m)).sum();
        let cov: f64 = x.windows(2).map(|w| (w[0] - m) * (w[1] - m)).sum();
        cov / var
    }

    #[test]
    fn matches_two_pass_definition() {
        let mut s = 12345u32;
        let mut xs = [0f64; 200];
        let mut acc = Lag1::new();
        let mut prev = 0.0;
        for x in xs.iter_mut() {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            let u = (s as f64 / u32::MAX as f64) - 0.5;
            // AR(1) with coefficient 0.6 around an offset of 5.0
            prev = 0.6 * prev + u;
            *x = 5.0 + prev;
            acc.push(*x as f32);
        }
        let want = direct(&xs);
        let got = f64::from(acc.correlation().unwrap());
        assert!((got - want).abs() < 1e-4, "{got} vs {want}");
        assert!(want > 0.4);
    }

    #[test]
    fn degenerate_cases() {
        let mut a = Lag1::new();
        assert_eq!(a.correlation(), None);
        for _ in 0..10 {
            a.push(2.0);
        }
        assert_eq!(a.correlation(), None);
        let mut b = Lag1::new();
        for i in 0..10 {
            b.push(if i % 2 == 0 { 1.0 } else { -1.0 });
        }
        assert!(b.correlation().unwrap() < -0.8);
        b.push(f32::NAN);
        assert_eq!(b.len(), 10);
    }
}
