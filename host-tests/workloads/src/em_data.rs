//! The EM bench's data set, shared by `benches/em.rs` and `examples/em_profile.rs`, so that the instruction counts are of exactly the bench's workload.

/// Readings in the data set.
pub const BEAMS: usize = 4_500;
/// M-steps per fit in the bench.
pub const ITERATIONS: u32 = 24;

use host_tests::splitmix::{Draws, SplitMix64 as Rng};

/// 4,500 readings from a lidar-like mixture (z_max 30 m, z* in [0.5, 30], σ = 0.15 m,
/// λ = 0.5/m, weights 0.75/0.1/0.05/0.1): `(z, z*)`, metres.
pub fn data() -> (Vec<f32>, Vec<f32>) {
    let mut rng = Rng::new(42);
    let zmax = 30.0f64;
    let (mut z, mut zs) = (Vec::new(), Vec::new());
    for _ in 0..BEAMS {
        let s = 0.5 + (zmax - 0.5) * rng.uniform();
        let u = rng.uniform();
        let r = if u < 0.75 {
            let g = (-2.0 * (1.0 - rng.uniform()).ln()).sqrt()
                * (2.0 * std::f64::consts::PI * rng.uniform()).cos();
            (s + 0.15 * g).clamp(0.0, zmax)
        } else if u < 0.85 {
            let m = 1.0 - (-0.5 * s).exp();
            -(1.0 - rng.uniform() * m).ln() / 0.5
        } else if u < 0.9 {
            zmax
        } else {
            rng.uniform() * zmax
        };
        z.push(r as f32);
        zs.push(s as f32);
    }
    (z, zs)
}
