//! The device's clock (µs since it started) as stamps: on the computer's clock for `--clock host`,
//! on its own for `--clock device`.
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
//!
//! [`DeviceClock`] (`--clock device`) keeps the device's own time as the stamps and uses the
//! computer's clock only to tell a restart or a jump from the passing of time; it then goes on
//! from the last stamp instead of going back or jumping.

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

/// What [`HostClock`] or [`DeviceClock`] did, by cause. Each is a count of messages.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ClockCounters {
    /// Re-anchored: the device's clock jumped ahead of the computer's.
    pub jump_forward: u64,
    /// Re-anchored: the device's clock fell behind the computer's while still counting up (a
    /// stall: the device paused, its clock with it). [`HostClock`] only: [`DeviceClock`]
    /// follows a stall.
    pub jump_back: u64,
    /// Re-anchored: the device's time went back (the device restarted, or its clock was set
    /// back).
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

/// The latest stamp a ROS time holds ([`Time::MAX`]), ns since the epoch.
const MAX_STAMP_NS: i128 = i32::MAX as i128 * 1_000_000_000 + 999_999_999;

/// A message that [`DeviceClock`] took: its device time and its arrival, ns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Taken {
    device_ns: i128,
    arrival_ns: i128,
}

/// The messages held by [`DeviceClock`] while a start or a jump is confirmed: the first and
/// the last of a run of messages that agree with each other.
#[derive(Clone, Copy, Debug)]
struct Run {
    first: Taken,
    last: Taken,
    len: usize,
}

/// Whether `next` follows `prev` on the device's clock: a later device time, advanced by at
/// most [`JUMP_NS`] more than the computer's clock advanced between their arrivals. A device
/// time that advanced less (a stall, a slow clock) follows.
fn follows(prev: Taken, next: Taken) -> bool {
    let device = next.device_ns - prev.device_ns;
    let host = next.arrival_ns - prev.arrival_ns;
    device > 0 && device - host <= JUMP_NS
}

/// What [`DeviceClock`] did the last time it re-anchored (a device restart or a jump of its
/// clock), for the warning line and the report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Reanchor {
    /// The device time of the last message stamped before, ns.
    pub from_device_ns: i128,
    /// The device time of the first message of the new run, ns.
    pub to_device_ns: i128,
    /// What is added to device time to make the stamps from there on, ns.
    pub shift_ns: i128,
}

/// `--clock device`: stamps on the device's own clock (device time, µs, as ns since the
/// epoch), that never go back and never jump ahead of the computer's clock by more than
/// [`JUMP_NS`] between two messages.
///
/// - **Start.** Nothing is stamped until [`CONFIRM`] messages that follow each other (see
///   below) and span [`CONFIRM_SPAN_NS`] of device time have come: one wild first stamp cannot
///   set the clock. The stamps are then the device's time as it is (shift 0).
/// - **Following.** A message follows the last one taken when its device time is later and
///   advanced at most [`JUMP_NS`] more than the computer's clock between their arrivals. A
///   device time that advanced less (a stall, a slow clock) follows: the device's clock is the
///   reference, not the computer's.
/// - **Jumps.** A message that does not follow (its time went back: a restart or its clock set
///   back; or it jumped ahead) is held. [`CONFIRM`] held messages that follow each other and
///   span [`CONFIRM_SPAN_NS`] re-anchor the clock: from then on the stamp is device time plus
///   a shift, chosen so that the run's first message is stamped the last stamp plus the
///   computer's time between the two arrivals (at least 1 ns). Stamps stay increasing and
///   continuous, and are no longer the device's time (the shift is in [`Self::shift_ns`] and
///   [`Self::last_reanchor`]). Held messages are not stamped ([`ClockCounters::held_confirming`]).
/// - **Outliers.** Held messages followed by one that follows the last taken are dropped
///   ([`ClockCounters::outlier_dropped`]).
///
/// Stamps saturate at 0 and [`Time::MAX`]; one not later than the last is refused
/// ([`ClockCounters::non_increasing_refused`]). No input panics.
#[derive(Clone, Debug, Default)]
pub struct DeviceClock {
    /// The last message taken (stamped, or refused only as non-increasing).
    last: Option<Taken>,
    /// Held messages.
    held: Option<Run>,
    /// Added to device time, ns.
    shift_ns: i128,
    /// The last stamp given out, ns.
    last_stamp_ns: Option<i128>,
    /// The last re-anchoring.
    pub last_reanchor: Option<Reanchor>,
    /// `restart` counts re-anchorings on a device time that went back, `jump_forward` on one
    /// that jumped ahead; `jump_back` stays 0 (a stall is followed, not re-anchored).
    pub counters: ClockCounters,
}

impl DeviceClock {
    pub fn new() -> Self {
        Self::default()
    }

    /// What is added to device time to make the stamps, ns (0 until a re-anchoring).
    pub fn shift_ns(&self) -> i128 {
        self.shift_ns
    }

    /// Takes a message stamped `device_us` (µs on the device's clock) that arrived at
    /// `arrival_ns` (ns on the computer's clock) and returns its stamp: device time plus
    /// [`Self::shift_ns`], always later than the last stamp returned; or why it gets none.
    pub fn stamp(&mut self, device_us: u64, arrival_ns: u64) -> Result<Time, NoStamp> {
        let m = Taken {
            device_ns: i128::from(device_us) * 1000,
            arrival_ns: i128::from(arrival_ns),
        };
        match self.last {
            Some(last) if follows(last, m) => {
                // Any held messages were outliers.
                if let Some(h) = self.held.take() {
                    self.counters.outlier_dropped += h.len as u64;
                }
            }
            _ => {
                let run = match self.held {
                    Some(h) if follows(h.last, m) => Run {
                        first: h.first,
                        last: m,
                        len: h.len.saturating_add(1),
                    },
                    other => {
                        if let Some(h) = other {
                            self.counters.outlier_dropped += h.len as u64;
                        }
                        Run {
                            first: m,
                            last: m,
                            len: 1,
                        }
                    }
                };
                if run.len < CONFIRM || m.device_ns - run.first.device_ns < CONFIRM_SPAN_NS {
                    self.held = Some(run);
                    self.counters.held_confirming += 1;
                    return Err(NoStamp::Confirming);
                }
                self.held = None;
                if let (Some(last), Some(stamp)) = (self.last, self.last_stamp_ns) {
                    // Re-anchor: the run's first message goes on from the last stamp by the
                    // computer's time between their arrivals.
                    let gap = (run.first.arrival_ns - last.arrival_ns).max(1);
                    self.shift_ns = stamp + gap - run.first.device_ns;
                    if run.first.device_ns < last.device_ns {
                        self.counters.restart += 1;
                    } else {
                        self.counters.jump_forward += 1;
                    }
                    self.last_reanchor = Some(Reanchor {
                        from_device_ns: last.device_ns,
                        to_device_ns: run.first.device_ns,
                        shift_ns: self.shift_ns,
                    });
                }
            }
        }
        self.last = Some(m);
        let stamp = (m.device_ns + self.shift_ns).clamp(0, MAX_STAMP_NS);
        if self.last_stamp_ns.is_some_and(|l| stamp <= l) {
            self.counters.non_increasing_refused += 1;
            return Err(NoStamp::NonIncreasing);
        }
        self.last_stamp_ns = Some(stamp);
        Ok(Time::from_nanos(u64::try_from(stamp).unwrap_or(u64::MAX)))
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

    /// What both clocks do: a stamp for a device time that arrived at `arrival_ns`.
    trait Stamps {
        fn stamp_at(&mut self, device_us: u64, arrival_ns: u64) -> Result<Time, NoStamp>;
    }

    impl Stamps for HostClock {
        fn stamp_at(&mut self, device_us: u64, arrival_ns: u64) -> Result<Time, NoStamp> {
            self.stamp(device_us, arrival_ns)
        }
    }

    impl Stamps for DeviceClock {
        fn stamp_at(&mut self, device_us: u64, arrival_ns: u64) -> Result<Time, NoStamp> {
            self.stamp(device_us, arrival_ns)
        }
    }

    /// Feeds `n` estimates: `device_us(k)` and `arrival(k)` (ns); returns the stamps (None:
    /// refused) with their arrivals.
    fn feed(
        c: &mut impl Stamps,
        n: u64,
        device_us: impl Fn(u64) -> u64,
        arrival: impl Fn(u64) -> u64,
    ) -> Vec<(u64, Option<u64>)> {
        (0..n)
            .map(|k| {
                let a = arrival(k);
                (a, c.stamp_at(device_us(k), a).ok().map(ns))
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

    /// Stamps strictly increasing, and each step between two published stamps at most
    /// `max_step_ns` more than the computer's time between their arrivals.
    fn check_device(out: &[(u64, Option<u64>)], max_step_ns: u64) {
        let stamped: Vec<(u64, u64)> = out.iter().filter_map(|(a, s)| s.map(|s| (*a, s))).collect();
        for w in stamped.windows(2) {
            let ((a0, s0), (a1, s1)) = (w[0], w[1]);
            assert!(s1 > s0, "stamp {s1} not after {s0}");
            assert!(
                (s1 - s0) <= (a1 - a0) + max_step_ns,
                "stamps {s0} -> {s1} for arrivals {a0} -> {a1}"
            );
        }
    }

    /// 10 Hz, 1 ms after the device's time on the computer's clock.
    fn at_10hz(k: u64) -> u64 {
        HOST0 + k * S / 10 + 1_000_000
    }

    #[test]
    fn device_stamps_are_the_device_time_once_three_agree() {
        let mut c = DeviceClock::new();
        let out = feed(&mut c, 50, |k| 5_000_000 + k * 100_000, at_10hz);
        // Two held while the start is confirmed, then the device's time as it is.
        assert_eq!(out[0].1, None);
        assert_eq!(out[1].1, None);
        for (k, o) in out.iter().enumerate().skip(2) {
            assert_eq!(o.1, Some((5_000_000 + k as u64 * 100_000) * 1000), "{k}");
        }
        assert_eq!(c.counters.held_confirming, 2);
        assert_eq!(c.shift_ns(), 0);
        assert_eq!(c.last_reanchor, None);
    }

    #[test]
    fn a_device_restart_continues_the_device_stamps() {
        let mut c = DeviceClock::new();
        // 30 s of uptime, then the device restarts: its clock is back at 0.
        let dev = |k: u64| {
            if k < 300 {
                30_000_000 + k * 100_000
            } else {
                (k - 300) * 100_000
            }
        };
        let out = feed(&mut c, 400, dev, at_10hz);
        check_device(&out, 0);
        assert_eq!(c.counters.restart, 1);
        assert_eq!(c.counters.jump_forward, 0);
        // Two held at the start, two while the restart was confirmed.
        assert_eq!(c.counters.held_confirming, 4);
        assert!(out[302..].iter().all(|o| o.1.is_some()));
        // The restart's first message would have come 0.1 s after the last stamp.
        let last_before = out[299].1.unwrap();
        assert_eq!(out[302].1, Some(last_before + 3 * S / 10));
        let r = c.last_reanchor.unwrap();
        assert_eq!(r.from_device_ns, (30_000_000 + 299 * 100_000) * 1000);
        assert_eq!(r.to_device_ns, 0);
        assert_eq!(c.shift_ns(), i128::from(last_before) + i128::from(S / 10));
    }

    #[test]
    fn a_device_clock_set_back_continues_the_device_stamps() {
        let mut c = DeviceClock::new();
        // The device's clock is set back 5 s at estimate 100, and goes on from there.
        let dev = |k: u64| 100_000_000 + k * 100_000 - if k >= 100 { 5_000_000 } else { 0 };
        let out = feed(&mut c, 200, dev, at_10hz);
        check_device(&out, 0);
        assert_eq!(c.counters.restart, 1);
        assert_eq!(out.iter().filter(|o| o.1.is_none()).count(), 4);
        assert_eq!(c.shift_ns(), 5 * i128::from(S));
    }

    #[test]
    fn a_device_clock_jumping_ahead_does_not_jump_the_stamps() {
        let mut c = DeviceClock::new();
        // An hour ahead from estimate 50 on.
        let dev = |k: u64| k * 100_000 + if k >= 50 { 3_600_000_000 } else { 0 };
        let out = feed(&mut c, 120, dev, at_10hz);
        check_device(&out, 0);
        assert_eq!(c.counters.jump_forward, 1);
        assert_eq!(c.counters.restart, 0);
        assert_eq!(c.shift_ns(), -3_600 * i128::from(S));
        assert!(out[52..].iter().all(|o| o.1.is_some()));
    }

    #[test]
    fn one_device_stamp_far_ahead_or_back_is_dropped() {
        let mut c = DeviceClock::new();
        let dev = |k: u64| match k {
            20 => u64::MAX,
            40 => 0,
            _ => 1_000_000 + k * 100_000,
        };
        let out = feed(&mut c, 60, dev, at_10hz);
        check_device(&out, 0);
        assert_eq!(out[20].1, None);
        assert_eq!(out[40].1, None);
        assert_eq!(c.counters.outlier_dropped, 2);
        assert_eq!(c.counters.restart + c.counters.jump_forward, 0);
        // The others are the device's time.
        assert_eq!(out[59].1, Some((1_000_000 + 59 * 100_000) * 1000));
    }

    #[test]
    fn a_device_stall_is_followed_not_re_anchored() {
        let mut c = DeviceClock::new();
        // The device and its clock pause for 14.6 s after estimate 100.
        let arrival = |k: u64| at_10hz(k) + if k > 100 { 14_600_000_000 } else { 0 };
        let out = feed(&mut c, 200, |k| k * 100_000, arrival);
        check_device(&out, 0);
        assert_eq!(
            c.counters,
            ClockCounters {
                held_confirming: 2,
                ..ClockCounters::default()
            }
        );
        assert_eq!(out[150].1, Some(150 * 100_000 * 1000));
    }

    #[test]
    fn extreme_device_times_never_panic_and_never_go_back() {
        let extremes = [
            0,
            1,
            u64::MAX / 1000,
            u64::MAX / 1000 + 1,
            u64::MAX - 1,
            u64::MAX,
        ];
        let mut c = DeviceClock::new();
        let mut last = None;
        for (i, &d) in extremes.iter().cycle().take(60).enumerate() {
            for &a in &[0, u64::MAX, HOST0 + i as u64] {
                if let Ok(t) = c.stamp(d, a) {
                    let t = ns(t);
                    assert!(last.is_none_or(|l| t > l), "{t} after {last:?}");
                    last = Some(t);
                }
            }
        }
        // A device time that saturates the stamps: later ones are refused, none panics.
        let mut c = DeviceClock::new();
        let near_max = |k: u64| u64::MAX - 1_000_000 + k * 100_000;
        assert!(c.stamp(near_max(0), HOST0).is_err());
        assert!(c.stamp(near_max(1), HOST0 + S).is_err());
        assert_eq!(c.stamp(near_max(2), HOST0 + 2 * S), Ok(Time::MAX));
        assert_eq!(
            c.stamp(near_max(3), HOST0 + 3 * S),
            Err(NoStamp::NonIncreasing)
        );
        assert_eq!(
            c.stamp(u64::MAX, HOST0 + 10 * S),
            Err(NoStamp::NonIncreasing)
        );
    }
}
