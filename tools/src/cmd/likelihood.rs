//! The likelihood field's options, shared by `score`, `calibrate`, `track` and
//! `field score-variants` (flattened into each with `#[command(flatten)]`).

use beamfield::field::{LikelihoodError, LikelihoodParams};
use clap::Args;

/// The likelihood field's mixture: σ_hit and the z_hit, z_rand weights.
#[derive(Args, Debug, Clone, Copy)]
pub struct LikelihoodArgs {
    /// σ_hit of the likelihood field, metres.
    #[arg(long = "sigma-hit", default_value_t = 0.05)]
    pub sigma_hit: f32,
    /// z_hit weight.
    #[arg(long = "z-hit", default_value_t = 0.95)]
    pub z_hit: f32,
    /// z_rand weight.
    #[arg(long = "z-rand", default_value_t = 0.05)]
    pub z_rand: f32,
}

impl LikelihoodArgs {
    /// The parameters for a sensor whose max-range value is `max_range_m`.
    ///
    /// # Errors
    /// The [`LikelihoodError`] of [`LikelihoodParams::new`].
    pub fn params(&self, max_range_m: f32) -> Result<LikelihoodParams, LikelihoodError> {
        LikelihoodParams::new(self.z_hit, self.z_rand, self.sigma_hit, max_range_m)
    }
}
