#![doc = include_str!("../README.md")]
#![cfg_attr(not(test), no_std)]

pub mod beam;
pub mod intrinsics;
pub mod math;
pub mod pose;
pub mod scan;
pub mod sonar;

pub use beam::{BeamModel, Components, BEAM_LOG_FLOOR};
pub use intrinsics::{BeamIntrinsics, IntrinsicsError, Param};
pub use pose::{wrap_angle, Pose, SensorMount};
pub use scan::{Beam, BeamLayout, Reading, Scan, ScanError, ScanScore};
