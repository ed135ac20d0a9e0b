//! Points of a spinning LiDAR → one [`Scan<N>`] per revolution, on a caller's [`BeamLayout<N>`].
//!
//! # Rules
//! - **Angles.** A point's clockwise sensor angle `a` (degrees, `[0, 360)`) becomes the
//!   counter-clockwise bearing `−a` of the crate's convention (see [`crate::pose`]); the layout's
//!   bearings are relative to the sensor's zero direction, and its [`SensorMount`](crate::pose::SensorMount) places the
//!   sensor on the robot as for any other scan.
//! - **Revolutions.** A revolution ends when the angle wraps: a point whose angle is more than
//!   180° below the previous point's. That point opens the next revolution, so a scan never
//!   mixes two revolutions. Every point (flagged invalid ones included) moves the rotor angle.
//!   A stopped motor never wraps and therefore never emits a scan; its points keep replacing
//!   each other in the bins, in fixed memory. (With timestamps, a gap between two points longer
//!   than half a turn at the learnt rate is read as turns gone by: the revolution is closed, on
//!   the safe side, even if the motor had in fact stopped during the gap.) The first revolution after [`ScanAssembler::new`]
//!   or [`ScanAssembler::reset`] is usually partial: its unvisited beams are NaN, like every
//!   empty bin. [`ScanAssembler::finish`] emits a pending revolution at the end of a recording.
//! - **Binning.** Each accepted point goes to the beam nearest to its bearing, provided it lies
//!   within half a beam step of it (otherwise it is outside the layout's field of view and is
//!   counted in [`AssemblerStats::outside_layout`]). When two points of one revolution fall on
//!   the same beam, the one nearer to the beam's bearing is kept (the earlier one on a tie); the
//!   other is counted in [`AssemblerStats::replaced`].
//! - **Acceptance.** A point is accepted when the sensor flagged it valid, its range is within
//!   `[min_range_m, max_range_m]` and its quality is at least `min_quality`
//!   ([`AssemblerConfig`]); otherwise it only moves the rotor angle and is counted.
//! - **Empty beams** read NaN ([`crate::scan::Reading::Invalid`]): skipped and counted by every
//!   model.
//! - **Time.** [`Revolution`] carries the sensor timestamps of the first and last points of the
//!   revolution (when the protocol has timestamps), so a caller can de-skew with odometry.
//!
//! The layout must be evenly spaced (any start, any positive step, up to a full turn): binning is
//! then one multiply per point, with no search.

use super::{bump, LidarPoint};
use crate::scan::{BeamLayout, Scan};

/// Why an assembler could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AssemblerError {
    /// The layout's bearings are not evenly spaced with a positive step (index of the first beam
    /// that is off).
    NotUniform(usize),
    /// The layout's beams span more than one turn.
    MoreThanOneTurn,
    /// A range threshold that is NaN, negative, or a minimum above the maximum.
    BadRange,
}

impl core::fmt::Display for AssemblerError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NotUniform(i) => write!(f, "layout bearing {i} is not evenly spaced"),
            Self::MoreThanOneTurn => f.write_str("layout spans more than one turn"),
            Self::BadRange => f.write_str("range thresholds must satisfy 0 <= min <= max"),
        }
    }
}

impl core::error::Error for AssemblerError {}

/// Per-sensor acceptance thresholds.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AssemblerConfig {
    /// Points nearer than this are rejected, metres (the LD06 is specified from 0.02 m).
    pub min_range_m: f32,
    /// Points farther than this are rejected, metres.
    pub max_range_m: f32,
    /// Points whose quality (protocol units) is below this are rejected.
    pub min_quality: u16,
    /// The point timestamps wrap to 0 at this many milliseconds (LD06: 30,000; a caller that
    /// stamps points with its own `u16` millisecond clock: 0, meaning 65,536).
    pub timestamp_wrap_ms: u16,
}

impl AssemblerConfig {
    /// Accepts every valid point from 0 up to the layout's maximum range, any quality.
    pub fn for_layout<const N: usize>(layout: &BeamLayout<N>) -> Self {
        Self {
            min_range_m: 0.0,
            max_range_m: layout.max_range_m(),
            min_quality: 0,
            timestamp_wrap_ms: super::ld06::TIMESTAMP_WRAP_MS,
        }
    }
}

/// Counters of an assembler, readable at any time. Every pushed point is counted once in
/// `points` and once in exactly one of `accepted`, `flagged_invalid`, `out_of_range`,
/// `low_quality`, `bad_angle`, `outside_layout`; every accepted point ends up in a bin of an
/// emitted scan, in `replaced`, or in the pending revolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AssemblerStats {
    /// Points pushed.
    pub points: u32,
    /// Points stored in a bin.
    pub accepted: u32,
    /// Points the sensor flagged as no measurement.
    pub flagged_invalid: u32,
    /// Valid points outside `[min_range_m, max_range_m]` (or with a NaN range).
    pub out_of_range: u32,
    /// Valid points in range below the quality threshold.
    pub low_quality: u32,
    /// Points whose angle is not in `[0, 360)` (NaN included); they do not move the rotor angle.
    pub bad_angle: u32,
    /// Accepted-quality points farther than half a step from every beam.
    pub outside_layout: u32,
    /// Accepted points displaced from their bin by a point nearer to the beam's bearing (or
    /// that lost to an earlier one).
    pub replaced: u32,
    /// Scans emitted.
    pub revolutions: u32,
    /// Whole turns that went by without a single point (data lost across the wrap for longer
    /// than a turn, detected from the timestamps).
    pub missed_revolutions: u32,
}

/// What is known about the last emitted revolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Revolution {
    /// Sequence number of the revolution, from 0.
    pub index: u32,
    /// Points pushed during the revolution (all of them, accepted or not).
    pub points: u32,
    /// Beams that received a point (the others are NaN).
    pub filled: u16,
    /// Sensor timestamp of the first point, milliseconds (protocol clock), if it has one.
    pub start_timestamp_ms: Option<u16>,
    /// Sensor timestamp of the last point, milliseconds, if it has one.
    pub end_timestamp_ms: Option<u16>,
}

/// Assembles LiDAR points into one scan per revolution. See the module docs for the rules.
#[derive(Clone, Debug)]
pub struct ScanAssembler<const N: usize> {
    config: AssemblerConfig,
    bins: Bins,
    /// The pending revolution's ranges and each one's distance to its beam, in steps.
    bins_m: [f32; N],
    offsets: [f32; N],
    filled: u16,
    rev_points: u32,
    /// Angle and timestamp of the previous point.
    prev_angle_deg: f32,
    prev_ms: Option<u16>,
    /// Rotor position within the pending revolution, degrees clockwise from the sensor's 0°
    /// (slightly negative after a backward jitter across 0°).
    pos_deg: f32,
    /// Position and timestamp of the pending revolution's first and last timestamped points.
    rev_first: Option<(f32, u16)>,
    rev_last: Option<(f32, u16)>,
    /// Rotation rate learnt from the last whole revolution, degrees per millisecond.
    rate_deg_per_ms: Option<f32>,
    out: Scan<N>,
    last: Revolution,
    next_index: u32,
    stats: AssemblerStats,
}

impl<const N: usize> ScanAssembler<N> {
    /// An assembler for `layout` (copied: the assembler keeps no reference to it).
    ///
    /// # Errors
    /// [`AssemblerError::NotUniform`] when the bearings are not evenly spaced (to 1e-4 rad) with
    /// a positive step, [`AssemblerError::MoreThanOneTurn`], [`AssemblerError::BadRange`].
    pub fn new(layout: &BeamLayout<N>, config: AssemblerConfig) -> Result<Self, AssemblerError> {
        if !(config.min_range_m >= 0.0 && config.max_range_m >= config.min_range_m) {
            return Err(AssemblerError::BadRange);
        }
        let bins = Bins::new(layout)?;
        let mut out = Scan::default();
        for _ in 0..bins.beams {
            // Capacity N ≥ beams.len(): cannot fail.
            let _ = out.push(f32::NAN);
        }
        Ok(Self {
            config,
            bins,
            bins_m: [f32::NAN; N],
            offsets: [f32::INFINITY; N],
            filled: 0,
            rev_points: 0,
            prev_angle_deg: f32::NAN,
            prev_ms: None,
            pos_deg: 0.0,
            rev_first: None,
            rev_last: None,
            rate_deg_per_ms: None,
            out,
            last: Revolution::default(),
            next_index: 0,
            stats: AssemblerStats::default(),
        })
    }

    /// Adds one point. Returns the finished scan when this point opened a new revolution (the
    /// point itself belongs to the new one).
    #[inline]
    pub fn push(&mut self, point: LidarPoint) -> Option<&Scan<N>> {
        bump(&mut self.stats.points);
        let a = point.angle_cw_deg;
        if !(0.0..360.0).contains(&a) {
            bump(&mut self.stats.bad_angle);
            return None;
        }
        let turns = self.advance(a, point.timestamp_ms);
        if turns > 0 {
            self.close(turns);
        }
        self.rev_points = self.rev_points.saturating_add(1);
        if let Some(t) = point.timestamp_ms {
            if self.rev_first.is_none() {
                self.rev_first = Some((self.pos_deg, t));
            }
            self.rev_last = Some((self.pos_deg, t));
        }
        self.bin(&point, a);
        if turns > 0 {
            Some(&self.out)
        } else {
            None
        }
    }

    /// Moves the rotor to angle `a` (stamped `t`), returns how many times it crossed 0°.
    ///
    /// The advance from the previous point is the signed angle difference in `(−180°, 180°]`;
    /// when both points carry timestamps and a rotation rate is known, whole turns are added so
    /// that the advance is the one nearest to `rate · Δt` (data lost for more than half a turn
    /// cannot hide a wrap).
    #[inline(always)]
    fn advance(&mut self, a: f32, t: Option<u16>) -> u32 {
        let prev = core::mem::replace(&mut self.prev_angle_deg, a);
        let prev_ms = core::mem::replace(&mut self.prev_ms, t);
        if prev.is_nan() {
            self.pos_deg = a;
            return 0;
        }
        let mut da = a - prev;
        if da > 180.0 {
            da -= 360.0;
        } else if da <= -180.0 {
            da += 360.0;
        }
        // Points of one frame share a timestamp (Δt = 0 adds no turn): skip the arithmetic.
        if let (Some(t), Some(tp), Some(rate)) = (t, prev_ms, self.rate_deg_per_ms) {
            if t == tp {
                return self.settle(a, da);
            }
            let dt = elapsed_ms(tp, t, self.config.timestamp_wrap_ms);
            // rate·dt − da ≥ −180, so the sum is ≥ 0 and truncation rounds to nearest.
            let extra = ((rate * dt as f32 - da) * (1.0 / 360.0) + 0.5) as u32;
            da += 360.0 * extra as f32;
        }
        self.settle(a, da)
    }

    /// Moves the rotor by `da` to angle `a`; returns the crossings of 0°.
    #[inline(always)]
    fn settle(&mut self, a: f32, da: f32) -> u32 {
        let pos = self.pos_deg + da;
        // pos − a is a whole number of turns up to rounding: find it (≥ −1 by construction).
        let k = ((pos - a) * (1.0 / 360.0) + 1.5) as u32;
        if k >= 1 {
            self.pos_deg = a;
            k - 1
        } else {
            self.pos_deg = (a - 360.0).max(-180.0);
            0
        }
    }

    fn bin(&mut self, point: &LidarPoint, a: f32) {
        if !point.valid {
            bump(&mut self.stats.flagged_invalid);
            return;
        }
        let r = point.range_m;
        if !(r >= self.config.min_range_m && r <= self.config.max_range_m) {
            bump(&mut self.stats.out_of_range);
            return;
        }
        if point.quality < self.config.min_quality {
            bump(&mut self.stats.low_quality);
            return;
        }
        let Some((idx, off)) = self.bins.nearest(a) else {
            bump(&mut self.stats.outside_layout);
            return;
        };
        bump(&mut self.stats.accepted);
        if let (Some(bin), Some(o)) = (self.bins_m.get_mut(idx), self.offsets.get_mut(idx)) {
            if off < *o {
                if o.is_finite() {
                    bump(&mut self.stats.replaced);
                } else {
                    self.filled = self.filled.saturating_add(1);
                }
                *bin = r;
                *o = off;
            } else {
                bump(&mut self.stats.replaced);
            }
        }
    }

    /// Moves the pending revolution to the output scan and starts an empty one (`turns` ≥ 1
    /// crossings of 0° ended it).
    fn close(&mut self, turns: u32) {
        if turns == 1 {
            if let (Some((p0, t0)), Some((p1, t1))) = (self.rev_first, self.rev_last) {
                let dt = elapsed_ms(t0, t1, self.config.timestamp_wrap_ms);
                if p1 - p0 >= 180.0 && dt > 0 {
                    self.rate_deg_per_ms = Some((p1 - p0) / dt as f32);
                }
            }
        } else {
            self.stats.missed_revolutions = self.stats.missed_revolutions.saturating_add(turns - 1);
        }
        let n = self.bins.beams;
        if let (Some(dst), Some(src), Some(offs)) = (
            self.out.ranges_m_mut().get_mut(..n),
            self.bins_m.get_mut(..n),
            self.offsets.get_mut(..n),
        ) {
            dst.copy_from_slice(src);
            src.fill(f32::NAN);
            offs.fill(f32::INFINITY);
        }
        self.last = Revolution {
            index: self.next_index,
            points: self.rev_points,
            filled: self.filled,
            start_timestamp_ms: self.rev_first.map(|(_, t)| t),
            end_timestamp_ms: self.rev_last.map(|(_, t)| t),
        };
        self.next_index = self.next_index.wrapping_add(1);
        bump(&mut self.stats.revolutions);
        self.filled = 0;
        self.rev_points = 0;
        self.rev_first = None;
        self.rev_last = None;
    }

    /// Emits the pending revolution, if it received any point (for the end of a recording; a
    /// live stream emits from [`ScanAssembler::push`]). The assembler then waits for a new
    /// revolution, as after a wrap.
    pub fn finish(&mut self) -> Option<&Scan<N>> {
        if self.rev_points == 0 {
            return None;
        }
        self.close(1);
        self.prev_angle_deg = f32::NAN;
        self.prev_ms = None;
        Some(&self.out)
    }

    /// The last emitted scan (all NaN before the first one).
    pub fn scan(&self) -> &Scan<N> {
        &self.out
    }

    /// What is known about the last emitted scan's revolution.
    pub fn revolution(&self) -> Revolution {
        self.last
    }

    /// Counters so far.
    pub fn stats(&self) -> AssemblerStats {
        self.stats
    }

    /// Points received in the pending (not yet emitted) revolution.
    pub fn pending_points(&self) -> u32 {
        self.rev_points
    }

    /// Beams filled in the pending revolution.
    pub fn pending_filled(&self) -> u16 {
        self.filled
    }

    /// Drops the pending revolution and the counters; the next point opens a new revolution.
    pub fn reset(&mut self) {
        self.bins_m.fill(f32::NAN);
        self.offsets.fill(f32::INFINITY);
        self.filled = 0;
        self.rev_points = 0;
        self.rev_first = None;
        self.rev_last = None;
        self.prev_angle_deg = f32::NAN;
        self.prev_ms = None;
        self.rate_deg_per_ms = None;
        self.stats = AssemblerStats::default();
    }
}

/// Milliseconds from `from` to `to` on a clock that wraps at `wrap` (0: 65,536). A timestamp
/// at or past `wrap` (impossible for the sensor) is read on the 65,536 clock.
fn elapsed_ms(from: u16, to: u16, wrap: u16) -> u32 {
    let (from, to) = (u32::from(from), u32::from(to));
    let wrap = if wrap == 0 || from >= u32::from(wrap) || to >= u32::from(wrap) {
        65_536
    } else {
        u32::from(wrap)
    };
    if to >= from {
        to - from
    } else {
        to + wrap - from
    }
}

/// The geometry of a uniform layout, in degrees, for nearest-beam lookups.
#[derive(Clone, Copy, Debug)]
struct Bins {
    beams: usize,
    /// Layout start, degrees counter-clockwise, in `[0, 360)`.
    first_deg: f32,
    /// Beams per degree.
    inv_step: f32,
    /// Beam steps in a full turn.
    steps_per_turn: f32,
}

impl Bins {
    fn new<const N: usize>(layout: &BeamLayout<N>) -> Result<Self, AssemblerError> {
        let beams = layout.beams();
        let first_rad = beams.first().map_or(0.0, |b| b.bearing_rad);
        let step_rad = match beams {
            [a, b, ..] => b.bearing_rad - a.bearing_rad,
            // One beam: a full-turn bin.
            _ => core::f32::consts::TAU,
        };
        if step_rad.is_nan() || step_rad <= 0.0 {
            return Err(AssemblerError::NotUniform(1));
        }
        for (i, b) in beams.iter().enumerate() {
            let want = first_rad + step_rad * i as f32;
            if (b.bearing_rad - want).abs() > 1e-4 {
                return Err(AssemblerError::NotUniform(i));
            }
        }
        let step_deg = step_rad.to_degrees();
        if step_deg * beams.len() as f32 > 360.0 + 1e-3 {
            return Err(AssemblerError::MoreThanOneTurn);
        }
        let mut first_deg = first_rad.to_degrees() % 360.0;
        if first_deg < 0.0 {
            first_deg += 360.0;
        }
        if first_deg >= 360.0 {
            first_deg = 0.0;
        }
        Ok(Self {
            beams: beams.len(),
            first_deg,
            inv_step: 1.0 / step_deg,
            steps_per_turn: 360.0 / step_deg,
        })
    }

    /// The beam nearest to the clockwise angle `a` (degrees, `[0, 360)`) and the distance to
    /// it in beam steps (≤ 0.5), or `None` when no beam is within half a step.
    #[inline(always)]
    fn nearest(&self, a: f32) -> Option<(usize, f32)> {
        // Bearing −a relative to the layout's first beam, brought into [0, 360].
        let mut rel = -a - self.first_deg; // in (−720, 0]
        rel += if rel < -360.0 { 720.0 } else { 360.0 };
        let mut k = rel * self.inv_step;
        // Within half a step below the first beam: measure from it, negatively.
        if k >= self.steps_per_turn - 0.5 {
            k -= self.steps_per_turn;
        }
        // k ≥ −0.5 here, so truncation is rounding to nearest.
        let idx = (k + 0.5) as usize;
        (idx < self.beams).then(|| (idx, (k - idx as f32).abs()))
    }
}

/// The inverse of assembly, for encoders and tests: the range a sensor turning clockwise would
/// report at each of `out.len()` evenly spaced angles (`out[k]` at `k · 360° / out.len()`
/// clockwise from the sensor's zero direction), read from `scan` on `layout`.
///
/// `out[k]` is the reading of the beam nearest to that angle when one lies within half a beam
/// step (the assembler's binning rule), NaN otherwise (the sensor sees nothing the scan covers).
/// A scan shorter than the layout reads NaN for its missing beams.
///
/// # Errors
/// As [`ScanAssembler::new`] for the layout.
pub fn sample_revolution<const N: usize>(
    layout: &BeamLayout<N>,
    scan: &Scan<N>,
    out: &mut [f32],
) -> Result<(), AssemblerError> {
    let bins = Bins::new(layout)?;
    let step_deg = 360.0 / out.len().max(1) as f32;
    for (k, o) in out.iter_mut().enumerate() {
        let a = k as f32 * step_deg;
        *o = bins
            .nearest(if a < 360.0 { a } else { 0.0 })
            .and_then(|(i, _)| scan.ranges_m().get(i).copied())
            .unwrap_or(f32::NAN);
    }
    Ok(())
}

/// The layout the LD06 family reports natively: 360 beams 1° apart, counter-clockwise from the
/// sensor's zero direction, for a sensor at `mount` (a convenience; any uniform layout works).
///
/// # Errors
/// As [`BeamLayout::uniform`].
pub fn full_turn_layout<const N: usize>(
    beams: usize,
    max_range_m: f32,
    mount: crate::pose::SensorMount,
) -> Result<BeamLayout<N>, crate::scan::ScanError> {
    let step = core::f32::consts::TAU / beams.max(1) as f32;
    BeamLayout::uniform(0.0, step, beams, max_range_m, mount)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::SensorMount;

    fn pt(angle_cw_deg: f32, range_m: f32) -> LidarPoint {
        LidarPoint {
            angle_cw_deg,
            range_m,
            quality: 100,
            valid: true,
            timestamp_ms: None,
        }
    }

    fn layout360() -> BeamLayout<360> {
        full_turn_layout(360, 12.0, SensorMount::CENTERED).unwrap()
    }

    #[test]
    fn clockwise_points_land_on_counter_clockwise_beams() {
        let layout = layout360();
        let mut a = ScanAssembler::new(&layout, AssemblerConfig::for_layout(&layout)).unwrap();
        // CW 90° is bearing −90° = 270° CCW → beam 270. CW 1° → beam 359. CW 0 → beam 0.
        assert!(a.push(pt(0.0, 1.0)).is_none());
        assert!(a.push(pt(1.0, 2.0)).is_none());
        assert!(a.push(pt(90.0, 3.0)).is_none());
        assert!(a.push(pt(180.0, 5.0)).is_none());
        assert!(a.push(pt(270.0, 6.0)).is_none());
        assert!(a.push(pt(359.6, 4.0)).is_none()); // 0.4° CCW: beam 0 would be nearer...
        let scan = a.push(pt(0.5, 9.0)).expect("wrap").clone();
        let r = scan.ranges_m();
        assert_eq!(r.len(), 360);
        assert_eq!(r[0], 1.0); // ...but the point exactly on beam 0 wins
        assert_eq!(r[359], 2.0);
        assert_eq!(r[270], 3.0);
        assert!(r[1].is_nan() && r[100].is_nan());
        let s = a.stats();
        assert_eq!(r[180], 5.0);
        assert_eq!(r[90], 6.0);
        assert_eq!((s.accepted, s.replaced, s.revolutions), (7, 1, 1));
        assert_eq!(a.revolution().filled, 5);
        assert_eq!(a.revolution().points, 6);
    }

    #[test]
    fn half_layout_and_out_of_view_points() {
        // The Intel/CARMEN layout: −90° .. +89°, 1° apart.
        let layout = BeamLayout::<180>::uniform(
            -core::f32::consts::FRAC_PI_2,
            1f32.to_radians(),
            180,
            50.0,
            SensorMount::CENTERED,
        )
        .unwrap();
        let mut a = ScanAssembler::new(&layout, AssemblerConfig::for_layout(&layout)).unwrap();
        a.push(pt(90.0, 1.0)); // bearing −90 → beam 0
        a.push(pt(271.0, 2.0)); // bearing −271 = +89 → beam 179
        a.push(pt(180.0, 3.0)); // behind: outside
        a.push(pt(90.4, 4.0)); // bearing −90.4: 0.4 step below beam 0 → beam 0, farther
        let scan = a.finish().unwrap();
        assert_eq!(scan.ranges_m()[0], 1.0);
        assert_eq!(scan.ranges_m()[179], 2.0);
        assert_eq!(a.stats().outside_layout, 1);
        assert_eq!(a.stats().replaced, 1);
    }

    #[test]
    fn stopped_motor_never_emits_and_thresholds_count() {
        let layout = layout360();
        let cfg = AssemblerConfig {
            min_range_m: 0.1,
            max_range_m: 5.0,
            min_quality: 10,
            timestamp_wrap_ms: 0,
        };
        let mut a = ScanAssembler::new(&layout, cfg).unwrap();
        for i in 0..100_000 {
            let mut p = pt(42.0 + (i % 3) as f32 * 0.01, 1.0);
            match i % 5 {
                0 => p.valid = false,
                1 => p.range_m = 0.05,
                2 => p.range_m = 6.0,
                3 => p.quality = 9,
                _ => {}
            }
            assert!(a.push(p).is_none());
        }
        assert!(a.push(pt(f32::NAN, 1.0)).is_none());
        assert!(a.push(pt(360.0, 1.0)).is_none());
        let s = a.stats();
        assert_eq!(s.revolutions, 0);
        assert_eq!(s.flagged_invalid, 20_000);
        assert_eq!(s.out_of_range, 40_000);
        assert_eq!(s.low_quality, 20_000);
        assert_eq!(s.accepted, 20_000);
        assert_eq!(s.bad_angle, 2);
        assert_eq!(a.pending_filled(), 1);
    }

    /// A 10 Hz rotor (3.6°/ms) seen through points 1° apart stamped with the time they were
    /// taken; `lost` is a range of point indices that never arrive.
    fn rotor(
        a: &mut ScanAssembler<360>,
        points: core::ops::Range<u32>,
        lost: core::ops::Range<u32>,
    ) -> Vec<(u32, Revolution, Vec<f32>)> {
        let mut out = Vec::new();
        for k in points {
            if lost.contains(&k) {
                continue;
            }
            let p = LidarPoint {
                angle_cw_deg: (k % 360) as f32,
                range_m: 1.0 + (k / 360) as f32, // the revolution's number, in metres
                quality: 1,
                valid: true,
                timestamp_ms: Some(((k as f32 / 3.6).round() as u32 % 30_000) as u16),
            };
            if a.push(p).is_some() {
                out.push((k, a.revolution(), a.scan().ranges_m().to_vec()));
            }
        }
        out
    }

    #[test]
    fn data_lost_across_the_wrap_never_mixes_revolutions() {
        let layout = layout360();
        let mut a = ScanAssembler::new(&layout, AssemblerConfig::for_layout(&layout)).unwrap();
        // Revolutions 0..3 whole; then points 3·360+170 .. 4·360+250 are lost: the angle goes
        // from 169° to 250°, which looks like a forward step within one turn.
        let got = rotor(&mut a, 0..6 * 360, 3 * 360 + 170..4 * 360 + 250);
        let ks: Vec<u32> = got.iter().map(|g| g.0).collect();
        assert_eq!(ks, vec![360, 720, 1080, 4 * 360 + 250, 5 * 360]);
        for (_, rev, ranges) in &got {
            let finite: Vec<f32> = ranges.iter().copied().filter(|r| r.is_finite()).collect();
            assert!(!finite.is_empty());
            assert!(
                finite.iter().all(|&r| r == finite[0]),
                "mixed revolutions in {rev:?}"
            );
        }
        // The revolution cut short by the loss holds its 170 points.
        assert_eq!(got[3].1.filled, 170);
        assert_eq!(got[3].1.points, 170);
        assert_eq!(a.stats().missed_revolutions, 0);
        // Whole turns lost are counted.
        let mut b = ScanAssembler::new(&layout, AssemblerConfig::for_layout(&layout)).unwrap();
        let got = rotor(&mut b, 0..9 * 360, 2 * 360 + 100..5 * 360 + 90);
        assert_eq!(
            got.iter().map(|g| g.0).collect::<Vec<_>>(),
            vec![360, 720, 5 * 360 + 90, 6 * 360, 7 * 360, 8 * 360]
        );
        assert_eq!(b.stats().missed_revolutions, 2);
    }

    #[test]
    fn rejects_bad_layouts_and_thresholds() {
        let m = SensorMount::CENTERED;
        let l = BeamLayout::<3>::from_bearings(&[0.0, 0.1, 0.3], 5.0, m).unwrap();
        assert_eq!(
            ScanAssembler::new(&l, AssemblerConfig::for_layout(&l)).err(),
            Some(AssemblerError::NotUniform(2))
        );
        let l = BeamLayout::<3>::from_bearings(&[0.0, -0.1, -0.2], 5.0, m).unwrap();
        assert!(ScanAssembler::new(&l, AssemblerConfig::for_layout(&l)).is_err());
        let l = BeamLayout::<3>::from_bearings(&[0.0, 3.0, 6.0], 5.0, m).unwrap();
        assert_eq!(
            ScanAssembler::new(&l, AssemblerConfig::for_layout(&l)).err(),
            Some(AssemblerError::MoreThanOneTurn)
        );
        let mut c = AssemblerConfig::for_layout(&l);
        c.min_range_m = f32::NAN;
        let l = layout360();
        assert_eq!(
            ScanAssembler::new(&l, c).err(),
            Some(AssemblerError::BadRange)
        );
    }
}
