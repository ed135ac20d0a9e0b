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
//!   each other in the bins, in fixed memory. (With the sensor's own timestamps
//!   ([`AssemblerConfig::sensor_timestamps`]), a gap between two points longer
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
//!   revolution (when the protocol has timestamps), and [`ScanAssembler::timing`] the rotor
//!   positions those stamps belong to, so a caller can de-skew with odometry
//!   ([`crate::lidar::deskew`]).
//!
//! The layout must be evenly spaced (any start, any positive step, up to a full turn): binning is
//! then one multiply per point, with no search.

use super::{bump, LidarPoint};
use crate::scan::{BeamLayout, Scan};

mod bins;
mod config;
#[cfg(test)]
mod tests;

pub(crate) use bins::Bins;
pub use bins::{full_turn_layout, sample_revolution};
pub use config::{AssemblerConfig, AssemblerError, AssemblerStats, Revolution, RevolutionTiming};

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
    /// Position of the first point that carried the pending revolution's latest timestamp (for
    /// [`ScanAssembler::timing`]: a frame's stamp is its first point's time).
    rev_stamp: Option<(f32, u16)>,
    /// Rotation rate learnt from the last whole revolution, degrees per millisecond.
    rate_deg_per_ms: Option<f32>,
    out: Scan<N>,
    last: Revolution,
    last_timing: Option<RevolutionTiming>,
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
            rev_stamp: None,
            rate_deg_per_ms: None,
            out,
            last: Revolution::default(),
            last_timing: None,
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
            if self.rev_stamp.is_none_or(|(_, s)| s != t) {
                self.rev_stamp = Some((self.pos_deg, t));
            }
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
    /// when both points carry timestamps of the sensor
    /// ([`AssemblerConfig::sensor_timestamps`]) and a rotation rate is known, whole turns are
    /// added so that the advance is the one nearest to `rate · Δt` (data lost for more than half
    /// a turn cannot hide a wrap).
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
        if !self.config.sensor_timestamps {
            // A receiver's stamps, per chunk: they count no turn.
            return self.settle(a, da);
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
        self.last_timing = match (self.rev_first, self.rev_stamp) {
            (Some((p0, t0)), Some((p1, t1))) if p1 > p0 => Some(RevolutionTiming {
                start_deg: p0,
                start_timestamp_ms: t0,
                end_deg: p1,
                end_timestamp_ms: t1,
            }),
            _ => None,
        };
        self.next_index = self.next_index.wrapping_add(1);
        bump(&mut self.stats.revolutions);
        self.filled = 0;
        self.rev_points = 0;
        self.rev_first = None;
        self.rev_last = None;
        self.rev_stamp = None;
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

    /// When the last emitted scan's beams were measured: the rotor positions at which its first
    /// and last timestamps were taken (`None` without two distinct timestamped positions, e.g.
    /// a protocol without timestamps, or a revolution of a single frame). See
    /// [`RevolutionTiming`].
    pub fn timing(&self) -> Option<RevolutionTiming> {
        self.last_timing
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
        self.rev_stamp = None;
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
