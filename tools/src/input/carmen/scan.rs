//! One FLASER message ([`LaserScan`]): its ranges, poses and timestamps, and its beams as a
//! [`beamfield::Scan`] and [`beamfield::BeamLayout`]; the f64 pose and the CARMEN bearing.

use beamfield::{Pose, Scan, ScanError};

/// One FLASER message.
#[derive(Clone, Debug, PartialEq)]
pub struct LaserScan {
    /// The ranges as written, metres, in beam order (beam `i` at [`carmen_bearing_rad`]). Max-range
    /// readings keep their sentinel value; [`beamfield::Reading::classify`] against the log's
    /// max range tells them apart.
    pub ranges_m: Vec<f32>,
    /// The laser's pose in the world frame (`x y theta`), metres and radians, θ as written.
    pub pose: Pose,
    /// The robot's pose (`odom_x odom_y odom_theta`), metres and radians.
    pub odom_pose: Pose,
    /// The laser's pose as parsed, in f64 ([`LaserScan::pose`] is it rounded to f32): what the
    /// map builder projects beams from, so that a log far from the origin keeps its precision.
    pub pose_f64: PoseF64,
    /// The ipc timestamp, seconds. Not necessarily increasing (the Intel log steps back 4 times).
    pub timestamp_s: f64,
    /// The logger timestamp, seconds.
    pub logger_timestamp_s: f64,
    /// 1-based line number in the log.
    pub line: usize,
}

impl LaserScan {
    /// The ranges as a fixed-capacity [`Scan`] for the `beamfield` models.
    ///
    /// # Errors
    /// [`ScanError::TooMany`] when the scan has more than `N` readings (nothing is truncated).
    pub fn to_scan<const N: usize>(&self) -> Result<Scan<N>, ScanError> {
        Scan::from_ranges(&self.ranges_m)
    }

    /// World-frame end point of beam `i` (metres), in f64 from the f64 pose
    /// ([`LaserScan::pose_f64`]), or `None` past the last beam. Uses the CARMEN bearing
    /// [`carmen_bearing_rad`]; max-range readings are projected like any other.
    pub fn endpoint(&self, i: usize) -> Option<(f64, f64)> {
        let n = self.ranges_m.len();
        let r = f64::from(*self.ranges_m.get(i)?);
        let p = self.pose_f64;
        let a = p.theta_rad + carmen_bearing_rad(i, n);
        Some((p.x_m + r * a.cos(), p.y_m + r * a.sin()))
    }
}

/// A pose in f64 (metres, metres, radians).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseF64 {
    /// x, metres.
    pub x_m: f64,
    /// y, metres.
    pub y_m: f64,
    /// θ, radians.
    pub theta_rad: f64,
}

impl From<Pose> for PoseF64 {
    fn from(p: Pose) -> Self {
        Self {
            x_m: f64::from(p.x_m),
            y_m: f64::from(p.y_m),
            theta_rad: f64::from(p.theta_rad),
        }
    }
}

/// Angle between consecutive beams of a FLASER scan of `n` beams, radians, in f64: a scan starts
/// at −90° and covers 180° in `n` intervals when `n` is even (`π/n`: the Intel and Edmonton
/// logs' 180 beams at −90° … +89°, 1° apart) and in `n − 1` when `n` is odd (`π/(n − 1)`: both
/// ends included, the Acapulco log's 181 beams 1° apart and the Belgioioso log's 361 beams 0.5°
/// apart, −90° … +90°). The logs do not say which; the layouts were established from the data,
/// each the one whose end points at the corrected poses fall into the fewest map cells (the
/// crispest map; data/README.md).
pub fn carmen_beam_step_rad(n: usize) -> f64 {
    let intervals = if n % 2 == 1 && n > 1 { n - 1 } else { n.max(1) };
    std::f64::consts::PI / intervals as f64
}

/// Bearing of beam `i` of `n` in a FLASER scan, radians: `−π/2 + i·`[`carmen_beam_step_rad`]`(n)`,
/// in f64.
pub fn carmen_bearing_rad(i: usize, n: usize) -> f64 {
    -std::f64::consts::FRAC_PI_2 + i as f64 * carmen_beam_step_rad(n)
}
