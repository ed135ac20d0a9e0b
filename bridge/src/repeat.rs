//! map → odom between estimates. nav2_amcl re-sends its last map → odom transform on every
//! scan that does not update the filter (the robot has not moved `update_min_d` or
//! `update_min_a`), stamped with the scan's time plus `transform_tolerance`. The device sends
//! an estimate only for the scans it used, so a robot standing still would see its transform
//! expire `transform_tolerance` after the last estimate.
//!
//! [`Repeater`] re-sends the last transform every [`INTERVAL`] (the LiDAR's 10 Hz) when no
//! estimate has come in that time, while the device shows it is alive: an estimate or a
//! heartbeat within [`DEVICE_SILENT_AFTER`]. The stamp is the last transform's (its estimate's
//! time plus `transform_tolerance`) advanced by the computer's time since that estimate arrived:
//! the current time on the stamps' clock plus `transform_tolerance`, as a scan's would be (later
//! than the next estimate's only when that estimate takes longer from its scan to the bridge
//! than the last one did). A stamp that is not later than the last transform's is not sent.

use std::time::{Duration, Instant};

use crate::msg::{Time, TransformStamped};

/// How often the last transform is re-sent while no estimate comes: 10 Hz, the LiDAR's rate,
/// at which nav2_amcl re-sends it.
pub const INTERVAL: Duration = Duration::from_millis(100);

/// The device is taken as gone (and nothing is re-sent) when neither an estimate nor a
/// heartbeat came for this long: two and a half heartbeat periods.
pub const DEVICE_SILENT_AFTER: Duration = Duration::from_millis(2500);

/// The last map → odom transform and what is needed to re-send it.
#[derive(Clone, Debug, Default)]
pub struct Repeater {
    /// The last transform sent for an estimate, and when that estimate arrived.
    last: Option<(TransformStamped, Instant)>,
    /// When the device last showed it is alive (an estimate or a heartbeat arrived).
    alive: Option<Instant>,
    /// The last transform's stamp (for an estimate or re-sent), ns since the clock's epoch.
    last_stamp_ns: Option<u64>,
    /// When a transform was last sent (for an estimate or re-sent).
    last_sent: Option<Instant>,
    /// Transforms re-sent.
    pub repeated: u64,
}

impl Repeater {
    pub fn new() -> Self {
        Self::default()
    }

    /// A frame from the device (an estimate or a heartbeat) arrived `at`: it is alive.
    pub fn alive(&mut self, at: Instant) {
        self.alive = Some(self.alive.map_or(at, |a| a.max(at)));
    }

    /// The transform sent for an estimate that arrived `arrived`, sent at `now`.
    pub fn sent(&mut self, t: &TransformStamped, arrived: Instant, now: Instant) {
        self.last_stamp_ns = t.header.stamp.to_nanos();
        self.last = Some((t.clone(), arrived));
        self.last_sent = Some(now);
    }

    /// The filter is no longer initialized: there is no transform to re-send (nav2_amcl sends
    /// none before it knows a pose).
    pub fn forget(&mut self) {
        self.last = None;
    }

    /// The transform to re-send at `now`, if one is due: the last one, its stamp advanced by the
    /// time since its estimate arrived (saturating at [`Time::MAX`]).
    pub fn due(&mut self, now: Instant) -> Option<TransformStamped> {
        let (last, arrived) = self.last.as_ref()?;
        if now.saturating_duration_since(self.alive?) > DEVICE_SILENT_AFTER {
            return None;
        }
        if self
            .last_sent
            .is_some_and(|s| now.saturating_duration_since(s) < INTERVAL)
        {
            return None;
        }
        // Whatever the outcome, the next try is an interval away.
        self.last_sent = Some(now);
        let since =
            u64::try_from(now.saturating_duration_since(*arrived).as_nanos()).unwrap_or(u64::MAX);
        let stamp = Time::from_nanos(last.header.stamp.to_nanos()?.saturating_add(since));
        let stamp_ns = stamp.to_nanos()?;
        if self.last_stamp_ns.is_some_and(|l| stamp_ns <= l) {
            return None;
        }
        let mut t = last.clone();
        t.header.stamp = stamp;
        self.last_stamp_ns = Some(stamp_ns);
        self.repeated += 1;
        Some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msg::{Header, Quaternion, Transform, Vector3};

    const MS: Duration = Duration::from_millis(1);
    /// The first estimate's transform stamp, ns (its time plus the tolerance).
    const STAMP0: u64 = 1_700_000_001_000_000_000;

    fn transform(stamp_ns: u64) -> TransformStamped {
        TransformStamped {
            header: Header {
                stamp: Time::from_nanos(stamp_ns),
                frame_id: "map".into(),
            },
            child_frame_id: "odom".into(),
            transform: Transform {
                translation: Vector3 {
                    x: 1.5,
                    y: -2.0,
                    z: 0.0,
                },
                rotation: Quaternion::from_yaw(0.3),
            },
        }
    }

    /// A repeater that sent an estimate's transform, the estimate having arrived at `t0` and
    /// been sent 2 ms later.
    fn after_estimate(t0: Instant) -> Repeater {
        let mut r = Repeater::new();
        r.alive(t0);
        r.sent(&transform(STAMP0), t0, t0 + 2 * MS);
        r
    }

    #[test]
    fn the_last_transform_is_resent_every_interval_stamped_as_time_went_on() {
        let t0 = Instant::now();
        let mut r = after_estimate(t0);
        // Not within an interval of the estimate's transform.
        assert!(r.due(t0 + 101 * MS).is_none());
        for k in 1..=20u32 {
            let now = t0 + 2 * MS + INTERVAL * k;
            // A heartbeat every second.
            if k % 10 == 0 {
                r.alive(now);
            }
            let t = r.due(now).expect("due");
            // The same transform, frames included.
            let mut same = t.clone();
            same.header.stamp = transform(STAMP0).header.stamp;
            assert_eq!(same, transform(STAMP0));
            // The estimate's stamp plus the time since it arrived.
            let want = STAMP0 + 2_000_000 + u64::from(k) * 100_000_000;
            assert_eq!(t.header.stamp.to_nanos(), Some(want), "k {k}");
            // Nothing more until the next interval.
            assert!(r.due(now + 50 * MS).is_none());
        }
        assert_eq!(r.repeated, 20);
    }

    #[test]
    fn nothing_is_resent_while_estimates_come() {
        let t0 = Instant::now();
        let mut r = after_estimate(t0);
        for k in 1..50u32 {
            let now = t0 + 90 * MS * k;
            assert!(r.due(now).is_none(), "{k}");
            r.alive(now);
            r.sent(&transform(STAMP0 + u64::from(k) * 90_000_000), now, now);
        }
        assert_eq!(r.repeated, 0);
    }

    #[test]
    fn a_silent_device_stops_the_resending_and_a_heartbeat_keeps_it_going() {
        let t0 = Instant::now();
        let mut r = after_estimate(t0);
        // Heartbeats 1 s and 2 s after the estimate.
        r.alive(t0 + 1000 * MS);
        r.alive(t0 + 2000 * MS);
        assert!(r.due(t0 + 4400 * MS).is_some());
        // 2.5 s after the last heartbeat: the device is taken as gone.
        assert!(r.due(t0 + 4501 * MS).is_none());
        assert!(r.due(t0 + 9000 * MS).is_none());
        // It comes back.
        r.alive(t0 + 9000 * MS);
        assert!(r.due(t0 + 9100 * MS).is_some());
    }

    #[test]
    fn a_stamp_not_later_than_the_last_is_not_sent() {
        let t0 = Instant::now();
        // The latest stamp already: it saturates and is not later.
        let mut r = Repeater::new();
        r.alive(t0);
        r.sent(&transform(Time::MAX.to_nanos().unwrap()), t0, t0);
        for k in 1..10u32 {
            assert!(r.due(t0 + INTERVAL * k).is_none());
        }
        assert_eq!(r.repeated, 0);
    }

    #[test]
    fn nothing_is_resent_without_a_transform_or_a_sign_of_life() {
        let t0 = Instant::now();
        let mut r = Repeater::new();
        r.alive(t0);
        assert!(r.due(t0 + INTERVAL).is_none());
        let mut r = Repeater::new();
        r.sent(&transform(STAMP0), t0, t0);
        assert!(r.due(t0 + INTERVAL).is_none());
        let mut r = after_estimate(t0);
        r.forget();
        assert!(r.due(t0 + INTERVAL * 2).is_none());
        assert_eq!(r.repeated, 0);
    }
}
