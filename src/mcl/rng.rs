//! SplitMix64 (Steele, Lea & Flood, "Fast splittable pseudorandom number generators", OOPSLA
//! 2014): a tiny seeded generator that the host and the device run identically, so a track
//! computed on a microcontroller can be recomputed bit for bit on a PC.
//!
//! Not cryptographic. Any seed (zero included) gives a full-period sequence of 2⁶⁴ words.

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
}
