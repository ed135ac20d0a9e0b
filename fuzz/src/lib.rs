//! What the fuzz targets share (the LiDAR decoders' targets: [`lidar_common`]).

pub mod lidar_common;
