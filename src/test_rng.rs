//! A seeded generator for the crate's unit tests (xorshift64, Marsaglia's 13/7/17 triple):
//! reproducible and dependency-free, not for statistics. Compiled for tests only.

/// xorshift64 state; the seed must not be zero.
pub(crate) struct XorShift64(pub(crate) u64);

impl XorShift64 {
    /// The next 64 bits.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// Uniform in `[0, 1)`, 53 random bits.
    pub(crate) fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}
