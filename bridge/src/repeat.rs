//! map → odom between estimates. nav2_amcl re-sends its last map → odom transform on every
//! scan that does not update the filter (the robot has not moved `update_min_d` or
//! `update_min_a`), stamped with the scan's time plus `transform_tolerance`. The device sends
//! an estimate only for the scans it used, so a robot standing still would see its transform
//! expire `transform_tolerance` after the last estimate.
//!
//! [`Repeater`] re-sends the last transform every [`INTERVAL`] (the LiDAR's 10 Hz) when no
//! estimate has come in that time, while the device shows it is alive: an estimate or a
//! heartbeat within [`DEVICE_SILENT_AFTER`]. The stamp is the device's current time on the
//! stamps' clock plus `transform_tolerance`: the latest device time received, advanced by the
//! computer's time since it arrived, mapped as estimates are (`--clock host`: plus the clock
//! model's offset). A stamp that is not later than the last transform's is not sent.

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
    /// The last transform sent for an estimate.
    last: Option<TransformStamped>,
    /// The latest device time received (µs on the device's clock) and when it arrived.
    device: Option<(u64, Instant)>,
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

    /// A frame from the device with its time (`device_us`, µs on its clock), arrived `at`: it
    /// is alive.
    pub fn device_time(&mut self, device_us: u64, at: Instant) {
        self.device = Some((device_us, at));
    }

    /// The transform sent for an estimate at `at`.
    pub fn sent(&mut self, t: &TransformStamped, at: Instant) {
        self.last_stamp_ns = t.header.stamp.to_nanos();
        self.last = Some(t.clone());
        self.last_sent = Some(at);
    }

    /// The filter is no longer initialized: there is no transform to re-send (nav2_amcl sends
    /// none before it knows a pose).
    pub fn forget(&mut self) {
        self.last = None;
    }

    /// The transform to re-send at `now`, if one is due: the last one stamped with the device's
    /// current time mapped with `offset_ns` (host − device, ns; `None`: no mapping yet) plus
    /// `tolerance_ns`, saturating at [`Time::MAX`].
    pub fn due(
        &mut self,
        now: Instant,
        offset_ns: Option<i128>,
        tolerance_ns: u64,
    ) -> Option<TransformStamped> {
        let last = self.last.as_ref()?;
        let (device_us, arrived) = self.device?;
        let since_device = now.saturating_duration_since(arrived);
        if since_device > DEVICE_SILENT_AFTER {
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
        let device_now_ns = i128::from(device_us) * 1000 + since_device.as_nanos() as i128;
        let mapped = device_now_ns.checked_add(offset_ns?)?;
        let stamp_ns = u64::try_from(mapped.max(0))
            .unwrap_or(u64::MAX)
            .saturating_add(tolerance_ns);
        let stamp = Time::from_nanos(stamp_ns);
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
    const TOLERANCE_NS: u64 = 1_000_000_000;
    /// Host − device, ns.
    const OFFSET: i128 = 1_700_000_000_000_000_000;

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

    /// A repeater that sent an estimate's transform at `t0`, for a scan at device time 10 s
    /// (50 ms before the estimate arrived), stamped as the bridge stamps it.
    fn after_estimate(t0: Instant) -> Repeater {
        let mut r = Repeater::new();
        let scan_us = 10_000_000u64;
        r.device_time(scan_us + 50_000, t0);
        let stamp = (i128::from(scan_us) * 1000 + OFFSET) as u64 + TOLERANCE_NS;
        r.sent(&transform(stamp), t0);
        r
    }

    #[test]
    fn the_last_transform_is_resent_every_interval_stamped_now_plus_the_tolerance() {
        let t0 = Instant::now();
        let mut r = after_estimate(t0);
        // Not within an interval of the estimate's transform.
        assert!(r.due(t0 + 99 * MS, Some(OFFSET), TOLERANCE_NS).is_none());
        for k in 1..=20u32 {
            let now = t0 + INTERVAL * k;
            let t = r.due(now, Some(OFFSET), TOLERANCE_NS).expect("due");
            // The same transform, frames included.
            let mut same = t.clone();
            same.header.stamp = transform(0).header.stamp;
            assert_eq!(same, transform(0));
            // The device's time then (its last message's time plus the time since), mapped,
            // plus the tolerance.
            let want =
                (10_050_000_000i128 + i128::from(k) * 100_000_000 + OFFSET) as u64 + TOLERANCE_NS;
            assert_eq!(t.header.stamp.to_nanos(), Some(want), "k {k}");
            // Nothing more until the next interval.
            assert!(r.due(now + 50 * MS, Some(OFFSET), TOLERANCE_NS).is_none());
        }
        assert_eq!(r.repeated, 20);
    }

    #[test]
    fn nothing_is_resent_while_estimates_come() {
        let t0 = Instant::now();
        let mut r = after_estimate(t0);
        for k in 1..50u32 {
            let now = t0 + 90 * MS * k;
            assert!(r.due(now, Some(OFFSET), TOLERANCE_NS).is_none(), "{k}");
            let device_us = 10_050_000 + u64::from(k) * 90_000;
            r.device_time(device_us, now);
            let stamp = (i128::from(device_us) * 1000 + OFFSET) as u64 + TOLERANCE_NS;
            r.sent(&transform(stamp), now);
        }
        assert_eq!(r.repeated, 0);
    }

    #[test]
    fn a_silent_device_stops_the_resending_and_a_heartbeat_keeps_it_going() {
        let t0 = Instant::now();
        let mut r = after_estimate(t0);
        // Heartbeats at 1 s and 2 s of device time after the estimate's frame.
        r.device_time(11_050_000, t0 + 1000 * MS);
        r.device_time(12_050_000, t0 + 2000 * MS);
        assert!(r.due(t0 + 4400 * MS, Some(OFFSET), TOLERANCE_NS).is_some());
        // 2.5 s after the last heartbeat: the device is taken as gone.
        assert!(r.due(t0 + 4501 * MS, Some(OFFSET), TOLERANCE_NS).is_none());
        assert!(r.due(t0 + 9000 * MS, Some(OFFSET), TOLERANCE_NS).is_none());
        // It comes back.
        r.device_time(19_050_000, t0 + 9000 * MS);
        assert!(r.due(t0 + 9100 * MS, Some(OFFSET), TOLERANCE_NS).is_some());
    }

    #[test]
    fn a_stamp_not_later_than_the_last_is_not_sent() {
        let t0 = Instant::now();
        let mut r = after_estimate(t0);
        // The device restarted: its time is back near 0, and the clock has not re-anchored.
        r.device_time(1_000, t0 + 50 * MS);
        for k in 1..10u32 {
            assert!(r
                .due(t0 + INTERVAL * k, Some(OFFSET), TOLERANCE_NS)
                .is_none());
        }
        // A huge tolerance saturates at the latest stamp once, then nothing more.
        let mut r = after_estimate(t0);
        let t = r.due(t0 + INTERVAL, Some(OFFSET), u64::MAX).unwrap();
        assert_eq!(t.header.stamp, Time::MAX);
        assert!(r.due(t0 + INTERVAL * 2, Some(OFFSET), u64::MAX).is_none());
        assert_eq!(r.repeated, 1);
    }

    #[test]
    fn nothing_is_resent_without_a_transform_or_a_clock() {
        let t0 = Instant::now();
        let mut r = Repeater::new();
        r.device_time(5_000_000, t0);
        assert!(r.due(t0 + INTERVAL, Some(OFFSET), TOLERANCE_NS).is_none());
        let mut r = after_estimate(t0);
        assert!(r.due(t0 + INTERVAL, None, TOLERANCE_NS).is_none());
        let mut r = after_estimate(t0);
        r.forget();
        assert!(r.due(t0 + INTERVAL, Some(OFFSET), TOLERANCE_NS).is_none());
        assert_eq!(r.repeated, 0);
    }
}
