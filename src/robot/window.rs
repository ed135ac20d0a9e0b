//! The recent odometry, timestamped, and the pose interpolated at any time within it.

use crate::pose::{wrap_angle, Pose};
use heapless::Deque;

/// Odometry samples kept (50 Hz odometry: 1.28 s).
pub const WINDOW: usize = 64;

/// One odometry pose and when it was measured (µs, device clock).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Measurement time, µs.
    pub t_us: u64,
    /// Odometry pose (the wheel odometry's own frame), m and rad.
    pub pose: Pose,
}

/// The odometry pose at a time, and how it was found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interpolated {
    /// The pose.
    pub pose: Pose,
    /// `true` when the time lies outside the samples (the nearest one was taken), between
    /// two samples further apart than the allowed gap, or across a restart of the odometry.
    pub stale: bool,
    /// The odometry frame the pose is in: the number of [`OdometryWindow::restart`]s before
    /// the sample it came from (poses of different frames cannot be compared).
    pub frame: u32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Entry {
    sample: Sample,
    frame: u32,
}

/// Odometry samples in time order (strictly increasing timestamps), each in the odometry frame
/// it was measured in (a new one after every [`OdometryWindow::restart`]).
#[derive(Clone, Debug, Default)]
pub struct OdometryWindow {
    samples: Deque<Entry, WINDOW>,
    frame: u32,
}

impl OdometryWindow {
    /// An empty window.
    pub const fn new() -> Self {
        Self {
            samples: Deque::new(),
            frame: 0,
        }
    }

    /// Whether another sample fits.
    pub fn has_room(&self) -> bool {
        !self.samples.is_full()
    }

    /// The newest sample.
    pub fn newest(&self) -> Option<&Sample> {
        self.samples.back().map(|e| &e.sample)
    }

    /// The odometry restarted: samples pushed from now on are in a new frame, and no pose is
    /// interpolated across the restart.
    pub fn restart(&mut self) {
        self.frame = self.frame.wrapping_add(1);
    }

    /// Samples held.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// Whether no sample is held.
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// Appends a sample; `false` (and nothing kept) when the window is full or `t_us` is not
    /// after the newest sample's.
    pub fn push(&mut self, sample: Sample) -> bool {
        if self.newest().is_some_and(|n| sample.t_us <= n.t_us) {
            return false;
        }
        self.samples
            .push_back(Entry {
                sample,
                frame: self.frame,
            })
            .is_ok()
    }

    /// Whether the samples reach time `t_us` (the newest is at or after it).
    pub fn covers(&self, t_us: u64) -> bool {
        self.newest().is_some_and(|n| n.t_us >= t_us)
    }

    /// The pose at `t_us`: linear in position, along the shorter arc in heading, between the
    /// samples on either side (across a restart: the sample before it, stale). `None` when the
    /// window is empty.
    pub fn at(&self, t_us: u64, max_gap_us: u64) -> Option<Interpolated> {
        let first = *self.samples.front()?;
        if t_us <= first.sample.t_us {
            return Some(Interpolated {
                pose: first.sample.pose,
                stale: t_us < first.sample.t_us,
                frame: first.frame,
            });
        }
        let mut before = first;
        for e in self.samples.iter() {
            let s = &e.sample;
            if s.t_us >= t_us {
                if e.frame != before.frame {
                    // Across a restart: the sample on the side of `t_us`'s own frame.
                    let side = if s.t_us == t_us { *e } else { before };
                    return Some(Interpolated {
                        pose: side.sample.pose,
                        stale: true,
                        frame: side.frame,
                    });
                }
                let before_frame = before.frame;
                let before = before.sample;
                let span = s.t_us - before.t_us;
                let f = if span == 0 {
                    1.0
                } else {
                    ((t_us - before.t_us) as f64 / span as f64) as f32
                };
                let (a, b) = (before.pose, s.pose);
                let pose = Pose::new(
                    a.x_m + f * (b.x_m - a.x_m),
                    a.y_m + f * (b.y_m - a.y_m),
                    wrap_angle(a.theta_rad + f * wrap_angle(b.theta_rad - a.theta_rad)),
                );
                return Some(Interpolated {
                    pose,
                    stale: span > max_gap_us,
                    frame: before_frame,
                });
            }
            before = *e;
        }
        Some(Interpolated {
            pose: before.sample.pose,
            stale: true,
            frame: before.frame,
        })
    }

    /// Drops the samples no longer needed once time `t_us` is reached: every sample before the
    /// last one at or before `t_us`.
    pub fn forget_before(&mut self, t_us: u64) {
        while self.samples.len() >= 2
            && self
                .samples
                .iter()
                .nth(1)
                .is_some_and(|e| e.sample.t_us <= t_us)
        {
            self.samples.pop_front();
        }
    }

    /// Drops the oldest sample (`false` when there was none).
    pub fn pop_oldest(&mut self) -> bool {
        self.samples.pop_front().is_some()
    }

    /// Drops every sample.
    pub fn clear(&mut self) {
        self.samples.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(t_us: u64, x: f32, th: f32) -> Sample {
        Sample {
            t_us,
            pose: Pose::new(x, 0.0, th),
        }
    }

    #[test]
    fn interpolates_position_and_heading_across_pi() {
        let mut w = OdometryWindow::new();
        assert!(w.push(s(1_000, 0.0, 3.0)));
        assert!(w.push(s(3_000, 2.0, -3.0)));
        let at = w.at(2_000, 10_000).unwrap();
        assert!((at.pose.x_m - 1.0).abs() < 1e-6);
        // Halfway along the short arc through ±π.
        assert!((at.pose.theta_rad.abs() - core::f32::consts::PI).abs() < 1e-3);
        assert!(!at.stale);
        assert!(w.at(2_000, 1_000).unwrap().stale);
        assert!(w.at(5_000, 10_000).unwrap().stale);
        assert!(w.covers(3_000) && !w.covers(3_001));
    }

    #[test]
    fn refuses_time_going_backwards_and_forgets_old_samples() {
        let mut w = OdometryWindow::new();
        assert!(w.push(s(10, 0.0, 0.0)));
        assert!(!w.push(s(10, 1.0, 0.0)));
        assert!(!w.push(s(5, 1.0, 0.0)));
        assert!(w.push(s(20, 1.0, 0.0)));
        assert!(w.push(s(30, 2.0, 0.0)));
        w.forget_before(25);
        assert_eq!(w.len(), 2);
        assert_eq!(w.samples.front().map(|e| e.sample.t_us), Some(20));
    }

    #[test]
    fn no_pose_is_interpolated_across_a_restart() {
        let mut w = OdometryWindow::new();
        assert!(w.push(s(1_000, 5.0, 0.0)));
        w.restart();
        assert!(w.push(s(3_000, 0.0, 0.0)));
        let at = w.at(2_000, 10_000).unwrap();
        assert_eq!((at.pose.x_m, at.stale, at.frame), (5.0, true, 0));
        let at = w.at(3_000, 10_000).unwrap();
        assert_eq!((at.pose.x_m, at.stale, at.frame), (0.0, true, 1));
    }
}
