//! f64 draws from the library's generator [`SplitMix64`]: the wheel model's slip
//! ([`super::wheels`]) and the host tests' data sets (`host_tests::splitmix` re-exports this
//! trait), so that no second copy of the draws exists.
//!
//! The draws are host code (std's `ln`, `sqrt`, `cos`), exactly as the tests' data sets were
//! generated before they moved onto the library's generator: the streams and the data sets are
//! unchanged.

use beamfield::mcl::SplitMix64;

/// f64 draws from a [`SplitMix64`] stream.
pub trait Draws {
    /// The next 64 random bits ([`SplitMix64::next_word`]).
    fn next_u64(&mut self) -> u64;

    /// Uniform in `[0, 1)`, 53 random bits.
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[lo, hi)`.
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// Standard normal (Box–Muller, one of the pair, from `1 − U` so the logarithm's argument is
    /// never 0).
    fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }

    /// Standard normal (Box–Muller, one of the pair, from `max(U, 1e-300)`): the variant the
    /// corridor and sonar simulators were written with, kept so their data sets do not change.
    fn normal_clamped(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

impl Draws for SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.next_word()
    }
}
