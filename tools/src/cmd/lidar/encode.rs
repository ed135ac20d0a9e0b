//! `beamfield lidar encode`: a CARMEN log's scans written as an LD06, RPLIDAR, XV-11 or YDLIDAR
//! byte stream.

use crate::input::carmen::{CarmenLog, ReadOptions};
use crate::lidar_stream::{
    encode_scans, EncodeReport, Format, LidarError, StreamOptions, MAX_BEAMS, MAX_GARBAGE_BYTES,
    POINTS_PER_REV,
};
use beamfield::{BeamLayout, SensorMount};
use clap::Args;
use serde::Serialize;
use std::fmt;
use std::path::PathBuf;

/// Arguments of `beamfield lidar encode`.
#[derive(Args, Debug)]
pub struct EncodeArgs {
    /// The CARMEN log whose scans are written.
    #[arg(long)]
    pub log: PathBuf,
    /// The sensor protocol.
    #[arg(long, value_enum)]
    pub format: Format,
    /// Rotation speed, revolutions per minute.
    #[arg(long, default_value_t = 600.0, value_name = "R")]
    pub rpm: f32,
    /// Standard deviation of Gaussian range noise, metres.
    #[arg(long, default_value_t = 0.0, value_name = "M")]
    pub noise: f32,
    /// Random start-up bytes before the first frame (at most 1 MiB).
    #[arg(long, default_value_t = 0, value_name = "BYTES",
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(0..=MAX_GARBAGE_BYTES as u64))]
    pub garbage: usize,
    /// Probability that a byte gets one random bit flipped.
    #[arg(long, default_value_t = 0.0, value_name = "RATE")]
    pub corrupt: f64,
    /// Seed of the noise, garbage and corruption.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Only the first this many scans.
    #[arg(long, value_name = "N")]
    pub scans: Option<usize>,
    /// Output stream file.
    #[arg(short, long, value_name = "STREAM.bin")]
    pub output: PathBuf,
}

/// What `lidar encode` wrote.
#[derive(Debug, Serialize)]
pub struct LidarEncodeReport {
    /// The protocol's name.
    pub format: &'static str,
    /// The stream file.
    pub output: String,
    /// Revolutions written.
    pub revolutions: usize,
    /// Points per revolution.
    pub points_per_revolution: usize,
    /// Stream length, bytes.
    pub bytes: usize,
    /// Start-up garbage, bytes.
    pub garbage: usize,
    /// Bytes with a bit flipped.
    pub corrupted_bytes: usize,
    /// Ranges the protocol could carry.
    pub ranges_carried: usize,
    /// Rotation speed, rpm.
    pub rpm: f32,
    /// The seed.
    pub seed: u64,
}

/// Runs `lidar encode`.
///
/// # Errors
/// [`LidarError`].
pub fn run(a: &EncodeArgs) -> Result<LidarEncodeReport, LidarError> {
    crate::progress::note(&format!("reading {} …", a.log.display()));
    let log = CarmenLog::read_path(&a.log, ReadOptions::default()).map_err(LidarError::Log)?;
    let layout: BeamLayout<MAX_BEAMS> = log
        .layout_with_mount(SensorMount::CENTERED)
        .map_err(LidarError::Layout)?;
    let take = a.scans.unwrap_or(log.scans.len()).min(log.scans.len());
    let scans: Vec<Vec<f32>> = log.scans[..take]
        .iter()
        .map(|s| s.ranges_m.clone())
        .collect();
    let options = StreamOptions {
        format: a.format,
        rpm: a.rpm,
        noise_m: a.noise,
        garbage: a.garbage,
        corrupt_rate: a.corrupt,
        seed: a.seed,
    };
    let total = scans.len();
    let (bytes, report): (Vec<u8>, EncodeReport) = encode_scans(&layout, &scans, &options, |k| {
        if k % 200 == 0 || k == total {
            crate::progress::note(&format!("encoded {k}/{total} scans"));
        }
    })?;
    std::fs::write(&a.output, &bytes).map_err(|e| LidarError::Io(a.output.clone(), e))?;
    Ok(LidarEncodeReport {
        format: a.format.name(),
        output: a.output.display().to_string(),
        revolutions: report.revolutions,
        points_per_revolution: POINTS_PER_REV,
        bytes: report.bytes,
        garbage: report.garbage,
        corrupted_bytes: report.corrupted_bytes,
        ranges_carried: report.carried,
        rpm: a.rpm,
        seed: a.seed,
    })
}

impl fmt::Display for LidarEncodeReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} revolutions of {} points, {} bytes ({} garbage, {} corrupted), {} ranges carried → {}",
            self.format,
            self.revolutions,
            self.points_per_revolution,
            self.bytes,
            self.garbage,
            self.corrupted_bytes,
            self.ranges_carried,
            self.output
        )
    }
}
