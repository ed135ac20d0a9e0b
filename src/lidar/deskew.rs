//! Motion de-skew of one revolution of a spinning LiDAR: every beam's endpoint moved into the
//! robot frame of one reference time, and the corrected endpoints binned back into the same
//! fixed layout.
//!
//! # Why
//! A revolution takes a while (LD06: ~100 ms at 10 Hz); a moving robot measures its first and
//! last beams from different poses. Scoring the revolution at one pose misplaces the endpoints:
//! at 1.5 rad/s a 100 ms turn spreads the bearings over 0.15 rad (±0.075 rad around the middle),
//! at 0.5 m/s the positions over 5 cm.
//!
//! # When each beam was measured
//! The assembler keeps one range per beam, not the point's own timestamp. What the data
//! supports is a beam's **rotor position**: the point in beam `j` lies within half a beam step
//! of the beam's clockwise angle `a_j = −β_j` (degrees, taken in `[0, 360)`, `β_j` the layout's
//! bearing). The LD06 stamps each frame of twelve points with its first point's time, and the
//! rotor turns at a near-constant rate, so time is linear in rotor position between the
//! revolution's two stamp anchors ([`RevolutionTiming`](super::RevolutionTiming)): the first
//! point (position `start_deg`) and the first point of the last frame (position `end_deg`).
//! The odometry is therefore asked for at those two times only, and the pose of beam `j` is
//! interpolated (or, after the last stamp, extrapolated) linearly between them, at
//! `f_j = (a_j − start_deg) / (end_deg − start_deg)`: linear in position, heading along the
//! shorter arc, as [`OdometryWindow::at`](crate::robot::OdometryWindow::at) interpolates. The
//! chord of a 100 ms arc at 0.5 m/s and 1.5 rad/s is within 1 mm of the arc.
//!
//! # What is computed
//! With `T_ref` the odometry pose at the reference time and `T_j` the pose of beam `j`, the
//! endpoint `p` of beam `j` in the robot frame at its own time (the mount applied) becomes
//! `q = T_ref⁻¹ · T_j · p`, then range `|q − m|` and bearing `atan2` in the sensor frame again
//! (`m` the mount). It is binned to the nearest beam within half a step, by the assembler's
//! rule ([`ScanAssembler`](super::ScanAssembler)); two endpoints in one bin keep the **nearer
//! range** (the obstacle in front hides the one behind); a bin that receives none reads NaN.
//! Readings that carry no endpoint (NaN, negative, at or beyond the layout's maximum range)
//! stay in their own bin unless an endpoint lands there. A corrected endpoint whose bearing
//! leaves a partial layout's field of view is dropped and counted.
//!
//! # Exactness
//! With no motion (the three poses bit-for-bit equal, or more generally every relative term
//! exactly zero) the scan is copied bit for bit, with no arithmetic. Otherwise the binning
//! moves an endpoint sideways by up to half a beam step (`r · sin(step/2)`: 8.7 mm at 1 m for
//! 1° beams); the continuous correction itself is exact up to `f32` rounding and the linear
//! model of the pose.
//!
//! # Cost per beam
//! One `sin_cos` (of the beam's relative heading), one `sqrt`, one `atan2`, one `floor`, 24
//! multiplies and about 20 adds (the layout's unit vectors are precomputed), the nearest-bin
//! lookup of the assembler (one multiply), one compare-and-store: counted by hand, not yet
//! under QEMU (docs/robot.md, "De-skew", has the measured effect and the cost). No allocation;
//! the output is a second `Scan<N>` the caller provides.

use super::assembler::{AssemblerError, Bins};
use crate::math;
use crate::pose::{wrap_angle, Pose};
use crate::scan::{BeamLayout, Scan};

/// Why a revolution could not be de-skewed (the caller then uses it as it is).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DeskewError {
    /// The layout cannot be binned (not evenly spaced, more than one turn).
    Layout(AssemblerError),
    /// A pose of the sweep has a NaN or infinite component.
    NonFinitePose,
    /// The anchor positions are not finite or not increasing (`end_deg ≤ start_deg`).
    BadAnchors,
    /// The revolution has no usable timing (no timestamps, a single frame): nothing to
    /// interpolate the beams' times with.
    NoTiming,
    /// The odometry does not reach the revolution's start or end (the pose there would be a
    /// guess).
    OdometryMissing,
}

impl core::fmt::Display for DeskewError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Layout(e) => write!(f, "de-skew layout: {e}"),
            Self::NonFinitePose => f.write_str("de-skew pose is not finite"),
            Self::BadAnchors => f.write_str("de-skew anchors must be finite and increasing"),
            Self::NoTiming => f.write_str("revolution has no timestamps to de-skew with"),
            Self::OdometryMissing => f.write_str("odometry does not cover the revolution"),
        }
    }
}

impl core::error::Error for DeskewError {}

/// The motion during one revolution: odometry poses (any fixed frame, m and rad) at the two
/// timing anchors and at the reference time whose robot frame the corrected scan is in.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sweep {
    /// Rotor position of the first anchor, degrees clockwise
    /// ([`RevolutionTiming::start_deg`](super::RevolutionTiming::start_deg)).
    pub start_deg: f32,
    /// Rotor position of the second anchor, degrees clockwise (> `start_deg`).
    pub end_deg: f32,
    /// Odometry pose at the first anchor's time.
    pub start: Pose,
    /// Odometry pose at the second anchor's time.
    pub end: Pose,
    /// Odometry pose at the reference time.
    pub reference: Pose,
}

/// What [`Deskewer::apply`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DeskewReport {
    /// No motion: the scan was copied unchanged.
    pub still: bool,
    /// Endpoints corrected and binned.
    pub moved: u16,
    /// Endpoints that lost their bin to a nearer one (or displaced a farther one).
    pub collided: u16,
    /// Corrected endpoints outside the layout's field of view (dropped).
    pub outside: u16,
}

/// De-skews revolutions on one evenly spaced layout. See the [module docs](self).
#[derive(Clone, Copy, Debug)]
pub struct Deskewer {
    bins: Bins,
}

impl Deskewer {
    /// A de-skewer for `layout` (which must be evenly spaced, as for the assembler).
    ///
    /// # Errors
    /// [`DeskewError::Layout`] as [`ScanAssembler::new`](super::ScanAssembler::new).
    pub fn new<const N: usize>(layout: &BeamLayout<N>) -> Result<Self, DeskewError> {
        Ok(Self {
            bins: Bins::new(layout).map_err(DeskewError::Layout)?,
        })
    }

    /// Writes `scan` (read against `layout`, the one given to [`Deskewer::new`]) de-skewed for
    /// `sweep` into `out` (same length as `scan`; readings past the layout's end are copied).
    ///
    /// # Errors
    /// [`DeskewError::NonFinitePose`], [`DeskewError::BadAnchors`]; `out` is then a copy of
    /// `scan`.
    pub fn apply<const N: usize>(
        &self,
        layout: &BeamLayout<N>,
        scan: &Scan<N>,
        sweep: &Sweep,
        out: &mut Scan<N>,
    ) -> Result<DeskewReport, DeskewError> {
        out.clone_from(scan);
        let Some(motion) = Motion::new(layout, sweep)? else {
            return Ok(DeskewReport {
                still: true,
                ..DeskewReport::default()
            });
        };
        let max_r = layout.max_range_m();
        let n = layout.len().min(scan.len());
        let mut report = DeskewReport::default();
        let dst = out.ranges_m_mut();
        // Bins of the layout start empty; readings without an endpoint are put back after.
        for d in dst.iter_mut().take(n) {
            *d = f32::NAN;
        }
        for (beam, &range) in layout.beams().iter().zip(scan.ranges_m()).take(n) {
            if !((range >= 0.0) & (range < max_r)) {
                continue;
            }
            let (r2, a2) = motion.correct(beam, range);
            report.moved = report.moved.saturating_add(1);
            let Some(slot) =
                self.bins
                    .nearest(a2)
                    .and_then(|(j, _)| if j < n { dst.get_mut(j) } else { None })
            else {
                report.outside = report.outside.saturating_add(1);
                continue;
            };
            if slot.is_nan() {
                *slot = r2;
            } else {
                report.collided = report.collided.saturating_add(1);
                if r2 < *slot {
                    *slot = r2;
                }
            }
        }
        for (d, &range) in dst.iter_mut().zip(scan.ranges_m()).take(n) {
            if d.is_nan() && !((range >= 0.0) & (range < max_r)) {
                *d = range;
            }
        }
        Ok(report)
    }

    /// The corrected endpoint of one reading before binning, as [`Deskewer::apply`] computes it:
    /// `(range_m, bearing_rad)` in the sensor frame at the reference time (bearing
    /// counter-clockwise, in `(−π, π]`), for `range_m` read on beam `index` of `layout`.
    /// `Ok(None)` when `index` is past the layout; with no motion the reading itself.
    ///
    /// # Errors
    /// As [`Deskewer::apply`].
    pub fn correct_beam<const N: usize>(
        &self,
        layout: &BeamLayout<N>,
        sweep: &Sweep,
        index: usize,
        range_m: f32,
    ) -> Result<Option<(f32, f32)>, DeskewError> {
        let Some(beam) = layout.beams().get(index) else {
            return Ok(None);
        };
        Ok(Some(match Motion::new(layout, sweep)? {
            None => (range_m, beam.bearing_rad),
            Some(m) => {
                let (r, a) = m.correct(beam, range_m);
                (r, wrap_angle(-a.to_radians()))
            }
        }))
    }
}

/// The per-revolution constants: the beam pose's offset from the reference `d0 + f·dv` and
/// relative heading `h0 + f·w` (reference frame), and the mount.
#[derive(Clone, Copy, Debug)]
struct Motion {
    start_deg: f32,
    inv_span: f32,
    d0: (f32, f32),
    dv: (f32, f32),
    h0: f32,
    w: f32,
    mount: crate::pose::SensorMount,
    sin_m: f32,
    cos_m: f32,
}

impl Motion {
    /// `None` when there is no motion (every relative term exactly zero).
    fn new<const N: usize>(
        layout: &BeamLayout<N>,
        sweep: &Sweep,
    ) -> Result<Option<Self>, DeskewError> {
        let (s, e, r) = (sweep.start, sweep.end, sweep.reference);
        if !(s.is_finite() && e.is_finite() && r.is_finite()) {
            return Err(DeskewError::NonFinitePose);
        }
        let span = sweep.end_deg - sweep.start_deg;
        if !(sweep.start_deg.is_finite() && span.is_finite() && span > 0.0) {
            return Err(DeskewError::BadAnchors);
        }
        let (sin_r, cos_r) = math::sin_cos(r.theta_rad);
        let rot = |x: f32, y: f32| (cos_r * x + sin_r * y, -sin_r * x + cos_r * y);
        let d0 = rot(s.x_m - r.x_m, s.y_m - r.y_m);
        let dv = rot(e.x_m - s.x_m, e.y_m - s.y_m);
        let h0 = wrap_angle(s.theta_rad - r.theta_rad);
        let w = wrap_angle(e.theta_rad - s.theta_rad);
        if d0 == (0.0, 0.0) && dv == (0.0, 0.0) && h0 == 0.0 && w == 0.0 {
            return Ok(None);
        }
        let mount = layout.mount();
        let (sin_m, cos_m) = math::sin_cos(mount.yaw_rad);
        Ok(Some(Self {
            start_deg: sweep.start_deg,
            inv_span: 1.0 / span,
            d0,
            dv,
            h0,
            w,
            mount,
            sin_m,
            cos_m,
        }))
    }

    /// The corrected range (m) and clockwise angle (degrees, `[0, 360)`) of a reading.
    #[inline(always)]
    fn correct(&self, beam: &crate::scan::Beam, range: f32) -> (f32, f32) {
        let (m, sin_m, cos_m) = (self.mount, self.sin_m, self.cos_m);
        // Rotor position of the beam, degrees clockwise in [0, 360).
        // (A floor, not `%`: `fmodf` loops in software on a Cortex-M4F.)
        let d = -beam.bearing_rad.to_degrees();
        let mut a = d - 360.0 * math::floor(d * (1.0 / 360.0));
        if !(0.0..360.0).contains(&a) {
            a = 0.0;
        }
        let f = (a - self.start_deg) * self.inv_span;
        let (dx, dy) = (self.d0.0 + f * self.dv.0, self.d0.1 + f * self.dv.1);
        let (sin_h, cos_h) = math::sin_cos(self.h0 + f * self.w);
        // Endpoint in the robot frame at the beam's time.
        let ux = cos_m * beam.cos - sin_m * beam.sin;
        let uy = sin_m * beam.cos + cos_m * beam.sin;
        let (px, py) = (m.x_m + range * ux, m.y_m + range * uy);
        // In the reference robot frame, then relative to the sensor, in its own axes.
        let qx = dx + cos_h * px - sin_h * py - m.x_m;
        let qy = dy + sin_h * px + cos_h * py - m.y_m;
        let (sx, sy) = (cos_m * qx + sin_m * qy, -sin_m * qx + cos_m * qy);
        let r2 = math::sqrt(sx * sx + sy * sy);
        let mut a2 = -math::atan2(sy, sx).to_degrees();
        if a2 < 0.0 {
            a2 += 360.0;
        }
        if !(0.0..360.0).contains(&a2) {
            a2 = 0.0;
        }
        (r2, a2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lidar::assembler::full_turn_layout;
    use crate::pose::SensorMount;

    const N: usize = 360;

    fn layout(mount: SensorMount) -> BeamLayout<N> {
        full_turn_layout(N, 12.0, mount).unwrap()
    }

    fn ring() -> Scan<N> {
        let mut s = Scan::<N>::default();
        for k in 0..N {
            let r = match k % 37 {
                0 => f32::NAN,
                1 => 12.0,
                _ => 1.0 + 0.013 * k as f32,
            };
            s.push(r).unwrap();
        }
        s
    }

    fn sweep(start: Pose, end: Pose, reference: Pose) -> Sweep {
        Sweep {
            start_deg: 0.0,
            end_deg: 348.0,
            start,
            end,
            reference,
        }
    }

    #[test]
    fn no_motion_copies_the_scan_bit_for_bit() {
        let mount = SensorMount {
            x_m: 0.1,
            y_m: -0.02,
            yaw_rad: 0.3,
        };
        let l = layout(mount);
        let d = Deskewer::new(&l).unwrap();
        let scan = ring();
        let p = Pose::new(3.2, -1.5, 2.9);
        let mut out = Scan::default();
        let rep = d.apply(&l, &scan, &sweep(p, p, p), &mut out).unwrap();
        assert!(rep.still);
        assert_eq!(out.len(), scan.len());
        for (a, b) in out.ranges_m().iter().zip(scan.ranges_m()) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
    }

    #[test]
    fn a_pure_rotation_shifts_bins_by_the_turned_angle() {
        let l = layout(SensorMount::CENTERED);
        let d = Deskewer::new(&l).unwrap();
        let mut scan = Scan::<N>::default();
        for _ in 0..N {
            scan.push(2.0).unwrap();
        }
        // The robot turns 10° counter-clockwise during the sweep; reference at the start: a
        // beam measured at fraction f saw its target at bearing β + 10°·f in the start frame.
        let start = Pose::new(0.0, 0.0, 0.0);
        let end = Pose::new(0.0, 0.0, 10f32.to_radians());
        let mut out = Scan::default();
        let rep = d
            .apply(&l, &scan, &sweep(start, end, start), &mut out)
            .unwrap();
        assert!(!rep.still);
        assert_eq!(rep.moved as usize, N);
        // Ranges are unchanged by a rotation about the sensor.
        for r in out.ranges_m().iter().filter(|r| r.is_finite()) {
            assert!((r - 2.0).abs() < 1e-5, "{r}");
        }
        // The sweep is compressed in bearing by 10°·(360/348) over the turn: some bins empty,
        // none of them near the start anchor (f ≈ 0 there).
        assert!(rep.collided > 0);
        assert!(out.ranges_m()[0].is_finite());
    }

    #[test]
    fn bad_inputs_are_typed_errors_and_leave_a_copy() {
        let l = layout(SensorMount::CENTERED);
        let d = Deskewer::new(&l).unwrap();
        let scan = ring();
        let p = Pose::new(0.0, 0.0, 0.0);
        let mut out = Scan::default();
        let nan = Pose::new(f32::NAN, 0.0, 0.0);
        assert_eq!(
            d.apply(&l, &scan, &sweep(p, nan, p), &mut out),
            Err(DeskewError::NonFinitePose)
        );
        assert_eq!(out.len(), scan.len());
        let mut sw = sweep(p, Pose::new(0.1, 0.0, 0.0), p);
        sw.end_deg = sw.start_deg;
        assert_eq!(
            d.apply(&l, &scan, &sw, &mut out),
            Err(DeskewError::BadAnchors)
        );
        sw.end_deg = f32::NAN;
        assert_eq!(
            d.apply(&l, &scan, &sw, &mut out),
            Err(DeskewError::BadAnchors)
        );
    }

    #[test]
    fn readings_without_endpoint_stay_unless_covered() {
        let l = layout(SensorMount::CENTERED);
        let d = Deskewer::new(&l).unwrap();
        let scan = ring();
        let start = Pose::new(0.0, 0.0, 0.0);
        let end = Pose::new(0.05, 0.0, 0.0);
        let mut out = Scan::default();
        let rep = d
            .apply(&l, &scan, &sweep(start, end, start), &mut out)
            .unwrap();
        let kept = out.ranges_m().iter().filter(|r| r.is_finite()).count();
        assert!(kept > 0 && rep.moved > 0);
        // A NaN scan de-skews to a NaN scan.
        let mut nan = Scan::<N>::default();
        for _ in 0..N {
            nan.push(f32::NAN).unwrap();
        }
        let rep = d
            .apply(&l, &nan, &sweep(start, end, start), &mut out)
            .unwrap();
        assert_eq!(rep.moved, 0);
        assert!(out.ranges_m().iter().all(|r| r.is_nan()));
    }
}
