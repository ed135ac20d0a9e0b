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

/// How far the squared norm of an `initialpose` orientation may be from 1 (nav2_amcl's
/// `validateMsg`: `|x² + y² + z² + w² − 1| < 1e-4`).
pub const QUATERNION_NORM2_TOLERANCE: f64 = 1e-4;

/// Nanoseconds in a second: a stamp's `nanosec` must be below it.
const NANOS_PER_SEC: u32 = 1_000_000_000;

/// Why an incoming `initialpose` was not sent to the device. The first six are nav2_amcl's own
/// refusals (docs/nav2.md, "What nav2_amcl refuses"); the last is the link's.
#[derive(Clone, Debug, PartialEq)]
pub enum Refused {
    /// The stamp's `nanosec` is 1,000,000,000 or more.
    Stamp,
    /// The frame id is empty.
    EmptyFrame,
    /// The message's frame is not the global frame (a leading `/` aside).
    WrongFrame { got: String, want: String },
    /// A position coordinate (x, y or z) that is not finite.
    Position,
    /// An orientation component that is not finite.
    Orientation,
    /// An orientation whose squared norm differs from 1 by [`QUATERNION_NORM2_TOLERANCE`] or
    /// more.
    NotUnitQuaternion,
    /// A covariance entry (any of the 36) that is not finite.
    Covariance,
    /// A variance of x, y or yaw below zero (the link's rule: nav2_amcl takes it).
    NegativeVariance,
}

impl std::fmt::Display for Refused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Stamp => f.write_str("the stamp's nanoseconds are 1e9 or more"),
            Self::EmptyFrame => f.write_str("the frame id is empty"),
            Self::WrongFrame { got, want } => {
                write!(f, "frame {got:?} is not the global frame {want:?}")
            }
            Self::Position => f.write_str("the position is not finite"),
            Self::Orientation => f.write_str("the orientation is not finite"),
            Self::NotUnitQuaternion => {
                f.write_str("the orientation is not a unit quaternion (within 1e-4)")
            }
            Self::Covariance => f.write_str("the covariance has a non-finite entry"),
            Self::NegativeVariance => f.write_str("a variance of x, y or yaw is negative"),
        }
    }
}

/// nav2_amcl's checks of an `initialpose` (`validateMsg` for PoseWithCovarianceStamped, then
/// the frame), in its order: the first that fails.
pub fn nav2_refusal(m: &PoseWithCovarianceStamped, global_frame: &str) -> Option<Refused> {
    if m.header.stamp.nanosec >= NANOS_PER_SEC {
        return Some(Refused::Stamp);
    }
    if m.header.frame_id.is_empty() {
        return Some(Refused::EmptyFrame);
    }
    let p = &m.pose.pose;
    if ![p.position.x, p.position.y, p.position.z]
        .iter()
        .all(|v| v.is_finite())
    {
        return Some(Refused::Position);
    }
    let q = &p.orientation;
    if ![q.x, q.y, q.z, q.w].iter().all(|v| v.is_finite()) {
        return Some(Refused::Orientation);
    }
    let n2 = q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w;
    // A squared norm that overflows to infinity is refused too.
    let within = (n2 - 1.0).abs() < QUATERNION_NORM2_TOLERANCE;
    if !within {
        return Some(Refused::NotUnitQuaternion);
    }
    if !m.pose.covariance.0.iter().all(|v| v.is_finite()) {
        return Some(Refused::Covariance);
    }
    // nav2_amcl on Jazzy strips one leading slash from the frame id before comparing.
    let frame = m
        .header
        .frame_id
        .strip_prefix('/')
        .unwrap_or(&m.header.frame_id);
    if frame != global_frame {
        return Some(Refused::WrongFrame {
            got: m.header.frame_id.clone(),
            want: global_frame.to_owned(),
        });
    }
    None
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

/// The device's `SetInitialPose` for an `initialpose` message (timestamp 0: on arrival), or
/// the first of nav2_amcl's refusals ([`nav2_refusal`]) or the link's (a negative variance)
/// that it meets. The x, y, yaw rows of the covariance are taken and made exactly symmetric
/// (the mean of each mirrored pair), as the link requires. Ranges the link refuses (more than
/// 100 km out) are the encoder's to report.
pub fn set_initial_pose(
    m: &PoseWithCovarianceStamped,
    global_frame: &str,
) -> Result<SetInitialPose, Refused> {
    if let Some(why) = nav2_refusal(m, global_frame) {
        return Err(why);
    }
    let p = &m.pose.pose;
    // A finite unit quaternion has a yaw.
    let yaw = p.orientation.yaw().ok_or(Refused::Orientation)?;
    let c6 = &m.pose.covariance.0;
    let mut c = [[0.0f32; 3]; 3];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            let a = c6[XY_YAW[i] * 6 + XY_YAW[j]];
            let b = c6[XY_YAW[j] * 6 + XY_YAW[i]];
            let mean = 0.5 * (a + b);
            // Two finite halves can overflow their sum.
            if !mean.is_finite() {
                return Err(Refused::Covariance);
            }
            if i == j && mean < 0.0 {
                return Err(Refused::NegativeVariance);
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

    /// A message nav2_amcl takes: frame `map`, a unit quaternion, nav2's default spread.
    fn good() -> PoseWithCovarianceStamped {
        let mut cov = [0.0; 36];
        cov[0] = 0.25;
        cov[7] = 0.25;
        cov[35] = 0.068;
        initialpose("map", 4.0, Quaternion::from_yaw(1.0), cov)
    }

    fn verdict(m: &PoseWithCovarianceStamped) -> Result<(), Refused> {
        set_initial_pose(m, "map").map(|_| ())
    }

    #[test]
    fn initialpose_becomes_a_symmetric_set_initial_pose() {
        let mut m = good();
        m.pose.covariance.0[1] = 0.01;
        m.pose.covariance.0[6] = 0.03; // asymmetric: the mean is taken
        let s = set_initial_pose(&m, "map").unwrap();
        assert_eq!(s.pose.x_m, 4.0);
        assert_eq!(s.pose.y_m, -2.0);
        assert!((s.pose.theta_rad - 1.0).abs() < 1e-6);
        assert_eq!(s.covariance[0][1], 0.02);
        assert_eq!(s.covariance[1][0], 0.02);
        assert_eq!(s.covariance[2][2], 0.068);
    }

    #[test]
    fn initialpose_stamp_nanoseconds_below_one_second() {
        let mut m = good();
        m.header.stamp = Time {
            sec: 5,
            nanosec: 999_999_999,
        };
        assert_eq!(verdict(&m), Ok(()));
        m.header.stamp.nanosec = 1_000_000_000;
        assert_eq!(verdict(&m), Err(Refused::Stamp));
        m.header.stamp.nanosec = u32::MAX;
        assert_eq!(verdict(&m), Err(Refused::Stamp));
    }

    #[test]
    fn initialpose_frame_id_must_not_be_empty() {
        let mut m = good();
        m.header.frame_id = String::new();
        assert_eq!(verdict(&m), Err(Refused::EmptyFrame));
        m.header.frame_id = "map".into();
        assert_eq!(verdict(&m), Ok(()));
    }

    #[test]
    fn initialpose_frame_must_be_the_global_frame_but_for_one_leading_slash() {
        let mut m = good();
        for ok in ["map", "/map"] {
            m.header.frame_id = ok.into();
            assert_eq!(verdict(&m), Ok(()), "{ok}");
        }
        for bad in ["odom", "//map", "map/", "Map", " map", "/"] {
            m.header.frame_id = bad.into();
            assert!(
                matches!(verdict(&m), Err(Refused::WrongFrame { ref got, .. }) if got == bad),
                "{bad}"
            );
        }
        // Another global frame.
        m.header.frame_id = "world".into();
        assert!(set_initial_pose(&m, "world").is_ok());
    }

    #[test]
    fn initialpose_position_must_be_finite_z_included() {
        for (axis, v) in [
            (0, f64::NAN),
            (1, f64::INFINITY),
            (2, f64::NAN),
            (2, -f64::INFINITY),
        ] {
            let mut m = good();
            let p = &mut m.pose.pose.position;
            *[&mut p.x, &mut p.y, &mut p.z][axis] = v;
            assert_eq!(verdict(&m), Err(Refused::Position), "axis {axis} = {v}");
        }
        // A finite z is taken (and dropped: the device is planar).
        let mut m = good();
        m.pose.pose.position.z = 3.5;
        assert_eq!(verdict(&m), Ok(()));
    }

    #[test]
    fn initialpose_orientation_must_be_finite() {
        for k in 0..4 {
            let mut m = good();
            let q = &mut m.pose.pose.orientation;
            *[&mut q.x, &mut q.y, &mut q.z, &mut q.w][k] = f64::NAN;
            assert_eq!(verdict(&m), Err(Refused::Orientation), "component {k}");
        }
    }

    #[test]
    fn initialpose_orientation_must_be_a_unit_quaternion() {
        let unit = Quaternion::from_yaw(0.7);
        let scaled = |k: f64| Quaternion {
            x: unit.x * k,
            y: unit.y * k,
            z: unit.z * k,
            w: unit.w * k,
        };
        // Squared norm 1 ± 0.9e-4 is taken, 1 ± 1.1e-4 and a norm of 2 or 0 are not.
        for (n2, ok) in [
            (1.0f64 + 0.9e-4, true),
            (1.0 - 0.9e-4, true),
            (1.0 + 1.1e-4, false),
            (1.0 - 1.1e-4, false),
            (4.0, false),
            (0.0, false),
            (1e300, false),
        ] {
            let mut m = good();
            m.pose.pose.orientation = scaled(n2.sqrt());
            let want = if ok {
                Ok(())
            } else {
                Err(Refused::NotUnitQuaternion)
            };
            assert_eq!(verdict(&m), want, "squared norm {n2}");
        }
        // Components that are each finite but whose squares overflow.
        let mut m = good();
        m.pose.pose.orientation = Quaternion {
            x: 1e200,
            y: 0.0,
            z: 0.0,
            w: 0.0,
        };
        assert_eq!(verdict(&m), Err(Refused::NotUnitQuaternion));
        // A roll and pitch are taken (their yaw is what is sent).
        let mut m = good();
        let h = std::f64::consts::FRAC_1_SQRT_2;
        m.pose.pose.orientation = Quaternion {
            x: h,
            y: 0.0,
            z: 0.0,
            w: h,
        };
        assert_eq!(verdict(&m), Ok(()));
    }

    #[test]
    fn initialpose_covariance_entries_must_all_be_finite() {
        // Every one of the 36 entries, including those of z, roll and pitch the device ignores.
        for i in 0..36 {
            for v in [f64::NAN, f64::INFINITY] {
                let mut m = good();
                m.pose.covariance.0[i] = v;
                assert_eq!(verdict(&m), Err(Refused::Covariance), "entry {i} = {v}");
            }
        }
        // nav2_amcl takes any finite covariance: a huge one and negative correlations.
        let mut m = good();
        m.pose.covariance.0[0] = 1e10;
        m.pose.covariance.0[1] = -0.1;
        m.pose.covariance.0[6] = -0.1;
        m.pose.covariance.0[5] = -0.01;
        m.pose.covariance.0[30] = -0.01;
        m.pose.covariance.0[14] = -5.0; // z's variance: not the device's
        assert_eq!(verdict(&m), Ok(()));
        // Two finite halves whose sum overflows.
        let mut m = good();
        m.pose.covariance.0[1] = f64::MAX;
        m.pose.covariance.0[6] = f64::MAX;
        assert_eq!(verdict(&m), Err(Refused::Covariance));
    }

    #[test]
    fn initialpose_variances_of_x_y_and_yaw_must_not_be_negative() {
        for i in [0, 7, 35] {
            let mut m = good();
            m.pose.covariance.0[i] = -1e-9;
            assert_eq!(verdict(&m), Err(Refused::NegativeVariance), "entry {i}");
            m.pose.covariance.0[i] = 0.0;
            assert_eq!(verdict(&m), Ok(()), "entry {i}");
        }
    }

    #[test]
    fn initialpose_refusals_come_in_nav2_amcls_order() {
        // Everything wrong at once: the stamp is checked first, then the frame id, and so on.
        let mut m = initialpose(
            "",
            f64::NAN,
            Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: f64::NAN,
            },
            [f64::NAN; 36],
        );
        m.header.stamp.nanosec = NANOS_PER_SEC;
        let mut seen = Vec::new();
        while let Err(why) = verdict(&m) {
            seen.push(why.clone());
            match why {
                Refused::Stamp => m.header.stamp.nanosec = 0,
                Refused::EmptyFrame => m.header.frame_id = "odom".into(),
                Refused::Position => m.pose.pose.position.x = 1.0,
                Refused::Orientation => m.pose.pose.orientation.w = 2.0,
                Refused::NotUnitQuaternion => m.pose.pose.orientation.w = 1.0,
                Refused::Covariance => m.pose.covariance.0 = [-1.0; 36],
                Refused::WrongFrame { .. } => m.header.frame_id = "map".into(),
                Refused::NegativeVariance => m.pose.covariance.0 = [0.0; 36],
            }
        }
        let names: Vec<&str> = seen
            .iter()
            .map(|r| match r {
                Refused::Stamp => "stamp",
                Refused::EmptyFrame => "empty frame",
                Refused::Position => "position",
                Refused::Orientation => "orientation",
                Refused::NotUnitQuaternion => "unit",
                Refused::Covariance => "covariance",
                Refused::WrongFrame { .. } => "frame",
                Refused::NegativeVariance => "variance",
            })
            .collect();
        assert_eq!(
            names,
            [
                "stamp",
                "empty frame",
                "position",
                "orientation",
                "unit",
                "covariance",
                "frame",
                "variance"
            ]
        );
    }
}
