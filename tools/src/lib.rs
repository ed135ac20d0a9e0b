//! Host-side (std) tools behind the `beamfield` command: everything that runs on a computer
//! rather than on the microcontroller. The device-side formats and models live in the
//! `beamfield` crate; this crate reads maps and logs, and writes blobs, reports and pictures.
//!
//! - [`cmd`]: one module per subcommand (`beamfield field build` is [`cmd::field::build`]),
//!   each returning one report that is `Serialize` and `Display`; `main` prints it.
//! - [`input`]: the readers (CARMEN logs, ROS 2 bags, map_server maps, field files, ring files, and the
//!   bounded file and line readers they go through).
//! - [`draw`]: the pictures (charts, heat maps, field figures, overlays, tracks, polar plots,
//!   map pictures).
//! - The work itself: [`blob`] (distance-field blobs from maps), [`mapping`] (maps from logs),
//!   [`pose_grid`] and [`calibrate`] (scores over pose grids, κ), [`beam_fit`] (EM on a log),
//!   [`track`] (localization runs), [`lidar_stream`] (LiDAR byte streams), [`sonar`] (firing
//!   schedules), [`demo_assets`] and [`track_assets`] (the firmware's generated assets),
//!   [`progress`] (progress on stderr).
pub mod beam_fit;
pub mod blob;
pub mod calibrate;
pub mod cmd;
pub mod demo_assets;
pub mod draw;
pub mod input;
pub mod lidar_stream;
pub mod mapping;
pub mod pose_grid;
pub mod progress;
pub mod sonar;
pub mod track;
pub mod track_assets;
