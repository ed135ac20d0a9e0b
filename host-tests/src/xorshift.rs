//! A tiny seeded generator for picking test poses and cells (xorshift64, Marsaglia's 13/7/17
//! triple): reproducible, dependency-free, not for statistics.

/// xorshift64 state; the seed must not be zero.
pub struct XorShift64(pub u64);

impl XorShift64 {
    /// The next value, uniform in `[0, 1)` with 53 random bits.
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}
