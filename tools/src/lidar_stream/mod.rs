//! LiDAR byte streams on the host: real scans written as a LiDAR's byte stream ([`encode`]) and
//! streams decoded back into scans ([`decode`]). The frames are written and read by the
//! library's own encoders and decoders (`beamfield::lidar`), so what these produce is what the
//! firmware receives. The CLI is [`crate::cmd::lidar`].

pub mod decode;
pub mod encode;

pub use decode::{
    decode_path, decode_stream, looks_like, sniff, AnyDecoder, Capture, Decoded, StreamDecoder,
};
pub use encode::{
    encode_scans, ydlidar_rotor_samples, EncodeReport, StreamOptions, YDLIDAR_MAX_MISS_DEG,
    YDLIDAR_PER_PACKET,
};

use crate::draw::plot::PlotError;
use crate::input::carmen::LogError;
use beamfield::lidar::ydlidar;
use beamfield::lidar::{AssemblerError, EncodeError};
use beamfield::{BeamLayout, ScanError, SensorMount};
use clap::ValueEnum;
use std::path::PathBuf;

/// Beams a decoded scan can hold (a full turn at 1°).
pub const MAX_BEAMS: usize = 360;
/// Points per revolution written by the encoders (1° apart).
pub const POINTS_PER_REV: usize = 360;

/// Largest `lidar encode --garbage`, bytes: 1 MiB (a real sensor sends a few hundred bytes
/// before its first frame).
pub const MAX_GARBAGE_BYTES: usize = 1 << 20;

/// A sensor protocol.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// LDROBOT LD06 / LD19 / STL-19P: 47-byte frames with CRC-8, 230,400 baud (`ld19` is
    /// accepted for the same protocol).
    #[value(alias = "ld19")]
    Ld06,
    /// SLAMTEC RPLIDAR standard scan: descriptor then 5-byte nodes, 115,200 baud (A1).
    Rplidar,
    /// Neato XV-11 / Xiaomi LDS02RR: 22-byte packets with checksum, 115,200 baud.
    Xv11,
    /// YDLIDAR X4 / X2 / G4: `AA 55` packets of up to 40 samples with an XOR check code,
    /// triangulation angle correction, 128,000 baud (X4).
    Ydlidar,
}

impl Format {
    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ld06 => "ld06",
            Self::Rplidar => "rplidar",
            Self::Xv11 => "xv11",
            Self::Ydlidar => "ydlidar",
        }
    }

    /// Every format, in the order they are tried when a stream is sniffed.
    pub const ALL: [Self; 4] = [Self::Ld06, Self::Rplidar, Self::Xv11, Self::Ydlidar];

    /// The largest range the protocol's distance field carries, metres.
    pub fn field_max_m(self) -> f32 {
        match self {
            Self::Ld06 => 65.535,
            Self::Rplidar => 16.383_75,
            Self::Xv11 => 16.383,
            Self::Ydlidar => ydlidar::MAX_RANGE_M,
        }
    }

    /// The protocol's range resolution, metres.
    pub fn resolution_m(self) -> f32 {
        match self {
            Self::Ld06 | Self::Xv11 => 0.001,
            Self::Rplidar | Self::Ydlidar => 0.000_25,
        }
    }
}

/// Errors of the `lidar` commands.
#[derive(Debug)]
pub enum LidarError {
    /// The log could not be read.
    Log(LogError),
    /// A file could not be read or written.
    Io(PathBuf, std::io::Error),
    /// The log's scans do not form a layout.
    Layout(ScanError),
    /// The layout does not suit the assembler.
    Assembler(AssemblerError),
    /// An encoder refused its input.
    Encode(EncodeError),
    /// A bad option value.
    BadOption(String),
    /// The picture could not be drawn.
    Plot(PlotError),
    /// The capture is longer than [`crate::input::limits::MAX_CAPTURE_BYTES`].
    CaptureTooLarge(PathBuf),
    /// The capture holds more than [`crate::input::limits::MAX_DECODED_SCANS`] scans.
    TooManyScans,
    /// The stream `lidar encode` would write is longer than
    /// [`crate::input::limits::MAX_CAPTURE_BYTES`] (what `lidar decode` reads).
    StreamTooLarge,
    /// No frame of `format` in the whole capture: the stream is not in that protocol.
    NotThisFormat {
        /// The capture.
        path: PathBuf,
        /// The protocol asked for (`--format`).
        format: Format,
        /// Bytes read.
        bytes: u64,
        /// The protocol whose decoder found the most frames in the capture's first
        /// [`decode::SNIFF_BYTES`] bytes, if any found one.
        looks_like: Option<Format>,
    },
}

impl std::fmt::Display for LidarError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Log(e) => write!(f, "{e}"),
            Self::Io(p, e) => write!(f, "{}: {e}", p.display()),
            Self::Layout(e) => write!(f, "scan layout: {e}"),
            Self::Assembler(e) => write!(f, "assembler: {e}"),
            Self::Encode(e) => write!(f, "encoder: {e}"),
            Self::BadOption(s) => f.write_str(s),
            Self::Plot(e) => write!(f, "{e}"),
            Self::CaptureTooLarge(p) => write!(
                f,
                "{} is larger than {} bytes, the limit for a LiDAR capture",
                p.display(),
                crate::input::limits::MAX_CAPTURE_BYTES
            ),
            Self::StreamTooLarge => write!(
                f,
                "the stream would be larger than {} bytes, the limit for a LiDAR capture \
                 (encode fewer --scans)",
                crate::input::limits::MAX_CAPTURE_BYTES
            ),
            Self::NotThisFormat {
                path,
                format,
                bytes,
                looks_like,
            } => {
                let name = format.name();
                if *bytes == 0 {
                    return write!(f, "{} is empty: no {name} frame to decode", path.display());
                }
                write!(
                    f,
                    "{}: no {name} frame in {bytes} bytes: the stream does not look like {name}; ",
                    path.display()
                )?;
                match looks_like {
                    Some(other) => write!(f, "it looks like {0} (try --format {0})", other.name()),
                    None => write!(
                        f,
                        "no other decoder ({}) finds a frame in its first {} bytes either",
                        Format::ALL
                            .iter()
                            .filter(|o| *o != format)
                            .map(|o| o.name())
                            .collect::<Vec<_>>()
                            .join(", "),
                        decode::SNIFF_BYTES
                    ),
                }
            }
            Self::TooManyScans => write!(
                f,
                "the capture holds more than {} scans, the limit for one decode",
                crate::input::limits::MAX_DECODED_SCANS
            ),
        }
    }
}

impl std::error::Error for LidarError {}

/// The beams a decoded stream is assembled on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum LayoutChoice {
    /// 360 beams 1° apart, counter-clockwise from the sensor's zero direction.
    Full,
    /// A CARMEN FLASER front scan: 180 beams 1° apart from −90° (the Intel log's layout).
    Carmen,
}

/// The layout for `choice`, with a maximum range of `max_range_m`.
///
/// # Errors
/// [`LidarError::Layout`] for a bad maximum range.
pub fn layout(choice: LayoutChoice, max_range_m: f32) -> Result<BeamLayout<MAX_BEAMS>, LidarError> {
    let deg = 1f32.to_radians();
    match choice {
        LayoutChoice::Full => {
            BeamLayout::uniform(0.0, deg, 360, max_range_m, SensorMount::CENTERED)
        }
        LayoutChoice::Carmen => BeamLayout::uniform(
            -std::f32::consts::FRAC_PI_2,
            deg,
            180,
            max_range_m,
            SensorMount::CENTERED,
        ),
    }
    .map_err(LidarError::Layout)
}
