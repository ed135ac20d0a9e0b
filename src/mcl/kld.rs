//! KLD sampling (Fox 2003; AMCL's `pf_err`, `pf_z`, `min_particles`, `max_particles`): the
//! number of particles in use adapts at each resampling, inside the fixed capacity.
//!
//! At a resampling the filter counts the histogram bins (x, y, heading; AMCL's 0.5 m, 0.5 m,
//! 10°) that the set about to be drawn occupies, `k`, and draws
//! `n = (k − 1)/(2ε) · (1 − 2/(9(k − 1)) + √(2/(9(k − 1)))·z)³` particles (the count that keeps
//! the Kullback–Leibler distance between the sample and the posterior below `ε` with
//! probability given by the normal quantile `z`), within `[min, max]` and the capacity. A
//! tracked cloud occupies a few bins and uses `min`; a cloud spread over the map uses up to
//! `max`. The bins are counted in fixed memory: a 4,096-bit hash set on the stack (512 bytes)
//! and linear counting (`k ≈ −B·ln(1 − ones/B)`, `B` = 4,096 bits), so that a set of any size
//! is counted in one pass with no allocation; above about 10,000 occupied bins the count
//! saturates, which only ever asks for `max`.

use crate::math;
use crate::pose::Pose;

/// The parameters of KLD sampling ([`MclConfig::with_kld`](super::MclConfig::with_kld)).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Kld {
    /// The fewest particles in use (AMCL `min_particles`), at least 1.
    pub min: u16,
    /// The most particles in use (AMCL `max_particles`); at most the capacity is used.
    pub max: u16,
    /// The bound on the Kullback–Leibler distance (AMCL `pf_err`), in `(0, 1)`.
    pub err: f32,
    /// The normal quantile of the bound's probability (AMCL `pf_z`, used as AMCL uses it),
    /// finite and non-negative.
    pub z: f32,
    /// The bins' side in x and y, metres.
    pub bin_m: f32,
    /// The bins' side in heading, radians.
    pub bin_rad: f32,
}

impl Kld {
    /// nav2's defaults: 500 to 2,000 particles, `pf_err` 0.05, `pf_z` 0.99, bins 0.5 m and
    /// 10°.
    pub const NAV2: Self = Self {
        min: 500,
        max: 2000,
        err: 0.05,
        z: 0.99,
        bin_m: 0.5,
        bin_rad: 10.0 * core::f32::consts::PI / 180.0,
    };

    /// True when every value is in range (see the fields).
    pub fn validate(&self) -> bool {
        self.min >= 1
            && self.min <= self.max
            && self.err > 0.0
            && self.err < 1.0
            && self.z.is_finite()
            && self.z >= 0.0
            && self.bin_m.is_finite()
            && self.bin_m > 0.0
            && self.bin_rad.is_finite()
            && self.bin_rad > 0.0
    }

    /// The KLD bound for `bins` occupied bins, within `[min, max]` and `capacity`.
    pub fn count(&self, bins: f32, capacity: usize) -> usize {
        let hi = usize::from(self.max).min(capacity).max(1);
        let lo = usize::from(self.min).min(hi);
        if bins.partial_cmp(&1.0) != Some(core::cmp::Ordering::Greater) {
            return lo;
        }
        let k1 = bins - 1.0;
        let a = 2.0 / (9.0 * k1);
        let c = 1.0 - a + math::sqrt(a) * self.z;
        let n = k1 / (2.0 * self.err) * c * c * c;
        if n.is_nan() {
            return hi;
        }
        // A float above `hi` saturates the cast; the clamp does the rest.
        (-math::floor(-n) as usize).clamp(lo, hi)
    }
}

impl Default for Kld {
    fn default() -> Self {
        Self::NAV2
    }
}

/// Bits of the hash set the bins are counted in.
pub const BIN_SET_BITS: usize = 4096;

/// Occupied bins, counted in a fixed hash set ([`BIN_SET_BITS`] bits) by linear counting.
pub(super) struct BinCount {
    bits: [u32; BIN_SET_BITS / 32],
    inv_bin_m: f32,
    inv_bin_rad: f32,
}

impl BinCount {
    pub(super) fn new(k: &Kld) -> Self {
        Self {
            bits: [0; BIN_SET_BITS / 32],
            inv_bin_m: 1.0 / k.bin_m,
            inv_bin_rad: 1.0 / k.bin_rad,
        }
    }

    /// Marks the bin of `p` (non-finite poses are skipped).
    pub(super) fn add(&mut self, p: &Pose) {
        if !p.is_finite() {
            return;
        }
        // Bin indices (floor, saturating casts), hashed together.
        let ix = math::floor(p.x_m * self.inv_bin_m) as i32;
        let iy = math::floor(p.y_m * self.inv_bin_m) as i32;
        let it = math::floor(p.theta_rad * self.inv_bin_rad) as i32;
        let mut h = (ix as u32).wrapping_mul(0x9E37_79B1);
        h ^= (iy as u32).wrapping_mul(0x85EB_CA77);
        h ^= (it as u32).wrapping_mul(0xC2B2_AE3D);
        h ^= h >> 15;
        h = h.wrapping_mul(0x2C1B_3C6D);
        h ^= h >> 12;
        let bit = (h as usize) % BIN_SET_BITS;
        if let Some(w) = self.bits.get_mut(bit / 32) {
            *w |= 1 << (bit % 32);
        }
    }

    /// The estimated number of distinct bins marked.
    pub(super) fn bins(&self) -> f32 {
        let ones: u32 = self.bits.iter().map(|w| w.count_ones()).sum();
        let b = BIN_SET_BITS as f32;
        if ones as usize >= BIN_SET_BITS {
            // Saturated: more bins than the set can tell; "very many".
            return b * 10.0;
        }
        -b * math::ln(1.0 - ones as f32 / b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bound_matches_the_formula_and_the_limits() {
        let k = Kld::NAV2;
        assert_eq!(k.count(1.0, 5000), 500);
        assert_eq!(k.count(0.0, 5000), 500);
        assert_eq!(k.count(f32::NAN, 5000), 500);
        // k = 101: 100/0.1 · (1 − 2/900 + √(2/900)·0.99)³, computed here in f64.
        let a = 2.0f64 / 900.0;
        let expect = (1000.0 * (1.0 - a + a.sqrt() * 0.99).powi(3)).ceil() as usize;
        assert_eq!(k.count(101.0, 5000), expect.clamp(500, 2000));
        assert_eq!(k.count(1e6, 5000), 2000);
        assert_eq!(k.count(1e6, 700), 700);
        assert_eq!(k.count(1.0, 300), 300);
        assert!(!Kld { min: 0, ..k }.validate());
        assert!(!Kld { min: 3000, ..k }.validate());
        assert!(!Kld { err: 0.0, ..k }.validate());
        assert!(!Kld {
            bin_m: f32::NAN,
            ..k
        }
        .validate());
        assert!(k.validate());
    }

    #[test]
    fn bins_are_counted() {
        let k = Kld::NAV2;
        let mut c = BinCount::new(&k);
        assert_eq!(c.bins(), 0.0);
        // 100 poses in one bin.
        for i in 0..100 {
            c.add(&Pose::new(0.1 + i as f32 * 0.001, 0.2, 0.01));
        }
        assert!((c.bins() - 1.0).abs() < 0.01, "{}", c.bins());
        // 400 distinct bins along x (1 m apart): linear counting within a few percent.
        let mut c = BinCount::new(&k);
        for i in 0..400 {
            c.add(&Pose::new(i as f32, 0.2, 0.01));
            c.add(&Pose::new(i as f32 + 0.01, 0.2, 0.01));
        }
        let b = c.bins();
        assert!((b - 400.0).abs() < 20.0, "{b}");
        c.add(&Pose::new(f32::NAN, 0.0, 0.0));
        assert_eq!(c.bins(), b);
    }
}
