//! Host-side (std) tools behind the `beamfield` command: everything that runs on a computer
//! rather than on the microcontroller. The device-side formats and models live in the
//! `beamfield` crate; this crate reads maps and logs, and writes blobs, reports and pictures.
pub mod beam_fit;
pub mod calibrate;
pub mod cmd;
pub mod draw;
pub mod input;
pub mod lidar_stream;
pub mod pose_grid;
pub mod progress;
pub mod track;

pub mod blob;

pub mod demo_assets;
pub mod mapping;
pub mod sonar;
pub mod track_assets;
