//! The landmark model with known correspondence: Thrun Table 6.4 in log space, its inverse
//! (Table 6.5, [`sample_pose`]) and the two-feature proposal ([`two_feature_poses`]).
//!
//! A feature `f = (r, φ, s)` is a detection at range `r` (metres) and bearing `φ` (radians,
//! counter-clockwise from the robot's heading), with a scalar signature `s` (unitless: a colour,
//! a fiducial id, a reflector width class). A [`Landmark`] `(m_x, m_y, s_j)` is the map's point
//! (metres, map frame) and signature. For a robot pose `x = (x, y, θ)`:
//!
//! ```text
//! r̂ = √((m_x − x)² + (m_y − y)²)
//! φ̂ = atan2(m_y − y, m_x − x) − θ
//! log q = log N(r − r̂; 0, σ_r²) + log N(wrap(φ − φ̂); 0, σ_φ²) + log N(s − s_j; 0, σ_s²)
//! ```
//!
//! The bearing residual is wrapped into `[−π, π)` ([`wrap_angle`]) before it is squared: a
//! feature at 179° and a prediction at −179° are 2° apart, not 358°.
//!
//! # Frames
//! Range and bearing are measured from the robot's origin and heading, as in Thrun's table. A
//! front end whose sensor is mounted off-centre (a camera on a mast) converts its detections
//! into this frame first.
//!
//! # Features without a signature
//! Give every feature and landmark the same signature (for instance 0): the signature term is
//! then the constant `−ln(√(2π)·σ_s)`, which shifts every hypothesis equally.
//!
//! # Numerics
//! Residuals are divided by their σ (not multiplied by a stored `1/σ²`), so any positive finite σ
//! works: a huge residual over a tiny σ gives `−∞`, never NaN. With finite inputs the result is
//! never NaN; a non-finite [`Pose`] (its fields are public) propagates NaN. At the exact
//! landmark position the bearing is undefined and `atan2(0, 0) = 0` is used. With the
//! `micromath` backend, `atan2` is off by up to 4e-3 rad, which matters against a σ_φ of a few
//! hundredths of a radian; the default libm backend is within 2.4e-7 rad.

mod sample;
mod two_feature;

pub use sample::{sample_pose, MAX_RANGE_REDRAWS};
pub use two_feature::{
    sample_two_feature_poses, two_feature_poses, IntersectionError, PoseCandidate, TwoFeaturePoses,
    CONCENTRIC_RELATIVE_TOLERANCE,
};

use crate::math;
use crate::pose::{wrap_angle, Pose};

/// Which of the three noise parameters an error is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum NoiseParam {
    /// `sigma_range_m`.
    Range,
    /// `sigma_bearing_rad`.
    Bearing,
    /// `sigma_signature`.
    Signature,
}

impl NoiseParam {
    /// The parameter's field name.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Range => "sigma_range_m",
            Self::Bearing => "sigma_bearing_rad",
            Self::Signature => "sigma_signature",
        }
    }
}

/// Why a feature, a landmark or a noise model was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum LandmarkError {
    /// A feature's range is NaN or infinite.
    NonFiniteRange,
    /// A feature's range is negative.
    NegativeRange,
    /// A feature's bearing is NaN or infinite.
    NonFiniteBearing,
    /// A signature (of a feature or a landmark) is NaN or infinite.
    NonFiniteSignature,
    /// A landmark coordinate is NaN or infinite.
    NonFinitePosition,
    /// A noise standard deviation is NaN or infinite.
    NonFiniteSigma(NoiseParam),
    /// A noise standard deviation is zero or negative.
    NonPositiveSigma(NoiseParam),
}

impl core::fmt::Display for LandmarkError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NonFiniteRange => f.write_str("feature range is not finite"),
            Self::NegativeRange => f.write_str("feature range is negative"),
            Self::NonFiniteBearing => f.write_str("feature bearing is not finite"),
            Self::NonFiniteSignature => f.write_str("signature is not finite"),
            Self::NonFinitePosition => f.write_str("landmark position is not finite"),
            Self::NonFiniteSigma(p) => write!(f, "{} is not finite", p.name()),
            Self::NonPositiveSigma(p) => write!(f, "{} must be > 0", p.name()),
        }
    }
}

impl core::error::Error for LandmarkError {}

/// A detected feature `(r, φ, s)`, validated: range finite and ≥ 0 (metres), bearing finite
/// (radians, counter-clockwise from the robot heading, any value: it is wrapped where it is
/// compared), signature finite.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Feature {
    range_m: f32,
    bearing_rad: f32,
    signature: f32,
}

impl Feature {
    /// Validates and builds a feature.
    ///
    /// # Errors
    /// [`LandmarkError::NonFiniteRange`], [`LandmarkError::NegativeRange`],
    /// [`LandmarkError::NonFiniteBearing`] or [`LandmarkError::NonFiniteSignature`], checked in
    /// that order.
    pub fn new(range_m: f32, bearing_rad: f32, signature: f32) -> Result<Self, LandmarkError> {
        if !range_m.is_finite() {
            return Err(LandmarkError::NonFiniteRange);
        }
        if range_m < 0.0 {
            return Err(LandmarkError::NegativeRange);
        }
        if !bearing_rad.is_finite() {
            return Err(LandmarkError::NonFiniteBearing);
        }
        if !signature.is_finite() {
            return Err(LandmarkError::NonFiniteSignature);
        }
        Ok(Self {
            range_m,
            bearing_rad,
            signature,
        })
    }

    /// Range to the landmark, metres (finite, ≥ 0).
    pub const fn range_m(&self) -> f32 {
        self.range_m
    }

    /// Bearing of the landmark, radians counter-clockwise from the robot heading (finite, as
    /// given: not wrapped).
    pub const fn bearing_rad(&self) -> f32 {
        self.bearing_rad
    }

    /// Signature (finite, unitless).
    pub const fn signature(&self) -> f32 {
        self.signature
    }
}

/// A map landmark `(m_x, m_y, s_j)`, validated: position finite (metres, map frame), signature
/// finite.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Landmark {
    x_m: f32,
    y_m: f32,
    signature: f32,
}

impl Landmark {
    /// Validates and builds a landmark.
    ///
    /// # Errors
    /// [`LandmarkError::NonFinitePosition`] or [`LandmarkError::NonFiniteSignature`].
    pub fn new(x_m: f32, y_m: f32, signature: f32) -> Result<Self, LandmarkError> {
        if !(x_m.is_finite() && y_m.is_finite()) {
            return Err(LandmarkError::NonFinitePosition);
        }
        if !signature.is_finite() {
            return Err(LandmarkError::NonFiniteSignature);
        }
        Ok(Self {
            x_m,
            y_m,
            signature,
        })
    }

    /// x in the map frame, metres.
    pub const fn x_m(&self) -> f32 {
        self.x_m
    }

    /// y in the map frame, metres.
    pub const fn y_m(&self) -> f32 {
        self.y_m
    }

    /// Signature (finite, unitless).
    pub const fn signature(&self) -> f32 {
        self.signature
    }
}

/// The feature noise `Q = diag(σ_r², σ_φ², σ_s²)` of Table 6.4, validated: every σ finite and
/// > 0. Also holds the log normalizer `−(3·ln√(2π) + ln σ_r + ln σ_φ + ln σ_s)`, computed once.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FeatureNoise {
    sigma_range_m: f32,
    sigma_bearing_rad: f32,
    sigma_signature: f32,
    log_normalizer: f32,
}

impl FeatureNoise {
    /// Validates and builds a noise model: range σ in metres, bearing σ in radians, signature σ
    /// in signature units.
    ///
    /// # Errors
    /// [`LandmarkError::NonFiniteSigma`] or [`LandmarkError::NonPositiveSigma`] naming the first
    /// bad parameter (range, bearing, signature order).
    pub fn new(
        sigma_range_m: f32,
        sigma_bearing_rad: f32,
        sigma_signature: f32,
    ) -> Result<Self, LandmarkError> {
        for (sigma, p) in [
            (sigma_range_m, NoiseParam::Range),
            (sigma_bearing_rad, NoiseParam::Bearing),
            (sigma_signature, NoiseParam::Signature),
        ] {
            if !sigma.is_finite() {
                return Err(LandmarkError::NonFiniteSigma(p));
            }
            if sigma <= 0.0 {
                return Err(LandmarkError::NonPositiveSigma(p));
            }
        }
        // Summing the logs (not taking the log of the product) cannot underflow or overflow.
        let log_normalizer = -(3.0 * math::LN_SQRT_2PI
            + math::ln(sigma_range_m)
            + math::ln(sigma_bearing_rad)
            + math::ln(sigma_signature));
        Ok(Self {
            sigma_range_m,
            sigma_bearing_rad,
            sigma_signature,
            log_normalizer,
        })
    }

    /// σ_r, metres.
    pub const fn sigma_range_m(&self) -> f32 {
        self.sigma_range_m
    }

    /// σ_φ, radians.
    pub const fn sigma_bearing_rad(&self) -> f32 {
        self.sigma_bearing_rad
    }

    /// σ_s, signature units.
    pub const fn sigma_signature(&self) -> f32 {
        self.sigma_signature
    }

    /// The log of the Gaussian normalizer, `−(3·ln√(2π) + ln σ_r + ln σ_φ + ln σ_s)`: the
    /// log-likelihood of a zero residual.
    pub const fn log_normalizer(&self) -> f32 {
        self.log_normalizer
    }

    /// The squared Mahalanobis distance of a residual, `(e_r/σ_r)² + (e_φ/σ_φ)² + (e_s/σ_s)²`
    /// (unitless, χ² with 3 degrees of freedom under the model): the quantity to gate a
    /// correspondence on.
    #[inline]
    pub fn mahalanobis_sq(&self, residual: &Residual) -> f32 {
        let r = residual.range_m / self.sigma_range_m;
        let b = residual.bearing_rad / self.sigma_bearing_rad;
        let s = residual.signature / self.sigma_signature;
        r * r + b * b + s * s
    }
}

/// Observed minus predicted, for one feature against one landmark at one pose.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Residual {
    /// `r − r̂`, metres.
    pub range_m: f32,
    /// `wrap(φ − φ̂)`, radians in `[−π, π)`.
    pub bearing_rad: f32,
    /// `s − s_j`, signature units.
    pub signature: f32,
}

/// The predicted range (metres) and bearing (radians, not wrapped) of `landmark` seen from
/// `pose`: `r̂` and `φ̂` of Table 6.4.
#[inline]
pub fn predict(landmark: &Landmark, pose: &Pose) -> (f32, f32) {
    let dx = landmark.x_m - pose.x_m;
    let dy = landmark.y_m - pose.y_m;
    let range_m = math::sqrt(dx * dx + dy * dy);
    let bearing_rad = math::atan2(dy, dx) - pose.theta_rad;
    (range_m, bearing_rad)
}

/// The residual of `feature` against `landmark` seen from `pose`, with the bearing wrapped into
/// `[−π, π)`.
#[inline]
pub fn residual(feature: &Feature, landmark: &Landmark, pose: &Pose) -> Residual {
    let (range_hat_m, bearing_hat_rad) = predict(landmark, pose);
    Residual {
        range_m: feature.range_m - range_hat_m,
        bearing_rad: wrap_angle(feature.bearing_rad - bearing_hat_rad),
        signature: feature.signature - landmark.signature,
    }
}

/// `ln p(f | c, x, m)`, Thrun Table 6.4 in log space: the sum of the three Gaussian
/// log-densities of the range, wrapped bearing and signature residuals, nats.
///
/// Equal to `noise.log_normalizer() − ½·noise.mahalanobis_sq(&residual(..))`. Finite for every
/// finite pose except when a residual over its σ overflows, where it is `−∞`. See the module docs.
#[inline]
pub fn log_likelihood(
    feature: &Feature,
    landmark: &Landmark,
    pose: &Pose,
    noise: &FeatureNoise,
) -> f32 {
    noise.log_normalizer - 0.5 * noise.mahalanobis_sq(&residual(feature, landmark, pose))
}

/// `p(f | c, x, m)` of Table 6.4: `exp` of [`log_likelihood`] (a density in
/// `1/(m·rad·signature unit)`).
///
/// Underflow: below a log-likelihood of −87.3 the f32 result is subnormal (precision lost), and
/// below −103.97 it is exactly 0. Overflow: it is `+∞` only when the log normalizer exceeds 88.7,
/// that is when `σ_r·σ_φ·σ_s < 2.2e-40`. Combine features and hypotheses with
/// [`log_likelihood`] and log-sum-exp, not with products of this.
#[inline]
pub fn likelihood(
    feature: &Feature,
    landmark: &Landmark,
    pose: &Pose,
    noise: &FeatureNoise,
) -> f32 {
    math::exp(log_likelihood(feature, landmark, pose, noise))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_table() {
        use LandmarkError as E;
        assert_eq!(Feature::new(f32::NAN, 0.0, 0.0), Err(E::NonFiniteRange));
        assert_eq!(
            Feature::new(f32::INFINITY, 0.0, 0.0),
            Err(E::NonFiniteRange)
        );
        assert_eq!(Feature::new(-1e-6, 0.0, 0.0), Err(E::NegativeRange));
        assert_eq!(Feature::new(1.0, f32::NAN, 0.0), Err(E::NonFiniteBearing));
        assert_eq!(
            Feature::new(1.0, 0.0, f32::NEG_INFINITY),
            Err(E::NonFiniteSignature)
        );
        assert!(Feature::new(0.0, 7.0, 3.0).is_ok());
        assert_eq!(Landmark::new(f32::NAN, 0.0, 0.0), Err(E::NonFinitePosition));
        assert_eq!(
            Landmark::new(0.0, f32::INFINITY, 0.0),
            Err(E::NonFinitePosition)
        );
        assert_eq!(
            Landmark::new(0.0, 0.0, f32::NAN),
            Err(E::NonFiniteSignature)
        );
        let p = NoiseParam::Bearing;
        assert_eq!(
            FeatureNoise::new(0.1, 0.0, 1.0),
            Err(E::NonPositiveSigma(p))
        );
        assert_eq!(
            FeatureNoise::new(0.1, -0.1, 1.0),
            Err(E::NonPositiveSigma(p))
        );
        assert_eq!(
            FeatureNoise::new(0.1, f32::NAN, 1.0),
            Err(E::NonFiniteSigma(p))
        );
        assert_eq!(
            FeatureNoise::new(f32::INFINITY, f32::NAN, 1.0),
            Err(E::NonFiniteSigma(NoiseParam::Range))
        );
        assert_eq!(
            FeatureNoise::new(1.0, 1.0, 0.0),
            Err(E::NonPositiveSigma(NoiseParam::Signature))
        );
    }

    #[test]
    fn tiny_sigma_gives_minus_infinity_not_nan() {
        let noise = FeatureNoise::new(1e-38, 1e-38, 1e-38).unwrap();
        let lm = Landmark::new(1.0, 0.0, 0.0).unwrap();
        let far = Feature::new(1e3, 0.0, 0.0).unwrap();
        let ll = log_likelihood(&far, &lm, &Pose::default(), &noise);
        assert_eq!(ll, f32::NEG_INFINITY);
        // A zero residual over a subnormal σ is still 0, not NaN.
        let noise = FeatureNoise::new(1e-44, 1.0, 1.0).unwrap();
        let exact = Feature::new(1.0, 0.0, 0.0).unwrap();
        let ll = log_likelihood(&exact, &lm, &Pose::default(), &noise);
        assert!(ll.is_finite() && ll > 90.0, "{ll}");
    }
}
