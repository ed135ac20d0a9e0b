//! Fixed-capacity scans and the sensor layout they are read against.
//!
//! A [`BeamLayout`] holds what is fixed per sensor: each beam's bearing (and its unit vector,
//! computed once so that no per-beam trigonometry is ever needed), the sensor's maximum range and
//! its mounting offset. A [`Scan`] holds only the ranges of one sweep. Both have a compile-time
//! capacity `N`; neither allocates.
//!
//! # Reading policy
//! Every range is classified by [`Reading::classify`] before a model sees it:
//! - NaN or negative: [`Reading::Invalid`]. It is skipped by every model and counted in the score
//!   report ([`ScanScore::invalid`]), so nothing is lost silently.
//! - `+∞`, or any value `≥ max_range_m`: [`Reading::MaxRange`], "no return". The beam model scores
//!   it with its max-range point mass; the likelihood field skips it (Table 6.3), and counts it.
//! - otherwise, `0 ≤ z < max_range_m`: [`Reading::Range`].

use crate::pose::SensorMount;
use heapless::Vec;

/// One beam of a layout: bearing relative to the sensor's heading, and its unit vector.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Beam {
    /// Bearing relative to the sensor heading, radians counter-clockwise.
    pub bearing_rad: f32,
    /// `cos(bearing_rad)`.
    pub cos: f32,
    /// `sin(bearing_rad)`.
    pub sin: f32,
}

/// Errors building a [`BeamLayout`] or a [`Scan`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ScanError {
    /// More beams or readings than the capacity `N`.
    TooMany {
        /// How many were given.
        given: usize,
        /// The compile-time capacity.
        capacity: usize,
    },
    /// A layout with no beams.
    Empty,
    /// A bearing that is not finite (index of the first one).
    NonFiniteBearing(usize),
    /// Maximum range not finite or ≤ 0.
    BadMaxRange,
    /// Mounting offset not finite.
    BadMount,
    /// Angular step not finite.
    BadStep,
}

impl core::fmt::Display for ScanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::TooMany { given, capacity } => {
                write!(f, "{given} beams given, capacity is {capacity}")
            }
            Self::Empty => f.write_str("layout has no beams"),
            Self::NonFiniteBearing(i) => write!(f, "bearing {i} is not finite"),
            Self::BadMaxRange => f.write_str("max range must be finite and > 0"),
            Self::BadMount => f.write_str("sensor mount offset must be finite"),
            Self::BadStep => f.write_str("angular step must be finite"),
        }
    }
}

impl core::error::Error for ScanError {}

/// The fixed geometry of a range sensor with at most `N` beams.
#[derive(Clone, Debug)]
pub struct BeamLayout<const N: usize> {
    beams: Vec<Beam, N>,
    max_range_m: f32,
    mount: SensorMount,
}

impl<const N: usize> BeamLayout<N> {
    /// A layout from explicit bearings (radians, relative to the sensor heading).
    ///
    /// # Errors
    /// [`ScanError::TooMany`] past capacity, [`ScanError::Empty`], [`ScanError::NonFiniteBearing`],
    /// [`ScanError::BadMaxRange`] (not finite or ≤ 0), [`ScanError::BadMount`].
    pub fn from_bearings(
        bearings_rad: &[f32],
        max_range_m: f32,
        mount: SensorMount,
    ) -> Result<Self, ScanError> {
        if bearings_rad.len() > N {
            return Err(ScanError::TooMany {
                given: bearings_rad.len(),
                capacity: N,
            });
        }
        if bearings_rad.is_empty() {
            return Err(ScanError::Empty);
        }
        if !(max_range_m.is_finite() && max_range_m > 0.0) {
            return Err(ScanError::BadMaxRange);
        }
        if !(mount.x_m.is_finite() && mount.y_m.is_finite() && mount.yaw_rad.is_finite()) {
            return Err(ScanError::BadMount);
        }
        let mut beams = Vec::new();
        for (i, &b) in bearings_rad.iter().enumerate() {
            if !b.is_finite() {
                return Err(ScanError::NonFiniteBearing(i));
            }
            let (sin, cos) = crate::math::sin_cos(b);
            // Capacity was checked above, so this push cannot fail; map it anyway.
            beams
                .push(Beam {
                    bearing_rad: b,
                    cos,
                    sin,
                })
                .map_err(|_| ScanError::TooMany {
                    given: bearings_rad.len(),
                    capacity: N,
                })?;
        }
        Ok(Self {
            beams,
            max_range_m,
            mount,
        })
    }

    /// An evenly spaced layout: beam `i` at `first_rad + i·step_rad`, for `i < count`.
    ///
    /// A CARMEN FLASER scan of n beams is `uniform(−π/2, π/n, n, …)`; a ROS `LaserScan` is
    /// `uniform(angle_min, angle_increment, ranges.len(), range_max, …)`.
    ///
    /// # Errors
    /// As [`BeamLayout::from_bearings`], plus [`ScanError::BadStep`].
    pub fn uniform(
        first_rad: f32,
        step_rad: f32,
        count: usize,
        max_range_m: f32,
        mount: SensorMount,
    ) -> Result<Self, ScanError> {
        if !(first_rad.is_finite() && step_rad.is_finite()) {
            return Err(ScanError::BadStep);
        }
        if count > N {
            return Err(ScanError::TooMany {
                given: count,
                capacity: N,
            });
        }
        // Bearing i is `first + i·step` with one rounding at the end, not i accumulated ones,
        // and without f64 (soft-float on a Cortex-M4F: 2 KB of flash). The step is split into
        // 12-bit halves, so for i < 4,096 both partial products are exact in f32; the three
        // terms are then added with the first addition's error carried (two-sum).
        let step_hi = f32::from_bits(step_rad.to_bits() & 0xFFFF_F000);
        let step_lo = step_rad - step_hi;
        let mut bearings: Vec<f32, N> = Vec::new();
        for i in 0..count {
            let fi = i as f32;
            let (a, c) = (fi * step_hi, fi * step_lo);
            let s = first_rad + a;
            let z = s - first_rad;
            let err = (first_rad - (s - z)) + (a - z);
            let b = s + (err + c);
            bearings.push(b).map_err(|_| ScanError::TooMany {
                given: count,
                capacity: N,
            })?;
        }
        Self::from_bearings(&bearings, max_range_m, mount)
    }

    /// The beams, in order.
    pub fn beams(&self) -> &[Beam] {
        &self.beams
    }

    /// Number of beams (≤ `N`).
    pub fn len(&self) -> usize {
        self.beams.len()
    }

    /// Always false: a layout has at least one beam.
    pub fn is_empty(&self) -> bool {
        self.beams.is_empty()
    }

    /// The sensor's maximum range, metres. Readings at or beyond it are max-range readings.
    pub fn max_range_m(&self) -> f32 {
        self.max_range_m
    }

    /// The sensor's mounting offset on the robot.
    pub fn mount(&self) -> SensorMount {
        self.mount
    }
}

/// How a model must treat one range reading. See the module docs for the policy.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reading {
    /// A measured range, metres, `0 ≤ z < max_range`.
    Range(f32),
    /// No return: `z ≥ max_range` or `+∞`.
    MaxRange,
    /// NaN or negative: skipped and counted.
    Invalid,
}

impl Reading {
    /// Classifies a raw range against the sensor's maximum range (metres).
    #[inline]
    pub fn classify(range_m: f32, max_range_m: f32) -> Self {
        if range_m.is_nan() || range_m < 0.0 {
            Self::Invalid
        } else if range_m >= max_range_m {
            Self::MaxRange
        } else {
            Self::Range(range_m)
        }
    }
}

/// The ranges of one sweep, at most `N` of them, metres, in the layout's beam order.
#[derive(Clone, Debug, PartialEq)]
pub struct Scan<const N: usize> {
    ranges_m: Vec<f32, N>,
}

impl<const N: usize> Default for Scan<N> {
    fn default() -> Self {
        Self {
            ranges_m: Vec::new(),
        }
    }
}

impl<const N: usize> Scan<N> {
    /// A scan from a slice of ranges (metres). Any value is accepted: the reading policy decides
    /// later how each one is treated.
    ///
    /// # Errors
    /// [`ScanError::TooMany`] when `ranges_m.len() > N`; nothing is truncated silently.
    pub fn from_ranges(ranges_m: &[f32]) -> Result<Self, ScanError> {
        let ranges_m = Vec::from_slice(ranges_m).map_err(|_| ScanError::TooMany {
            given: ranges_m.len(),
            capacity: N,
        })?;
        Ok(Self { ranges_m })
    }

    /// The ranges, metres.
    pub fn ranges_m(&self) -> &[f32] {
        &self.ranges_m
    }

    /// Mutable access to the ranges, for a driver that refills a scan in place.
    pub fn ranges_m_mut(&mut self) -> &mut [f32] {
        &mut self.ranges_m
    }

    /// Appends one reading.
    ///
    /// # Errors
    /// Gives the reading back when the scan is full.
    pub fn push(&mut self, range_m: f32) -> Result<(), f32> {
        self.ranges_m.push(range_m)
    }

    /// Removes every reading, keeping the storage.
    pub fn clear(&mut self) {
        self.ranges_m.clear();
    }

    /// Number of readings.
    pub fn len(&self) -> usize {
        self.ranges_m.len()
    }

    /// True when the scan holds no reading.
    pub fn is_empty(&self) -> bool {
        self.ranges_m.is_empty()
    }
}

/// The result of scoring one scan at one pose.
///
/// `log_likelihood` sums over the beams that were scored; the counts say what happened to the
/// others. `scored + max_range + invalid + unpaired` equals the number of readings in the scan.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScanScore {
    /// Sum of per-beam log-likelihoods (natural log, nats). Never NaN; finite for valid models.
    pub log_likelihood: f32,
    /// Beams that contributed a term (for the beam model, max-range readings are included here).
    pub scored: u16,
    /// Max-range readings skipped by a model that does not score them (likelihood field).
    pub max_range: u16,
    /// NaN or negative readings, skipped.
    pub invalid: u16,
    /// Readings past the end of the layout (scan longer than the layout), skipped.
    pub unpaired: u16,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classify_table() {
        let cases = [
            (1.0, Reading::Range(1.0)),
            (0.0, Reading::Range(0.0)),
            (10.0, Reading::MaxRange),
            (11.0, Reading::MaxRange),
            (f32::INFINITY, Reading::MaxRange),
            (f32::NEG_INFINITY, Reading::Invalid),
            (-0.5, Reading::Invalid),
            (f32::NAN, Reading::Invalid),
        ];
        for (z, want) in cases {
            assert_eq!(Reading::classify(z, 10.0), want, "z = {z}");
        }
    }

    #[test]
    fn layout_validation() {
        let m = SensorMount::CENTERED;
        assert_eq!(
            BeamLayout::<2>::from_bearings(&[0.0, 0.1, 0.2], 10.0, m).err(),
            Some(ScanError::TooMany {
                given: 3,
                capacity: 2
            })
        );
        assert_eq!(
            BeamLayout::<2>::from_bearings(&[], 10.0, m).err(),
            Some(ScanError::Empty)
        );
        assert_eq!(
            BeamLayout::<2>::from_bearings(&[0.0, f32::NAN], 10.0, m).err(),
            Some(ScanError::NonFiniteBearing(1))
        );
        assert_eq!(
            BeamLayout::<2>::from_bearings(&[0.0], 0.0, m).err(),
            Some(ScanError::BadMaxRange)
        );
        let l = BeamLayout::<180>::uniform(
            -core::f32::consts::FRAC_PI_2,
            core::f32::consts::PI / 180.0,
            180,
            81.83,
            m,
        )
        .unwrap();
        assert_eq!(l.len(), 180);
        assert!((l.beams()[90].bearing_rad).abs() < 1e-7);
        assert!((l.beams()[0].cos).abs() < 1e-6 && (l.beams()[0].sin + 1.0).abs() < 1e-6);
    }

    /// `uniform`'s f32 bearings against `first + i·step` computed in f64, the formula it used
    /// before (the product is exact in f64; the sum is exact or one f64 rounding away): each must
    /// be the f32 nearest to it or its neighbour (faithful), and the nearest in nearly every case.
    #[test]
    fn uniform_bearings_are_rounded_once() {
        let mut rng = crate::mcl::XorShift64::new(0x9E37_79B9_7F4A_7C15u64);
        let mut next = || rng.uniform();
        let (mut total, mut not_nearest) = (0usize, 0usize);
        for _ in 0..300 {
            let first = (-3.2 + 6.4 * next()) as f32;
            let step = (1e-3 + 0.05 * next()) as f32;
            let l =
                BeamLayout::<720>::uniform(first, step, 720, 10.0, SensorMount::CENTERED).unwrap();
            for (i, beam) in l.beams().iter().enumerate() {
                let exact = f64::from(first) + i as f64 * f64::from(step);
                let nearest = exact as f32;
                let got = beam.bearing_rad;
                total += 1;
                if got != nearest {
                    not_nearest += 1;
                    let ulp =
                        f64::from(f32::from_bits(nearest.abs().to_bits() + 1) - nearest.abs());
                    assert!(
                        (f64::from(got) - exact).abs() < ulp,
                        "beam {i}: {got} vs {exact}"
                    );
                }
            }
        }
        println!("uniform: {not_nearest} of {total} bearings are the other faithful neighbour");
        assert!(not_nearest * 1000 <= total, "{not_nearest} of {total}");
    }

    #[test]
    fn scan_capacity_is_an_error_not_a_truncation() {
        assert!(Scan::<3>::from_ranges(&[1.0, 2.0, 3.0]).is_ok());
        assert_eq!(
            Scan::<3>::from_ranges(&[1.0, 2.0, 3.0, 4.0]).err(),
            Some(ScanError::TooMany {
                given: 4,
                capacity: 3
            })
        );
        let mut s = Scan::<1>::default();
        assert_eq!(s.push(1.0), Ok(()));
        assert_eq!(s.push(2.0), Err(2.0));
    }
}
