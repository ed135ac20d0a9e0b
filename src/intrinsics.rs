//! The six intrinsic parameters of the beam model (Thrun Table 6.1) plus the sensor's range
//! limit, validated once at construction.
//!
//! | field | meaning | unit | AMCL parameter |
//! |---|---|---|---|
//! | `z_hit` | weight of the correct-return Gaussian | – | `laser_z_hit` |
//! | `z_short` | weight of the unexpected-obstacle exponential | – | `laser_z_short` |
//! | `z_max` | weight of the max-range point mass | – | `laser_z_max` |
//! | `z_rand` | weight of the uniform random reading | – | `laser_z_rand` |
//! | `sigma_hit_m` | standard deviation of the hit Gaussian | m | `laser_sigma_hit` |
//! | `lambda_short_per_m` | rate of the short-reading exponential | 1/m | `laser_lambda_short` |
//! | `max_range_m` | the sensor's maximum range `z_max` | m | `laser_max_range` |
//!
//! The four weights must be ≥ 0 and sum to 1 within [`WEIGHT_SUM_TOLERANCE`].

/// How far the four weights may sum from 1 and still be accepted (absolute).
///
/// Loose enough for weights typed with four decimals or produced by an f32 EM, tight enough
/// that a transposed or missing weight is caught.
pub const WEIGHT_SUM_TOLERANCE: f32 = 1e-4;

/// Which intrinsic parameter an error is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Param {
    /// `z_hit`.
    ZHit,
    /// `z_short`.
    ZShort,
    /// `z_max`.
    ZMax,
    /// `z_rand`.
    ZRand,
    /// `sigma_hit_m`.
    SigmaHit,
    /// `lambda_short_per_m`.
    LambdaShort,
    /// `max_range_m`.
    MaxRange,
}

impl Param {
    /// The parameter's name as AMCL spells it.
    pub const fn amcl_name(self) -> &'static str {
        match self {
            Self::ZHit => "laser_z_hit",
            Self::ZShort => "laser_z_short",
            Self::ZMax => "laser_z_max",
            Self::ZRand => "laser_z_rand",
            Self::SigmaHit => "laser_sigma_hit",
            Self::LambdaShort => "laser_lambda_short",
            Self::MaxRange => "laser_max_range",
        }
    }
}

/// Why a set of intrinsics was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum IntrinsicsError {
    /// A parameter is NaN or infinite.
    NonFinite(Param),
    /// A mixture weight is negative.
    NegativeWeight(Param),
    /// The four weights do not sum to 1 within [`WEIGHT_SUM_TOLERANCE`].
    WeightsDoNotSumToOne,
    /// `sigma_hit_m ≤ 0`.
    NonPositiveSigma,
    /// `lambda_short_per_m ≤ 0`.
    NonPositiveLambda,
    /// `max_range_m ≤ 0`.
    NonPositiveMaxRange,
}

impl core::fmt::Display for IntrinsicsError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NonFinite(p) => write!(f, "{} is not finite", p.amcl_name()),
            Self::NegativeWeight(p) => write!(f, "{} is negative", p.amcl_name()),
            Self::WeightsDoNotSumToOne => f.write_str("mixture weights do not sum to 1"),
            Self::NonPositiveSigma => f.write_str("laser_sigma_hit must be > 0"),
            Self::NonPositiveLambda => f.write_str("laser_lambda_short must be > 0"),
            Self::NonPositiveMaxRange => f.write_str("laser_max_range must be > 0"),
        }
    }
}

impl core::error::Error for IntrinsicsError {}

/// Θ: the beam model's validated intrinsic parameters. See the module docs for units and the
/// AMCL names. Fields are read through accessors; construct with [`BeamIntrinsics::new`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BeamIntrinsics {
    z_hit: f32,
    z_short: f32,
    z_max: f32,
    z_rand: f32,
    sigma_hit_m: f32,
    lambda_short_per_m: f32,
    max_range_m: f32,
}

impl BeamIntrinsics {
    /// AMCL's defaults (`laser_z_hit` 0.95, `laser_z_short` 0.1, `laser_z_max` 0.05,
    /// `laser_z_rand` 0.05, `laser_sigma_hit` 0.2, `laser_lambda_short` 0.1) renormalized to the
    /// simplex (AMCL does not require the weights to sum to 1; this crate does), for a sensor of
    /// the given range.
    ///
    /// # Errors
    /// [`IntrinsicsError::NonPositiveMaxRange`] or [`IntrinsicsError::NonFinite`] for a bad range.
    pub fn amcl_defaults(max_range_m: f32) -> Result<Self, IntrinsicsError> {
        let s = 0.95 + 0.1 + 0.05 + 0.05;
        Self::new(0.95 / s, 0.1 / s, 0.05 / s, 0.05 / s, 0.2, 0.1, max_range_m)
    }

    /// Validates and builds a parameter set.
    ///
    /// # Errors
    /// One distinct [`IntrinsicsError`] per defect, checked in this order: non-finite values,
    /// negative weights, weights not summing to 1, σ ≤ 0, λ ≤ 0, max range ≤ 0.
    pub fn new(
        z_hit: f32,
        z_short: f32,
        z_max: f32,
        z_rand: f32,
        sigma_hit_m: f32,
        lambda_short_per_m: f32,
        max_range_m: f32,
    ) -> Result<Self, IntrinsicsError> {
        let all = [
            (z_hit, Param::ZHit),
            (z_short, Param::ZShort),
            (z_max, Param::ZMax),
            (z_rand, Param::ZRand),
            (sigma_hit_m, Param::SigmaHit),
            (lambda_short_per_m, Param::LambdaShort),
            (max_range_m, Param::MaxRange),
        ];
        for (v, p) in all {
            if !v.is_finite() {
                return Err(IntrinsicsError::NonFinite(p));
            }
        }
        for (v, p) in all.iter().take(4) {
            if *v < 0.0 {
                return Err(IntrinsicsError::NegativeWeight(*p));
            }
        }
        let sum = z_hit + z_short + z_max + z_rand;
        if (sum - 1.0).abs() > WEIGHT_SUM_TOLERANCE {
            return Err(IntrinsicsError::WeightsDoNotSumToOne);
        }
        if sigma_hit_m <= 0.0 {
            return Err(IntrinsicsError::NonPositiveSigma);
        }
        if lambda_short_per_m <= 0.0 {
            return Err(IntrinsicsError::NonPositiveLambda);
        }
        if max_range_m <= 0.0 {
            return Err(IntrinsicsError::NonPositiveMaxRange);
        }
        Ok(Self {
            z_hit,
            z_short,
            z_max,
            z_rand,
            sigma_hit_m,
            lambda_short_per_m,
            max_range_m,
        })
    }

    /// `z_hit` (`laser_z_hit`).
    pub fn z_hit(&self) -> f32 {
        self.z_hit
    }
    /// `z_short` (`laser_z_short`).
    pub fn z_short(&self) -> f32 {
        self.z_short
    }
    /// `z_max` (`laser_z_max`).
    pub fn z_max(&self) -> f32 {
        self.z_max
    }
    /// `z_rand` (`laser_z_rand`).
    pub fn z_rand(&self) -> f32 {
        self.z_rand
    }
    /// σ_hit, metres (`laser_sigma_hit`).
    pub fn sigma_hit_m(&self) -> f32 {
        self.sigma_hit_m
    }
    /// λ_short, per metre (`laser_lambda_short`).
    pub fn lambda_short_per_m(&self) -> f32 {
        self.lambda_short_per_m
    }
    /// The sensor's maximum range, metres (`laser_max_range`).
    pub fn max_range_m(&self) -> f32 {
        self.max_range_m
    }
    /// The four weights `[z_hit, z_short, z_max, z_rand]`.
    pub fn weights(&self) -> [f32; 4] {
        [self.z_hit, self.z_short, self.z_max, self.z_rand]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_defect_has_its_own_error() {
        let ok = BeamIntrinsics::new(0.25, 0.25, 0.25, 0.25, 1.0, 0.5, 10.0);
        assert!(ok.is_ok());
        let cases = [
            (
                BeamIntrinsics::new(f32::NAN, 0.25, 0.25, 0.25, 1.0, 0.5, 10.0),
                IntrinsicsError::NonFinite(Param::ZHit),
            ),
            (
                BeamIntrinsics::new(0.25, 0.25, 0.25, 0.25, 1.0, 0.5, f32::INFINITY),
                IntrinsicsError::NonFinite(Param::MaxRange),
            ),
            (
                BeamIntrinsics::new(0.5, -0.25, 0.5, 0.25, 1.0, 0.5, 10.0),
                IntrinsicsError::NegativeWeight(Param::ZShort),
            ),
            (
                BeamIntrinsics::new(0.25, 0.25, 0.25, 0.2, 1.0, 0.5, 10.0),
                IntrinsicsError::WeightsDoNotSumToOne,
            ),
            (
                BeamIntrinsics::new(0.25, 0.25, 0.25, 0.25, 0.0, 0.5, 10.0),
                IntrinsicsError::NonPositiveSigma,
            ),
            (
                BeamIntrinsics::new(0.25, 0.25, 0.25, 0.25, 1.0, -1.0, 10.0),
                IntrinsicsError::NonPositiveLambda,
            ),
            (
                BeamIntrinsics::new(0.25, 0.25, 0.25, 0.25, 1.0, 0.5, 0.0),
                IntrinsicsError::NonPositiveMaxRange,
            ),
        ];
        for (got, want) in cases {
            assert_eq!(got, Err(want));
        }
    }

    #[test]
    fn amcl_defaults_are_on_the_simplex() {
        let d = BeamIntrinsics::amcl_defaults(30.0).unwrap();
        let s: f32 = d.weights().iter().sum();
        assert!((s - 1.0).abs() < 1e-6);
    }
}
