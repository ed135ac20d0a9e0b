//! Ring geometry: `M ≤ capacity` ultrasonic transducers around a robot (docs/models.md#sonar).
//!
//! Each transducer has a bearing (radians, counter-clockwise from the robot's heading), a mounting
//! offset (metres in the robot frame: x forward, y left) and the ring shares one cone half-angle
//! (radians, in `(0, π)`) and one maximum range (metres). All values are validated once in
//! [`Ring::new`]; afterwards every accessor is infallible.

use crate::pose::{wrap_angle, SensorMount};
use crate::scan::{BeamLayout, ScanError};
use heapless::Vec;

/// One transducer of a ring.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Transducer {
    /// Bearing relative to the robot heading, radians counter-clockwise.
    pub bearing_rad: f32,
    /// Forward offset of the transducer from the robot origin, metres.
    pub x_m: f32,
    /// Leftward offset of the transducer from the robot origin, metres.
    pub y_m: f32,
}

/// Why a ring was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum RingError {
    /// More transducers than the capacity `M`.
    TooMany {
        /// How many were given.
        given: usize,
        /// The compile-time capacity.
        capacity: usize,
    },
    /// A ring with no transducer.
    Empty,
    /// A bearing that is not finite (index of the first one).
    NonFiniteBearing(usize),
    /// A mounting offset that is not finite (index of the first one).
    NonFiniteOffset(usize),
    /// Cone half-angle not finite or outside `(0, π)`.
    BadCone,
    /// Maximum range not finite or ≤ 0.
    BadMaxRange,
    /// A ring radius or angular step that is not finite (for [`Ring::uniform`]).
    BadGeometry,
}

impl core::fmt::Display for RingError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::TooMany { given, capacity } => {
                write!(f, "{given} transducers given, capacity is {capacity}")
            }
            Self::Empty => f.write_str("ring has no transducer"),
            Self::NonFiniteBearing(i) => write!(f, "bearing of transducer {i} is not finite"),
            Self::NonFiniteOffset(i) => write!(f, "offset of transducer {i} is not finite"),
            Self::BadCone => f.write_str("cone half-angle must be finite and in (0, pi)"),
            Self::BadMaxRange => f.write_str("max range must be finite and > 0"),
            Self::BadGeometry => f.write_str("ring radius and angular step must be finite"),
        }
    }
}

impl core::error::Error for RingError {}

/// A validated ring of at most `M` transducers.
#[derive(Clone, Debug, PartialEq)]
pub struct Ring<const M: usize> {
    transducers: Vec<Transducer, M>,
    cone_half_angle_rad: f32,
    max_range_m: f32,
}

impl<const M: usize> Ring<M> {
    /// A ring from explicit transducers.
    ///
    /// # Errors
    /// [`RingError::TooMany`], [`RingError::Empty`], [`RingError::NonFiniteBearing`],
    /// [`RingError::NonFiniteOffset`], [`RingError::BadCone`], [`RingError::BadMaxRange`].
    pub fn new(
        transducers: &[Transducer],
        cone_half_angle_rad: f32,
        max_range_m: f32,
    ) -> Result<Self, RingError> {
        if transducers.len() > M {
            return Err(RingError::TooMany {
                given: transducers.len(),
                capacity: M,
            });
        }
        if transducers.is_empty() {
            return Err(RingError::Empty);
        }
        for (i, t) in transducers.iter().enumerate() {
            if !t.bearing_rad.is_finite() {
                return Err(RingError::NonFiniteBearing(i));
            }
            if !(t.x_m.is_finite() && t.y_m.is_finite()) {
                return Err(RingError::NonFiniteOffset(i));
            }
        }
        if !(cone_half_angle_rad.is_finite()
            && cone_half_angle_rad > 0.0
            && cone_half_angle_rad < core::f32::consts::PI)
        {
            return Err(RingError::BadCone);
        }
        if !(max_range_m.is_finite() && max_range_m > 0.0) {
            return Err(RingError::BadMaxRange);
        }
        let transducers = Vec::from_slice(transducers).map_err(|_| RingError::TooMany {
            given: transducers.len(),
            capacity: M,
        })?;
        Ok(Self {
            transducers,
            cone_half_angle_rad,
            max_range_m,
        })
    }

    /// An evenly spaced ring: transducer `i` at bearing `first_rad + i·step_rad`, mounted at
    /// `radius_m` from the robot origin along its own bearing. A clockwise-numbered ring (the
    /// SCITOS G5's US1…US24) has a negative `step_rad`.
    ///
    /// # Errors
    /// As [`Ring::new`], plus [`RingError::BadGeometry`] for a non-finite radius, first bearing
    /// or step.
    pub fn uniform(
        count: usize,
        first_rad: f32,
        step_rad: f32,
        radius_m: f32,
        cone_half_angle_rad: f32,
        max_range_m: f32,
    ) -> Result<Self, RingError> {
        if !(first_rad.is_finite() && step_rad.is_finite() && radius_m.is_finite()) {
            return Err(RingError::BadGeometry);
        }
        if count > M {
            return Err(RingError::TooMany {
                given: count,
                capacity: M,
            });
        }
        let mut ts: Vec<Transducer, M> = Vec::new();
        for i in 0..count {
            // f64 so that transducer i does not accumulate i roundings.
            let b = (f64::from(first_rad) + i as f64 * f64::from(step_rad)) as f32;
            let (s, c) = crate::math::sin_cos(b);
            ts.push(Transducer {
                bearing_rad: b,
                x_m: radius_m * c,
                y_m: radius_m * s,
            })
            .map_err(|_| RingError::TooMany {
                given: count,
                capacity: M,
            })?;
        }
        Self::new(&ts, cone_half_angle_rad, max_range_m)
    }

    /// The transducers, in index order.
    pub fn transducers(&self) -> &[Transducer] {
        &self.transducers
    }

    /// Number of transducers (≥ 1, ≤ `M`).
    pub fn len(&self) -> usize {
        self.transducers.len()
    }

    /// Always false: a ring has at least one transducer.
    pub fn is_empty(&self) -> bool {
        self.transducers.is_empty()
    }

    /// The cone half-angle, radians, in `(0, π)`.
    pub fn cone_half_angle_rad(&self) -> f32 {
        self.cone_half_angle_rad
    }

    /// The transducers' maximum range, metres.
    pub fn max_range_m(&self) -> f32 {
        self.max_range_m
    }

    /// The unsigned angular separation `|Δβ_ij|` of two transducers, radians in `[0, π]`;
    /// 0 when either index is out of range.
    pub fn separation_rad(&self, i: usize, j: usize) -> f32 {
        match (self.transducers.get(i), self.transducers.get(j)) {
            (Some(a), Some(b)) => wrap_angle(a.bearing_rad - b.bearing_rad).abs(),
            _ => 0.0,
        }
    }

    /// The ring as a [`BeamLayout`] (bearings and max range), mounted at the robot origin.
    ///
    /// A `BeamLayout` has a single mount, so the per-transducer offsets are not carried over:
    /// ray-cast each transducer from `robot pose ⊕ (x_m, y_m)` using [`Ring::transducers`].
    ///
    /// # Errors
    /// None in practice (a validated ring always makes a valid layout); the layout's own
    /// [`ScanError`] is passed through rather than hidden.
    pub fn layout(&self) -> Result<BeamLayout<M>, ScanError> {
        let mut b: Vec<f32, M> = Vec::new();
        for t in &self.transducers {
            b.push(t.bearing_rad).map_err(|_| ScanError::TooMany {
                given: self.transducers.len(),
                capacity: M,
            })?;
        }
        BeamLayout::from_bearings(&b, self.max_range_m, SensorMount::CENTERED)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_table() {
        let t = Transducer::default();
        let bad = Transducer {
            bearing_rad: f32::NAN,
            ..t
        };
        let off = Transducer {
            y_m: f32::INFINITY,
            ..t
        };
        assert_eq!(
            Ring::<1>::new(&[t, t], 0.2, 5.0).err(),
            Some(RingError::TooMany {
                given: 2,
                capacity: 1
            })
        );
        assert_eq!(Ring::<2>::new(&[], 0.2, 5.0).err(), Some(RingError::Empty));
        assert_eq!(
            Ring::<2>::new(&[t, bad], 0.2, 5.0).err(),
            Some(RingError::NonFiniteBearing(1))
        );
        assert_eq!(
            Ring::<2>::new(&[off], 0.2, 5.0).err(),
            Some(RingError::NonFiniteOffset(0))
        );
        for cone in [0.0, -0.1, core::f32::consts::PI, f32::NAN] {
            assert_eq!(
                Ring::<2>::new(&[t], cone, 5.0).err(),
                Some(RingError::BadCone)
            );
        }
        for r in [0.0, f32::INFINITY, f32::NAN] {
            assert_eq!(
                Ring::<2>::new(&[t], 0.2, r).err(),
                Some(RingError::BadMaxRange)
            );
        }
        assert_eq!(
            Ring::<2>::uniform(2, 0.0, f32::NAN, 0.2, 0.2, 5.0).err(),
            Some(RingError::BadGeometry)
        );
    }

    #[test]
    fn clockwise_ring_and_separation() {
        let deg = core::f32::consts::PI / 180.0;
        let r = Ring::<24>::uniform(24, 0.0, -15.0 * deg, 0.3, 15.0 * deg, 5.0).unwrap();
        assert_eq!(r.len(), 24);
        // US7 (index 6) points right (−90°), US19 (index 18) left (−270° ≡ +90°).
        assert!((r.transducers()[6].bearing_rad + 90.0 * deg).abs() < 1e-6);
        assert!((r.transducers()[6].y_m + 0.3).abs() < 1e-6);
        assert!((r.separation_rad(0, 23) - 15.0 * deg).abs() < 1e-5);
        assert!((r.separation_rad(0, 12) - 180.0 * deg).abs() < 1e-5);
        assert_eq!(r.layout().unwrap().len(), 24);
    }
}
