//! Input readers: the CARMEN log reader, the ROS 2 bag reader, the ROS map_server map reader, the sonar ring file reader, and the bounded file and
//! line readers every command reads its inputs through (docs/resource-limits.md).
/// ROS 2 bags: the `beamfield-bag` crate (shared with `cargo xtask robot --bag`).
pub use beamfield_bag as bag;
pub mod carmen;
pub mod field_file;
pub mod kind;
pub mod limits;
pub mod map;
pub mod ring;
