//! The two-feature proposal: the pose(s) consistent with two features of two known landmarks.
//!
//! One feature leaves a circle of positions (Table 6.5 samples along it); two features give two
//! range circles whose intersection (0, 1 or 2 points) pins the position, and the two bearings
//! then give the heading. With four constraints on three unknowns, the leftover disagreement
//! between the two implied headings is a consistency check: at the mirror-image candidate it is
//! large unless the geometry is symmetric.
//!
//! Circle intersection, with `c₁, c₂` the landmarks, `d = |c₂ − c₁|`, `e = (c₂ − c₁)/d` and
//! `n = (−e_y, e_x)` (the left normal of `c₁ → c₂`):
//!
//! ```text
//! a = (d² + r₁² − r₂²) / (2d),   h² = r₁² − a²
//! p = c₁ + a·e ± h·n             (first candidate +h: left of c₁ → c₂; second −h)
//! ```
//!
//! Heading at a candidate `p`: each feature implies `θ_i = atan2(c_i − p) − φ_i`; the candidate's
//! heading is their circular mean, computed as `θ₁ + ½·wrap(θ₂ − θ₁)` (identical to
//! `atan2(sin θ₁ + sin θ₂, cos θ₁ + cos θ₂)` whenever the two are not exactly opposite, and
//! cheaper), and `|wrap(θ₂ − θ₁)|` is reported as the candidate's heading spread. A feature of
//! range 0 carries no bearing information (the robot sits on its landmark); the heading then
//! comes from the other feature alone, with spread 0.

use super::sample::perturb;
use super::{Feature, FeatureNoise, Landmark};
use crate::math;
use crate::pose::{wrap_angle, Pose};
use rand_core::Rng;

/// Landmarks closer together than this fraction of the larger range are reported as
/// [`IntersectionError::Concentric`]: below it the f32 intersection loses most of its digits
/// (the error of `a` grows like `ε·r²/d`).
pub const CONCENTRIC_RELATIVE_TOLERANCE: f32 = 1e-5;

/// Rounding allowance, in units of `f32::EPSILON·(r₁² + a²)`, under which a slightly negative
/// `h²` is read as a tangency (one candidate) rather than a miss.
const TANGENT_ULPS: f32 = 8.0;

/// Why two range circles give no position.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum IntersectionError {
    /// The landmarks coincide (closer than [`CONCENTRIC_RELATIVE_TOLERANCE`] of the larger
    /// range): the circles are concentric and the position is not determined.
    Concentric,
    /// The circles are disjoint and side by side: the landmarks are farther apart than the sum
    /// of the ranges.
    CirclesApart,
    /// One circle lies inside the other: the landmarks are closer together than the difference
    /// of the ranges.
    CircleInside,
}

impl core::fmt::Display for IntersectionError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Concentric => "landmarks coincide: range circles are concentric",
            Self::CirclesApart => "landmarks farther apart than the sum of the ranges",
            Self::CircleInside => "one range circle lies inside the other",
        })
    }
}

impl core::error::Error for IntersectionError {}

/// One candidate pose of the two-feature proposal.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PoseCandidate {
    /// Position on both range circles; heading the circular mean of the two implied headings,
    /// wrapped into `[−π, π)`.
    pub pose: Pose,
    /// `|wrap(θ₂ − θ₁)|`, radians in `[0, π]`: how far apart the headings implied by the two
    /// bearings are. Near 0 at the true pose (up to bearing noise); large at a mirror-image
    /// candidate.
    pub heading_spread_rad: f32,
}

/// The one or two candidates of a two-feature proposal (two circles meet in at most two points;
/// none is an [`IntersectionError`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TwoFeaturePoses {
    candidates: [PoseCandidate; 2],
    two: bool,
}

impl TwoFeaturePoses {
    /// The candidates: one for tangent circles, otherwise two (first the one to the left of the
    /// direction from the first landmark to the second).
    pub fn as_slice(&self) -> &[PoseCandidate] {
        let n = if self.two { 2 } else { 1 };
        self.candidates.get(..n).unwrap_or(&[])
    }

    /// How many candidates: 1 or 2.
    pub fn len(&self) -> usize {
        if self.two {
            2
        } else {
            1
        }
    }

    /// Always false: a result holds at least one candidate. (For `clippy::len_without_is_empty`.)
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The candidate whose two implied headings agree best (smallest heading spread; the first
    /// on a tie).
    pub fn best(&self) -> PoseCandidate {
        let [a, b] = self.candidates;
        if self.two && b.heading_spread_rad < a.heading_spread_rad {
            b
        } else {
            a
        }
    }
}

/// The pose(s) at which feature `f1` of landmark `l1` and feature `f2` of landmark `l2` are
/// both observed exactly (range circles intersected, heading from the bearings). Signatures are
/// not used: the correspondences are given.
///
/// # Errors
/// [`IntersectionError`] when the circles do not meet (apart, nested) or the landmarks
/// coincide. A near-tangency whose `h²` is negative only by rounding (within 8 ulp of
/// `r₁² + a²`) is reported as one tangent candidate, not as a miss.
pub fn two_feature_poses(
    f1: &Feature,
    l1: &Landmark,
    f2: &Feature,
    l2: &Landmark,
) -> Result<TwoFeaturePoses, IntersectionError> {
    intersect(
        (f1.range_m, f1.bearing_rad, l1),
        (f2.range_m, f2.bearing_rad, l2),
    )
}

/// The two-feature proposal with sampling noise: each feature's range and bearing are perturbed
/// exactly as in [`super::sample_pose`] (`r̂_i = r_i + ε_r` conditioned on `r̂_i ≥ 0`,
/// `φ̂_i = φ_i + ε_φ`), then the noisy circles are intersected as in [`two_feature_poses`].
///
/// Random numbers: one Box–Muller pair (two `next_u32`, plus redraws for a negative range) for
/// `f1`, then one for `f2`.
///
/// # Errors
/// An [`IntersectionError`], as [`two_feature_poses`]: with noise, circles that nearly touch can miss each other; draw
/// again or widen the search.
pub fn sample_two_feature_poses<R: Rng + ?Sized>(
    f1: &Feature,
    l1: &Landmark,
    f2: &Feature,
    l2: &Landmark,
    noise: &FeatureNoise,
    rng: &mut R,
) -> Result<TwoFeaturePoses, IntersectionError> {
    let (r1, b1) = perturb(f1, noise, rng);
    let (r2, b2) = perturb(f2, noise, rng);
    intersect((r1, b1, l1), (r2, b2, l2))
}

/// Intersects the circles `(range, bearing, landmark)` and attaches headings.
fn intersect(
    (r1, b1, l1): (f32, f32, &Landmark),
    (r2, b2, l2): (f32, f32, &Landmark),
) -> Result<TwoFeaturePoses, IntersectionError> {
    let dx = l2.x_m - l1.x_m;
    let dy = l2.y_m - l1.y_m;
    let d = math::sqrt(dx * dx + dy * dy);
    let r_max = r1.max(r2);
    // Inputs are finite (validated), so this also catches d = 0 with both ranges 0.
    if d <= CONCENTRIC_RELATIVE_TOLERANCE * r_max {
        return Err(IntersectionError::Concentric);
    }
    let (ex, ey) = (dx / d, dy / d);
    let a = (d * d + (r1 - r2) * (r1 + r2)) / (2.0 * d);
    let h_sq = (r1 - a) * (r1 + a);
    let tolerance = TANGENT_ULPS * f32::EPSILON * (r1 * r1 + a * a);
    let h = if h_sq >= 0.0 {
        math::sqrt(h_sq)
    } else if h_sq >= -tolerance {
        0.0
    } else if d > r_max {
        return Err(IntersectionError::CirclesApart);
    } else {
        return Err(IntersectionError::CircleInside);
    };
    let (mx, my) = (l1.x_m + a * ex, l1.y_m + a * ey);
    let at = |sign: f32| {
        let x_m = mx - sign * h * ey;
        let y_m = my + sign * h * ex;
        candidate(x_m, y_m, (r1, b1, l1), (r2, b2, l2))
    };
    let first = at(1.0);
    if h > 0.0 {
        Ok(TwoFeaturePoses {
            candidates: [first, at(-1.0)],
            two: true,
        })
    } else {
        Ok(TwoFeaturePoses {
            candidates: [first, first],
            two: false,
        })
    }
}

/// The candidate at `(x_m, y_m)`: headings implied by both bearings, their circular mean and
/// spread.
fn candidate(
    x_m: f32,
    y_m: f32,
    (r1, b1, l1): (f32, f32, &Landmark),
    (r2, b2, l2): (f32, f32, &Landmark),
) -> PoseCandidate {
    let implied =
        |bearing_rad: f32, l: &Landmark| math::atan2(l.y_m - y_m, l.x_m - x_m) - bearing_rad;
    let (theta_rad, heading_spread_rad) = if r1 == 0.0 {
        (implied(b2, l2), 0.0)
    } else if r2 == 0.0 {
        (implied(b1, l1), 0.0)
    } else {
        let t1 = implied(b1, l1);
        let diff = wrap_angle(implied(b2, l2) - t1);
        (t1 + 0.5 * diff, diff.abs())
    };
    PoseCandidate {
        pose: Pose::new(x_m, y_m, wrap_angle(theta_rad)),
        heading_spread_rad,
    }
}
