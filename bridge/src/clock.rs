//! The device's clock (µs since it started) on the computer's clock, for `--clock host`.
//!
//! [`HostClock`] maps device time to host time with an offset: the smallest
//! `arrival − device time` over a sliding window of recent messages ([`WINDOW_NS`]), so that a
//! message that waited in a buffer does not push the stamps later, and a device clock that runs
//! slow or fast against the computer's is followed within the window's length.
//!
//! A message whose `arrival − device time` disagrees with the offset by more than
//! [`JUMP_NS`] is not stamped with the old offset. It is held as a candidate: when
//! [`CONFIRM`] consecutive such messages agree with each other (within [`JUMP_NS`]) and span at
//! least [`CONFIRM_SPAN_NS`] of device time, the clock re-anchors on them (a device restart, a
//! stall, a jump of its clock). One that is followed by a message agreeing with the old offset
//! is dropped as an outlier. A stamp that is not later than the last one given out is refused.
//! Every cause is counted ([`ClockCounters`]).

use std::collections::VecDeque;

use serde::Serialize;

use crate::msg::Time;

/// How far back the offset's minimum looks, ns of host time.
pub const WINDOW_NS: i128 = 5_000_000_000;
/// A disagreement with the offset above this, ns, is a jump or an outlier.
pub const JUMP_NS: i128 = 500_000_000;
/// Consecutive agreeing messages that confirm a jump.
pub const CONFIRM: usize = 3;
/// The device time the confirming messages must span at least, ns.
pub const CONFIRM_SPAN_NS: i128 = 100_000_000;
/// The most offsets the window keeps (a flood of messages within [`WINDOW_NS`]).
pub const WINDOW_CAPACITY: usize = 1024;

/// What [`HostClock`] did, by cause. Each is a count of messages.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ClockCounters {
    /// Re-anchored: the device's clock jumped ahead of the computer's.
    pub jump_forward: u64,
    /// Re-anchored: the device's clock fell behind the computer's while still counting up (a
    /// stall: the device paused, its clock with it).
    pub jump_back: u64,
    /// Re-anchored: the device's time went back (the device restarted).
    pub restart: u64,
    /// Messages that disagreed with the clock and were not confirmed by the next ones.
    pub outlier_dropped: u64,
    /// Messages held while a jump was being confirmed (not stamped).
    pub held_confirming: u64,
    /// Stamps refused because they were not later than the last one given out.
    pub non_increasing_refused: u64,
}

/// Why a message got no stamp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoStamp {
    /// It disagrees with the clock: held until the next ones confirm or refute it.
    Confirming,
    /// Its stamp would not be later than the last one given out.
    NonIncreasing,
}

/// One message's offset on the window.
#[derive(Clone, Copy, Debug)]
struct Sample {
    arrival_ns: i128,
    offset_ns: i128,
}

/// A message that disagrees with the current offset.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    arrival_ns: i128,
    device_ns: i128,
    offset_ns: i128,
}

/// The device's clock on the computer's (see the module's documentation).
#[derive(Clone, Debug, Default)]
pub struct HostClock {
    /// Offsets, increasing from front to back (a minimum queue): the front is the window's
    /// smallest.
    window: VecDeque<Sample>,
    candidates: Vec<Candidate>,
    /// The device time of the last message taken into the window, ns.
    last_device_ns: Option<i128>,
    /// The last stamp given out, ns since the Unix epoch.
    last_stamp_ns: Option<i128>,
    pub counters: ClockCounters,
}

impl HostClock {
    pub fn new() -> Self {
        Self::default()
    }

    /// The current offset (host − device), ns; `None` before the first message.
    pub fn offset_ns(&self) -> Option<i128> {
        self.window.front().map(|s| s.offset_ns)
    }

    fn push(&mut self, arrival_ns: i128, offset_ns: i128) {
        while self.window.back().is_some_and(|b| b.offset_ns >= offset_ns) {
            self.window.pop_back();
        }
        self.window.push_back(Sample {
            arrival_ns,
            offset_ns,
        });
        while self.window.len() > WINDOW_CAPACITY
            || self
                .window
                .front()
                .is_some_and(|f| arrival_ns.saturating_sub(f.arrival_ns) > WINDOW_NS)
        {
            self.window.pop_front();
        }
    }

    /// Takes a message stamped `device_us` (µs on the device's clock) that arrived at
    /// `arrival_ns` (ns since the Unix epoch on the computer's clock) and returns its stamp on
    /// the computer's clock, never later than `arrival_ns` and always later than the last stamp
    /// returned; or why it gets none.
    pub fn stamp(&mut self, device_us: u64, arrival_ns: u64) -> Result<Time, NoStamp> {
        let device_ns = i128::from(device_us) * 1000;
        let arrival_ns = i128::from(arrival_ns);
        let seen = arrival_ns - device_ns;
        match self.offset_ns() {
            None => {
                self.push(arrival_ns, seen);
                self.last_device_ns = Some(device_ns);
            }
            Some(off) if (seen - off).abs() <= JUMP_NS => {
                // Agrees: any pending candidates were outliers.
                self.counters.outlier_dropped += self.candidates.len() as u64;
                self.candidates.clear();
                self.push(arrival_ns, seen);
                self.last_device_ns = Some(device_ns);
            }
            Some(off) => {
                let c = Candidate {
                    arrival_ns,
                    device_ns,
                    offset_ns: seen,
                };
                let agrees = self
                    .candidates
                    .iter()
                    .all(|p| (p.offset_ns - seen).abs() <= JUMP_NS && p.device_ns < device_ns);
                if !agrees {
                    self.counters.outlier_dropped += self.candidates.len() as u64;
                    self.candidates.clear();
                }
                self.candidates.push(c);
                let first = self.candidates[0];
                if self.candidates.len() < CONFIRM || device_ns - first.device_ns < CONFIRM_SPAN_NS
                {
                    self.counters.held_confirming += 1;
                    return Err(NoStamp::Confirming);
                }
                // Confirmed: re-anchor on the candidates.
                if self.last_device_ns.is_some_and(|d| first.device_ns < d) {
                    self.counters.restart += 1;
                } else if seen < off {
                    self.counters.jump_forward += 1;
                } else {
                    self.counters.jump_back += 1;
                }
                // The earlier candidates were held, not stamped.
                self.window.clear();
                for p in std::mem::take(&mut self.candidates) {
                    self.push(p.arrival_ns, p.offset_ns);
                }
                self.last_device_ns = Some(device_ns);
            }
        }
        let off = self.offset_ns().unwrap_or(seen);
        let stamp = (device_ns + off).clamp(0, i128::from(i32::MAX) * 1_000_000_000);
        if self.last_stamp_ns.is_some_and(|l| stamp <= l) {
            self.counters.non_increasing_refused += 1;
            return Err(NoStamp::NonIncreasing);
        }
        self.last_stamp_ns = Some(stamp);
        Ok(Time::from_nanos(stamp as u64))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: u64 = 1_000_000_000;
    /// The computer's clock at the device's start, ns since the epoch.
    const HOST0: u64 = 1_700_000_000 * S;

    fn ns(t: Time) -> u64 {
        t.to_nanos().unwrap()
    }

    /// Feeds estimates at 10 Hz: `device_us(k)` and `arrival(k)` (ns); returns the stamps
    /// (None: refused) with their arrivals.
    fn feed(
        c: &mut HostClock,
        n: u64,
        device_us: impl Fn(u64) -> u64,
        arrival: impl Fn(u64) -> u64,
    ) -> Vec<(u64, Option<u64>)> {
        (0..n)
            .map(|k| {
                let a = arrival(k);
                (a, c.stamp(device_us(k), a).ok().map(ns))
            })
            .collect()
    }

    /// Stamps strictly increasing, each at most `max_lag_ns` before its arrival and never
    /// after it, from the `from`-th on.
    fn check(out: &[(u64, Option<u64>)], from: usize, max_lag_ns: u64) {
        let mut last = 0;
        for (i, (a, s)) in out.iter().enumerate() {
            if let Some(s) = s {
                assert!(*s > last, "stamp {i} not increasing: {s} after {last}");
                last = *s;
                assert!(s <= a, "stamp {i} after its arrival: {s} > {a}");
                if i >= from {
                    assert!(a - s <= max_lag_ns, "stamp {i}: {} ns behind", a - s);
                }
            }
        }
    }

    #[test]
    fn takes_the_smallest_delay() {
        let mut c = HostClock::new();
        // Device at 1 s arrives at host 100 s + 5 ms; then device 2 s at host 101 s + 1 ms.
        assert_eq!(
            c.stamp(1_000_000, 100_005_000_000).map(ns),
            Ok(100_005_000_000)
        );
        assert_eq!(
            c.stamp(2_000_000, 101_001_000_000).map(ns),
            Ok(101_001_000_000)
        );
        // Later stamps use the smaller offset (99.001 s).
        assert_eq!(
            c.stamp(3_000_000, 102_500_000_000).map(ns),
            Ok(102_001_000_000)
        );
        assert_eq!(c.counters, ClockCounters::default());
    }

    #[test]
    fn one_stamp_far_ahead_is_dropped_not_followed() {
        let mut c = HostClock::new();
        let dev = |k: u64| {
            if k == 20 {
                1_000_000_000_000_000
            } else {
                k * 100_000
            }
        };
        let out = feed(&mut c, 60, dev, |k| HOST0 + k * S / 10 + 2_000_000);
        assert_eq!(out[20].1, None);
        check(&out, 0, 3_000_000);
        assert_eq!(out.iter().filter(|o| o.1.is_none()).count(), 1);
        assert_eq!(c.counters.outlier_dropped, 1);
        assert_eq!(c.counters.jump_forward, 0);
    }

    #[test]
    fn a_restart_re_anchors_within_three_estimates() {
        let mut c = HostClock::new();
        // 30 s of uptime, then the device restarts: its clock is back at 0.
        let dev = |k: u64| {
            if k < 300 {
                k * 100_000
            } else {
                (k - 300) * 100_000
            }
        };
        let out = feed(&mut c, 400, dev, |k| HOST0 + k * S / 10 + 1_000_000);
        check(&out, 303, 2_000_000);
        assert_eq!(c.counters.restart, 1);
        assert_eq!(c.counters.held_confirming, 2);
        assert!(out[303..].iter().all(|o| o.1.is_some()));
    }

    #[test]
    fn a_stall_re_anchors() {
        let mut c = HostClock::new();
        // The device (and its clock) pauses 14.6 s after estimate 100.
        let arrival = |k: u64| HOST0 + k * S / 10 + if k > 100 { 14_600_000_000 } else { 0 };
        let out = feed(&mut c, 200, |k| k * 100_000, arrival);
        check(&out, 104, 1_000_000);
        assert_eq!(c.counters.jump_back, 1);
        assert_eq!(c.counters.restart, 0);
    }

    #[test]
    fn a_device_clock_jumping_ahead_re_anchors() {
        let mut c = HostClock::new();
        let dev = |k: u64| k * 100_000 + if k >= 50 { 3_600 * 1_000_000 } else { 0 };
        let out = feed(&mut c, 120, dev, |k| HOST0 + k * S / 10 + 3_000_000);
        check(&out, 53, 3_000_000);
        assert_eq!(c.counters.jump_forward, 1);
    }

    #[test]
    fn a_slow_device_clock_is_followed() {
        let mut c = HostClock::new();
        // 0.5 % slow for 10 minutes, with delays of 1 to 9 ms.
        let dev = |k: u64| k * 99_500;
        let out = feed(&mut c, 6_000, dev, |k| {
            HOST0 + k * S / 10 + 1_000_000 + (k % 9) * 1_000_000
        });
        // The window's oldest offset is at most 5 s × 0.5 % = 25 ms stale.
        check(&out, 0, 40_000_000);
        assert!(out.iter().all(|o| o.1.is_some()));
        assert_eq!(c.counters, ClockCounters::default());
    }

    #[test]
    fn a_repeated_device_time_is_refused() {
        let mut c = HostClock::new();
        assert!(c.stamp(1_000_000, HOST0).is_ok());
        assert_eq!(
            c.stamp(1_000_000, HOST0 + 1_000),
            Err(NoStamp::NonIncreasing)
        );
        assert_eq!(c.counters.non_increasing_refused, 1);
    }

    #[test]
    fn extreme_times_saturate() {
        let mut c = HostClock::new();
        assert!(c.stamp(u64::MAX, u64::MAX).is_ok());
        let mut c = HostClock::new();
        assert_eq!(c.stamp(u64::MAX, 0).map(ns), Ok(0));
        assert_eq!(c.stamp(u64::MAX, 5), Err(NoStamp::NonIncreasing));
    }
}
