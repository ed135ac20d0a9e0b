//! `beamfield lidar encode` and `beamfield lidar decode`: real scans as a LiDAR's byte stream,
//! and back ([`crate::lidar_stream`]). One module per subcommand; [`LidarReport`] is what either
//! reports.

pub mod decode;
pub mod encode;

use crate::lidar_stream::LidarError;
use clap::Subcommand;
use serde::Serialize;
use std::fmt;

/// `beamfield lidar …`
#[derive(Subcommand, Debug)]
pub enum LidarCommand {
    /// Write a CARMEN log's scans as a LiDAR's byte stream.
    ///
    /// Each FLASER scan (beam i at −90° + i·180°/n, counter-clockwise) becomes one clockwise
    /// revolution of 360 points 1° apart; angles the scan does not cover read "no measurement",
    /// and so do ranges the protocol's distance field cannot carry (the Intel log's 81.83 m
    /// max-range value, anything past 16.38 m for RPLIDAR, XV-11 and YDLIDAR). Timestamps (LD06)
    /// and the speed field follow --rpm. YDLIDAR samples are taken at the rotor angles whose
    /// distance-corrected angle lands on a beam (the decoder applies the X4's triangulation
    /// correction), so a few beams per scan come back empty. See docs/lidar.md.
    Encode(encode::EncodeArgs),
    /// Decode a LiDAR byte stream into scans and report the decoder's and the assembler's
    /// counters; optionally draw one scan as a polar plot.
    Decode(decode::DecodeArgs),
}

/// What a `lidar` subcommand reports.
#[derive(Debug, Serialize)]
#[serde(untagged)]
pub enum LidarReport {
    /// `lidar encode`.
    Encode(encode::LidarEncodeReport),
    /// `lidar decode`.
    Decode(decode::LidarDecodeReport),
}

impl fmt::Display for LidarReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Encode(r) => r.fmt(f),
            Self::Decode(r) => r.fmt(f),
        }
    }
}

/// Runs a `lidar` subcommand.
///
/// # Errors
/// Every failure as a [`LidarError`].
pub fn run(command: &LidarCommand) -> Result<LidarReport, LidarError> {
    Ok(match command {
        LidarCommand::Encode(a) => LidarReport::Encode(encode::run(a)?),
        LidarCommand::Decode(a) => LidarReport::Decode(decode::run(a)?),
    })
}
