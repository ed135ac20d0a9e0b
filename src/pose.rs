//! Planar poses, angle wrapping, and the sensor's mounting offset on the robot.
//!
//! Conventions (those of ROS, AMCL and Thrun's book): x forward, y left, angles counter-clockwise
//! from +x, in radians; poses in the map (world) frame, metres.

use core::f32::consts::{PI, TAU};

/// A robot pose `(x, y, θ)` in the map frame: metres, metres, radians (counter-clockwise).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pose {
    /// x position in the map frame, metres.
    pub x_m: f32,
    /// y position in the map frame, metres.
    pub y_m: f32,
    /// Heading, radians counter-clockwise from the map's +x axis. Any finite value; use
    /// [`wrap_angle`] to bring it into `[−π, π)`.
    pub theta_rad: f32,
}

impl Pose {
    /// A pose from its three coordinates (metres, metres, radians).
    pub const fn new(x_m: f32, y_m: f32, theta_rad: f32) -> Self {
        Self {
            x_m,
            y_m,
            theta_rad,
        }
    }

    /// True when all three coordinates are finite.
    pub fn is_finite(&self) -> bool {
        self.x_m.is_finite() && self.y_m.is_finite() && self.theta_rad.is_finite()
    }
}

/// Wraps an angle into `[−π, π)`, radians. Non-finite input comes back unchanged (NaN stays NaN).
///
/// 179° and −179° wrap to values 2° apart: `wrap_angle(a − b)` is the signed shortest
/// difference between two headings.
pub fn wrap_angle(angle_rad: f32) -> f32 {
    if !angle_rad.is_finite() {
        return angle_rad;
    }
    if (-PI..PI).contains(&angle_rad) {
        return angle_rad;
    }
    let mut a = angle_rad - TAU * crate::math::floor((angle_rad + PI) / TAU);
    // Rounding can land exactly on +π (or a hair outside); fold it back.
    if a >= PI {
        a -= TAU;
    }
    if a < -PI {
        a += TAU;
    }
    a
}

/// Wraps an angle into `[−π, π)`, radians, in f64.
pub fn wrap_angle_f64(angle_rad: f64) -> f64 {
    use core::f64::consts::{PI, TAU};
    if !angle_rad.is_finite() || (-PI..PI).contains(&angle_rad) {
        return angle_rad;
    }
    let mut a = angle_rad - TAU * libm::floor((angle_rad + PI) / TAU);
    if a >= PI {
        a -= TAU;
    }
    if a < -PI {
        a += TAU;
    }
    a
}

/// Where the range sensor sits on the robot: Thrun's `(x_k,sens, y_k,sens)` plus a yaw.
///
/// Metres in the robot frame (x forward, y left) and radians. AMCL takes the same numbers from
/// the laser's TF frame. The yaw is added to every beam's bearing.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SensorMount {
    /// Forward offset of the sensor origin from the robot origin, metres.
    pub x_m: f32,
    /// Leftward offset of the sensor origin from the robot origin, metres.
    pub y_m: f32,
    /// Sensor yaw relative to the robot heading, radians counter-clockwise.
    pub yaw_rad: f32,
}

impl SensorMount {
    /// A sensor mounted at the robot origin, facing forward.
    pub const CENTERED: Self = Self {
        x_m: 0.0,
        y_m: 0.0,
        yaw_rad: 0.0,
    };

    /// The sensor's own pose in the map frame when the robot is at `robot`.
    ///
    /// Costs one `sin_cos`; call it once per hypothesis, never per beam.
    pub fn sensor_pose(&self, robot: &Pose) -> Pose {
        let (s, c) = crate::math::sin_cos(robot.theta_rad);
        Pose {
            x_m: robot.x_m + self.x_m * c - self.y_m * s,
            y_m: robot.y_m + self.x_m * s + self.y_m * c,
            theta_rad: robot.theta_rad + self.yaw_rad,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_table() {
        let deg = PI / 180.0;
        let cases: [(f32, f32); 7] = [
            (0.0, 0.0),
            (PI, -PI),
            (-PI, -PI),
            (2.5 * PI, 0.5 * PI),
            (179.0 * deg - (-179.0 * deg), -2.0 * deg),
            (TAU + 0.5, 0.5),
            (-TAU - 0.5, -0.5),
        ];
        for (input, want) in cases {
            let got = wrap_angle(input);
            assert!(
                (got - want).abs() < 1e-5,
                "wrap({input}) = {got}, want {want}"
            );
            assert!((-PI..PI).contains(&got));
        }
        assert!(wrap_angle(f32::NAN).is_nan());
    }

    #[test]
    fn wrap_stays_in_range_for_large_inputs() {
        for k in -1000..1000 {
            let a = k as f32 * 0.731;
            let w = wrap_angle(a);
            assert!((-PI..PI).contains(&w), "{a} -> {w}");
        }
    }

    #[test]
    fn mount_offset_rotates_with_robot() {
        let m = SensorMount {
            x_m: 0.2,
            y_m: 0.0,
            yaw_rad: 0.0,
        };
        let p = m.sensor_pose(&Pose::new(1.0, 2.0, core::f32::consts::FRAC_PI_2));
        assert!((p.x_m - 1.0).abs() < 1e-6 && (p.y_m - 2.2).abs() < 1e-6);
    }
}
