//! Planar poses, the sensor's mounting offset on the robot, and angle wrapping (from `math`).
//!
//! Conventions (those of ROS, AMCL and Thrun's book): x forward, y left, angles counter-clockwise
//! from +x, in radians; poses in the map (world) frame, metres.

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

/// Angle wrapping lives in the math module (`crate::math`), below every model; re-exported here,
/// beside the poses whose headings it wraps.
pub use crate::math::{wrap_angle, wrap_angle_f64};

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
