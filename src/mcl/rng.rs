//! The crate's seeded generators, run identically on the host and the device.
//!
//! - [`SplitMix64`] (Steele, Lea & Flood, "Fast splittable pseudorandom number generators",
//!   OOPSLA 2014): the localizer's generator (a `rand_core` RNG), so a track computed on a
//!   microcontroller can be recomputed bit for bit on a PC. Any seed (zero included) gives a
//!   full-period sequence of 2⁶⁴ words.
//! - [`XorShift64`] (Marsaglia, "Xorshift RNGs", 2003, the 13/7/17 triple): the randomized
//!   checks' generator (the crate's unit tests and the host tests pick poses and cells with it).
//!   Not used by any model or the localizer.
//!
//! Contract: integer arithmetic only, no allocation, no panics; a given seed gives the same
//! stream on every target and in every build. Neither is cryptographic or meant for statistics
//! beyond reproducible sampling.

use core::convert::Infallible;

/// SplitMix64 state. `next_u64` adds `0x9E37_79B9_7F4A_7C15` to the state and returns it
/// mixed (`z ^= z >> 30; z *= 0xBF58_476D_1CE4_E5B9; z ^= z >> 27; z *= 0x94D0_49BB_1331_11EB;
/// z ^= z >> 31`); `next_u32` is the top 32 bits of `next_u64`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator seeded with `seed`.
    pub const fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// The next 64 bits.
    pub fn next_word(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

impl rand_core::TryRng for SplitMix64 {
    type Error = Infallible;

    fn try_next_u32(&mut self) -> Result<u32, Infallible> {
        Ok((self.next_word() >> 32) as u32)
    }

    fn try_next_u64(&mut self) -> Result<u64, Infallible> {
        Ok(self.next_word())
    }

    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Infallible> {
        for chunk in dst.chunks_mut(8) {
            let w = self.next_word().to_le_bytes();
            for (d, s) in chunk.iter_mut().zip(w) {
                *d = s;
            }
        }
        Ok(())
    }
}

/// xorshift64 state (Marsaglia's 13/7/17 triple: `x ^= x << 13; x ^= x >> 7; x ^= x << 17`,
/// the new state being the output).
///
/// The seed must not be zero: a zero state stays zero (every word 0, every [`uniform`] 0.0).
/// Any other seed gives a sequence of period 2⁶⁴ − 1.
///
/// [`uniform`]: XorShift64::uniform
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct XorShift64 {
    state: u64,
}

impl XorShift64 {
    /// A generator seeded with `seed` (not zero: see the type's docs).
    pub const fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// The next 64 bits (the new state).
    pub fn next_word(&mut self) -> u64 {
        self.state ^= self.state << 13;
        self.state ^= self.state >> 7;
        self.state ^= self.state << 17;
        self.state
    }

    /// Uniform in `[0, 1)`: the top 53 bits of [`XorShift64::next_word`] times 2⁻⁵³ (exact).
    pub fn uniform(&mut self) -> f64 {
        (self.next_word() >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_sequence() {
        // The first outputs for seed 1234567, from the reference C implementation
        // (splitmix64.c by Sebastiano Vigna, public domain), as published with it.
        let mut g = SplitMix64::new(1_234_567);
        assert_eq!(g.next_word(), 6_457_827_717_110_365_317);
        assert_eq!(g.next_word(), 3_203_168_211_198_807_973);
        assert_eq!(g.next_word(), 9_817_491_932_198_370_423);
    }

    #[test]
    fn xorshift64_first_words() {
        // x₁ for seed 1, by hand: 1 ^ 1<<13 = 0x2001; ^ >>7 (0x40) = 0x2041;
        // ^ <<17 = 0x2041 ^ 0x4082_0000 = 0x4082_2041.
        let mut g = XorShift64::new(1);
        assert_eq!(g.next_word(), 0x4082_2041);
        let want = (0x4082_2041u64 >> 11) as f64 / 9_007_199_254_740_992.0;
        assert_eq!(XorShift64::new(1).uniform(), want);
        assert_eq!(XorShift64::new(0).next_word(), 0);
    }
}
