//! The ROS 2 messages the bridge speaks, declared as their `.msg` definitions lay them out in
//! CDR (field order is wire order; `float64` is `f64`, `string` a `String`, `T[]` a `Vec<T>`,
//! `T[36]` a fixed array with no length prefix). ROS 2 over DDS names each type
//! `<package>::msg::dds_::<Type>_`; [`ros2_client::MessageTypeName`] adds that mangling.

use ros2_client::Message;
use serde::{Deserialize, Serialize};

/// `builtin_interfaces/Time`: seconds and nanoseconds since the clock's epoch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Time {
    pub sec: i32,
    pub nanosec: u32,
}

impl Time {
    /// The latest time this type holds: `i32::MAX` s and 999,999,999 ns (in 2038).
    pub const MAX: Self = Self {
        sec: i32::MAX,
        nanosec: 999_999_999,
    };

    /// The time `ns` nanoseconds after the epoch, saturating at [`Time::MAX`].
    pub fn from_nanos(ns: u64) -> Self {
        match i32::try_from(ns / 1_000_000_000) {
            Ok(sec) => Self {
                sec,
                nanosec: (ns % 1_000_000_000) as u32,
            },
            Err(_) => Self::MAX,
        }
    }

    /// Nanoseconds since the epoch; `None` before it.
    pub fn to_nanos(self) -> Option<u64> {
        u64::try_from(self.sec)
            .ok()
            .map(|s| s * 1_000_000_000 + u64::from(self.nanosec))
    }
}

/// `std_msgs/Header`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    pub stamp: Time,
    pub frame_id: String,
}

/// `geometry_msgs/Point` (metres).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Point {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// `geometry_msgs/Vector3` (metres, in a transform).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// `geometry_msgs/Quaternion`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

impl Default for Quaternion {
    /// The identity rotation (ROS's default has `w = 1`).
    fn default() -> Self {
        Self::from_yaw(0.0)
    }
}

impl Quaternion {
    /// A rotation of `yaw` radians about +z.
    pub fn from_yaw(yaw: f64) -> Self {
        let (s, c) = (0.5 * yaw).sin_cos();
        Self {
            x: 0.0,
            y: 0.0,
            z: s,
            w: c,
        }
    }

    /// The yaw (rotation about +z, radians in `[−π, π]`) of this rotation, normalized first;
    /// `None` when a component is not finite or the norm is (nearly) zero.
    pub fn yaw(&self) -> Option<f64> {
        let n2 = self.x * self.x + self.y * self.y + self.z * self.z + self.w * self.w;
        if !n2.is_finite() || n2 < 1e-12 {
            return None;
        }
        let (x, y, z, w) = (self.x, self.y, self.z, self.w);
        let yaw = (2.0 * (w * z + x * y)).atan2(n2 - 2.0 * (y * y + z * z));
        yaw.is_finite().then_some(yaw)
    }
}

/// `geometry_msgs/Pose`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    pub position: Point,
    pub orientation: Quaternion,
}

/// A row-major 6×6 covariance of (x, y, z, roll, pitch, yaw): `float64[36]`, written as 36
/// numbers with no length (serde stops its array impls at 32, hence this type).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Covariance6(pub [f64; 36]);

impl Default for Covariance6 {
    fn default() -> Self {
        Self([0.0; 36])
    }
}

impl Serialize for Covariance6 {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeTuple;
        let mut t = s.serialize_tuple(36)?;
        for v in &self.0 {
            t.serialize_element(v)?;
        }
        t.end()
    }
}

impl<'de> Deserialize<'de> for Covariance6 {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Numbers;
        impl<'de> serde::de::Visitor<'de> for Numbers {
            type Value = Covariance6;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("36 float64")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Covariance6, A::Error> {
                let mut c = [0.0; 36];
                for (i, v) in c.iter_mut().enumerate() {
                    *v = seq
                        .next_element()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
                }
                Ok(Covariance6(c))
            }
        }
        d.deserialize_tuple(36, Numbers)
    }
}

/// `geometry_msgs/PoseWithCovariance`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseWithCovariance {
    pub pose: Pose,
    pub covariance: Covariance6,
}

/// `geometry_msgs/PoseWithCovarianceStamped`: `amcl_pose` and `initialpose`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseWithCovarianceStamped {
    pub header: Header,
    pub pose: PoseWithCovariance,
}
impl Message for PoseWithCovarianceStamped {}

/// `geometry_msgs/Transform`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    pub translation: Vector3,
    pub rotation: Quaternion,
}

/// `geometry_msgs/TransformStamped`: the transform from `header.frame_id` to `child_frame_id`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TransformStamped {
    pub header: Header,
    pub child_frame_id: String,
    pub transform: Transform,
}

/// `tf2_msgs/TFMessage`: what `/tf` carries.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TfMessage {
    pub transforms: Vec<TransformStamped>,
}
impl Message for TfMessage {}

/// `std_srvs/Empty`'s request and response: an empty IDL struct, which ROS 2 gives one
/// placeholder byte.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Empty {
    pub structure_needs_at_least_one_member: u8,
}
impl Message for Empty {}

/// `lifecycle_msgs/State`: a managed node's state (ids as rcl_lifecycle numbers them).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct LifecycleState {
    pub id: u8,
    pub label: String,
}

/// `lifecycle_msgs/Transition`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct LifecycleTransition {
    pub id: u8,
    pub label: String,
}

/// `lifecycle_msgs/TransitionDescription`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TransitionDescription {
    pub transition: LifecycleTransition,
    pub start_state: LifecycleState,
    pub goal_state: LifecycleState,
}

/// `lifecycle_msgs/GetState`'s response (its request is empty: [`Empty`]).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GetStateResponse {
    pub current_state: LifecycleState,
}
impl Message for GetStateResponse {}

/// `lifecycle_msgs/ChangeState`'s request.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ChangeStateRequest {
    pub transition: LifecycleTransition,
}
impl Message for ChangeStateRequest {}

/// `lifecycle_msgs/ChangeState`'s response.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ChangeStateResponse {
    pub success: bool,
}
impl Message for ChangeStateResponse {}

/// `lifecycle_msgs/GetAvailableStates`' response.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GetAvailableStatesResponse {
    pub available_states: Vec<LifecycleState>,
}
impl Message for GetAvailableStatesResponse {}

/// `lifecycle_msgs/GetAvailableTransitions`' response (also `get_transition_graph`'s).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GetAvailableTransitionsResponse {
    pub available_transitions: Vec<TransitionDescription>,
}
impl Message for GetAvailableTransitionsResponse {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yaw_round_trips_and_refuses_nonsense() {
        for yaw in [-3.1, -1.0, 0.0, 0.5, 3.1] {
            let q = Quaternion::from_yaw(yaw);
            assert!((q.yaw().unwrap() - yaw).abs() < 1e-12, "{yaw}");
            // Not normalized: the same yaw.
            let s = Quaternion {
                x: q.x * 3.0,
                y: q.y * 3.0,
                z: q.z * 3.0,
                w: q.w * 3.0,
            };
            assert!((s.yaw().unwrap() - yaw).abs() < 1e-12, "{yaw}");
        }
        let nan = Quaternion {
            w: f64::NAN,
            ..Quaternion::default()
        };
        assert_eq!(nan.yaw(), None);
        let zero = Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 0.0,
        };
        assert_eq!(zero.yaw(), None);
    }

    #[test]
    fn time_in_nanoseconds() {
        let t = Time::from_nanos(12_345_678_901);
        assert_eq!(
            t,
            Time {
                sec: 12,
                nanosec: 345_678_901
            }
        );
        assert_eq!(t.to_nanos(), Some(12_345_678_901));
        assert_eq!(
            Time {
                sec: -1,
                nanosec: 0
            }
            .to_nanos(),
            None
        );
        assert_eq!(Time::from_nanos(u64::MAX), Time::MAX);
        let last = u64::try_from(i32::MAX).unwrap() * 1_000_000_000 + 999_999_999;
        assert_eq!(Time::from_nanos(last), Time::MAX);
        assert_eq!(Time::from_nanos(last + 1), Time::MAX);
    }
}
