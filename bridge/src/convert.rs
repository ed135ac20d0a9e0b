//! Between the link's messages and ROS 2's: the estimate as `amcl_pose` and as the map → odom
//! transform nav2_amcl broadcasts, `initialpose` as the device's `SetInitialPose`. Stamps are
//! the caller's ([`crate::clock`] puts the device's clock on the computer's). Pure functions;
//! every refusal is a [`Refused`].

use beamfield::link::{Estimate, SetInitialPose};
use beamfield::Pose as DevicePose;

use crate::msg::{
    Covariance6, Header, Point, Pose, PoseWithCovariance, PoseWithCovarianceStamped, Quaternion,
    Time, Transform, TransformStamped, Vector3,
};

/// The rows and columns of ROS's 6×6 pose covariance (x, y, z, roll, pitch, yaw) that the
/// link's 3×3 (x, y, yaw) covers.
const XY_YAW: [usize; 3] = [0, 1, 5];

/// Why an incoming ROS message was not sent to the device.
#[derive(Clone, Debug, PartialEq)]
pub enum Refused {
    /// The message's frame is not the global frame (nav2_amcl ignores those too).
    WrongFrame { got: String, want: String },
    /// A position that is not finite.
    Position,
    /// An orientation that is not finite or has no length.
    Orientation,
    /// A covariance entry (x, y, yaw rows) that is not finite, or a negative variance.
    Covariance,
}

impl std::fmt::Display for Refused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::WrongFrame { got, want } => {
                write!(f, "frame {got:?} is not the global frame {want:?}")
            }
            Self::Position => f.write_str("the position is not finite"),
            Self::Orientation => f.write_str("the orientation is not finite or has zero length"),
            Self::Covariance => {
                f.write_str("the covariance has a non-finite entry or a negative variance")
            }
        }
    }
}

/// `amcl_pose` for an estimate: the pose in `global_frame`, the 3×3 covariance spread into the
/// 6×6 at rows and columns x, y, yaw (the rest zero, as nav2_amcl leaves them).
pub fn amcl_pose(e: &Estimate, stamp: Time, global_frame: &str) -> PoseWithCovarianceStamped {
    let mut c = [0.0; 36];
    for (i, row) in e.covariance.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            c[XY_YAW[i] * 6 + XY_YAW[j]] = f64::from(*v);
        }
    }
    PoseWithCovarianceStamped {
        header: Header {
            stamp,
            frame_id: global_frame.to_owned(),
        },
        pose: PoseWithCovariance {
            pose: Pose {
                position: Point {
                    x: f64::from(e.pose.x_m),
                    y: f64::from(e.pose.y_m),
                    z: 0.0,
                },
                orientation: Quaternion::from_yaw(f64::from(e.pose.theta_rad)),
            },
            covariance: Covariance6(c),
        },
    }
}

/// The map → odom transform `map_T_base ∘ (odom_T_base)⁻¹` in metres and radians (x, y, yaw):
/// where the odometry frame lies in the map, given where the robot is in both.
pub fn map_to_odom(map_base: &DevicePose, odom_base: &DevicePose) -> (f64, f64, f64) {
    let (mx, my, mt) = (
        f64::from(map_base.x_m),
        f64::from(map_base.y_m),
        f64::from(map_base.theta_rad),
    );
    let (ox, oy, ot) = (
        f64::from(odom_base.x_m),
        f64::from(odom_base.y_m),
        f64::from(odom_base.theta_rad),
    );
    let yaw = mt - ot;
    let (s, c) = yaw.sin_cos();
    // t = m − R(yaw)·o
    let x = mx - (c * ox - s * oy);
    let y = my - (s * ox + c * oy);
    (x, y, yaw.sin().atan2(yaw.cos()))
}

/// The `/tf` entry nav2_amcl broadcasts for an estimate: map → odom, stamped `stamp`
/// (nav2_amcl post-dates it by `transform_tolerance`; the caller adds that).
pub fn map_to_odom_transform(
    e: &Estimate,
    stamp: Time,
    global_frame: &str,
    odom_frame: &str,
) -> TransformStamped {
    let (x, y, yaw) = map_to_odom(&e.pose, &e.odometry);
    TransformStamped {
        header: Header {
            stamp,
            frame_id: global_frame.to_owned(),
        },
        child_frame_id: odom_frame.to_owned(),
        transform: Transform {
            translation: Vector3 { x, y, z: 0.0 },
            rotation: Quaternion::from_yaw(yaw),
        },
    }
}

/// The device's `SetInitialPose` for an `initialpose` message (timestamp 0: on arrival).
/// The x, y, yaw rows of the covariance are taken and made exactly symmetric (the mean of each
/// mirrored pair), as the link requires. Ranges the link refuses (more than 100 km out) are the
/// encoder's to report.
pub fn set_initial_pose(
    m: &PoseWithCovarianceStamped,
    global_frame: &str,
) -> Result<SetInitialPose, Refused> {
    // nav2_amcl accepts an empty frame id as the global frame.
    let frame = m.header.frame_id.trim_start_matches('/');
    if !frame.is_empty() && frame != global_frame {
        return Err(Refused::WrongFrame {
            got: m.header.frame_id.clone(),
            want: global_frame.to_owned(),
        });
    }
    let p = &m.pose.pose;
    if !(p.position.x.is_finite() && p.position.y.is_finite()) {
        return Err(Refused::Position);
    }
    let yaw = p.orientation.yaw().ok_or(Refused::Orientation)?;
    let c6 = &m.pose.covariance.0;
    let mut c = [[0.0f32; 3]; 3];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            let a = c6[XY_YAW[i] * 6 + XY_YAW[j]];
            let b = c6[XY_YAW[j] * 6 + XY_YAW[i]];
            let mean = 0.5 * (a + b);
            if !mean.is_finite() || (i == j && mean < 0.0) {
                return Err(Refused::Covariance);
            }
            *v = mean as f32;
        }
    }
    // f32 rounding of the two halves gives the same value: exactly symmetric.
    Ok(SetInitialPose {
        timestamp_us: 0,
        pose: DevicePose::new(p.position.x as f32, p.position.y as f32, yaw as f32),
        covariance: c,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use beamfield::link::{EstimateFlags, Quality};

    fn estimate(pose: DevicePose, odometry: DevicePose) -> Estimate {
        Estimate {
            timestamp_us: 2_500_000,
            pose,
            covariance: [
                [0.04, 0.01, 0.002],
                [0.01, 0.09, 0.003],
                [0.002, 0.003, 0.01],
            ],
            ess: 321.0,
            flags: EstimateFlags::INITIALIZED,
            quality: Quality::default(),
            odometry,
        }
    }

    #[test]
    fn amcl_pose_places_the_covariance_at_x_y_yaw() {
        let e = estimate(DevicePose::new(1.0, 2.0, 0.5), DevicePose::default());
        let m = amcl_pose(&e, Time { sec: 3, nanosec: 4 }, "map");
        assert_eq!(m.header.frame_id, "map");
        let c = &m.pose.covariance.0;
        assert_eq!(c[0], f64::from(0.04f32));
        assert_eq!(c[1], f64::from(0.01f32));
        assert_eq!(c[5], f64::from(0.002f32));
        assert_eq!(c[6 + 1], f64::from(0.09f32));
        assert_eq!(c[5 * 6 + 5], f64::from(0.01f32));
        assert_eq!(c[5 * 6 + 1], f64::from(0.003f32));
        let nonzero = c.iter().filter(|v| **v != 0.0).count();
        assert_eq!(nonzero, 9);
        let yaw = m.pose.pose.orientation.yaw().unwrap();
        assert!((yaw - 0.5).abs() < 1e-7);
    }

    #[test]
    fn map_to_odom_composes_back_to_the_estimate() {
        // For any map and odom poses, (map → odom) ∘ (odom → base) = (map → base).
        let cases = [
            (
                DevicePose::new(1.0, 2.0, 0.5),
                DevicePose::new(-3.0, 0.25, -2.0),
            ),
            (
                DevicePose::new(-7.5, 4.0, 3.0),
                DevicePose::new(10.0, -1.0, 2.9),
            ),
            (
                DevicePose::new(0.0, 0.0, 0.0),
                DevicePose::new(0.0, 0.0, 0.0),
            ),
        ];
        for (m, o) in cases {
            let (x, y, yaw) = map_to_odom(&m, &o);
            let (s, c) = yaw.sin_cos();
            let bx = x + c * f64::from(o.x_m) - s * f64::from(o.y_m);
            let by = y + s * f64::from(o.x_m) + c * f64::from(o.y_m);
            let bt = yaw + f64::from(o.theta_rad);
            assert!((bx - f64::from(m.x_m)).abs() < 1e-9, "{m:?} {o:?}");
            assert!((by - f64::from(m.y_m)).abs() < 1e-9, "{m:?} {o:?}");
            let d = (bt - f64::from(m.theta_rad))
                .sin()
                .atan2((bt - f64::from(m.theta_rad)).cos());
            assert!(d.abs() < 1e-9, "{m:?} {o:?}");
        }
    }

    fn initialpose(
        frame: &str,
        x: f64,
        q: Quaternion,
        cov: [f64; 36],
    ) -> PoseWithCovarianceStamped {
        PoseWithCovarianceStamped {
            header: Header {
                stamp: Time::default(),
                frame_id: frame.into(),
            },
            pose: PoseWithCovariance {
                pose: Pose {
                    position: Point { x, y: -2.0, z: 0.0 },
                    orientation: q,
                },
                covariance: Covariance6(cov),
            },
        }
    }

    #[test]
    fn initialpose_becomes_a_symmetric_set_initial_pose() {
        let mut cov = [0.0; 36];
        cov[0] = 0.25;
        cov[7] = 0.25;
        cov[35] = 0.068;
        cov[1] = 0.01;
        cov[6] = 0.03; // asymmetric: the mean is taken
        let s = set_initial_pose(
            &initialpose("map", 4.0, Quaternion::from_yaw(1.0), cov),
            "map",
        )
        .unwrap();
        assert_eq!(s.pose.x_m, 4.0);
        assert_eq!(s.pose.y_m, -2.0);
        assert!((s.pose.theta_rad - 1.0).abs() < 1e-6);
        assert_eq!(s.covariance[0][1], 0.02);
        assert_eq!(s.covariance[1][0], 0.02);
        assert_eq!(s.covariance[2][2], 0.068);
        assert!(set_initial_pose(&initialpose("", 4.0, Quaternion::default(), cov), "map").is_ok());
    }

    #[test]
    fn initialpose_refusals() {
        let cov = [0.0; 36];
        let q = Quaternion::default();
        assert!(matches!(
            set_initial_pose(&initialpose("odom", 1.0, q, cov), "map"),
            Err(Refused::WrongFrame { .. })
        ));
        assert_eq!(
            set_initial_pose(&initialpose("map", f64::NAN, q, cov), "map"),
            Err(Refused::Position)
        );
        let nan_q = Quaternion { z: f64::NAN, ..q };
        assert_eq!(
            set_initial_pose(&initialpose("map", 1.0, nan_q, cov), "map"),
            Err(Refused::Orientation)
        );
        let mut bad = cov;
        bad[35] = -1.0;
        assert_eq!(
            set_initial_pose(&initialpose("map", 1.0, q, bad), "map"),
            Err(Refused::Covariance)
        );
        bad[35] = f64::INFINITY;
        assert_eq!(
            set_initial_pose(&initialpose("map", 1.0, q, bad), "map"),
            Err(Refused::Covariance)
        );
    }
}
