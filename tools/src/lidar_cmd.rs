//! `beamfield lidar encode` and `beamfield lidar decode`: real scans as a LiDAR's byte stream, and
//! back. The frames are written and read by the library's own encoders and decoders
//! (`beamfield::lidar`), so what these commands produce is what the firmware receives.

use crate::draw::plot::{register_fonts, PlotError};
use crate::input::carmen::{CarmenLog, LogError, ReadOptions};
use beamfield::lidar::assembler::sample_revolution;
use beamfield::lidar::ld06::{self, Ld06Decoder, Ld06Sample};
use beamfield::lidar::rplidar::{self, RplidarDecoder};
use beamfield::lidar::xv11::{self, Xv11Decoder, Xv11Reading};
use beamfield::lidar::ydlidar::{self, YdlidarDecoder};
use beamfield::lidar::{
    AssemblerConfig, AssemblerError, AssemblerStats, DecoderStats, EncodeError, LidarPoint,
    Revolution, ScanAssembler,
};
use beamfield::{BeamLayout, Scan, ScanError, SensorMount};
use clap::{Args, Subcommand, ValueEnum};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use std::path::{Path, PathBuf};

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
    /// LDROBOT LD06 / LD19 / STL-19P: 47-byte frames with CRC-8, 230,400 baud.
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
pub enum LidarCmdError {
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
}

impl std::fmt::Display for LidarCmdError {
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
            Self::TooManyScans => write!(
                f,
                "the capture holds more than {} scans, the limit for one decode",
                crate::input::limits::MAX_DECODED_SCANS
            ),
        }
    }
}

impl std::error::Error for LidarCmdError {}

/// How to turn scans into a stream.
#[derive(Clone, Debug)]
pub struct StreamOptions {
    /// The protocol.
    pub format: Format,
    /// Rotation speed, revolutions per minute (> 0).
    pub rpm: f32,
    /// Standard deviation of Gaussian noise added to every carried range, metres (0: none).
    pub noise_m: f32,
    /// Random bytes written before the first frame (start-up garbage).
    pub garbage: usize,
    /// Probability that a byte of the frames gets one random bit flipped.
    pub corrupt_rate: f64,
    /// Seed of the noise, garbage and corruption.
    pub seed: u64,
}

/// What [`encode_scans`] wrote.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EncodeReport {
    /// Revolutions written.
    pub revolutions: usize,
    /// Bytes written in all.
    pub bytes: usize,
    /// Garbage bytes at the start.
    pub garbage: usize,
    /// Bytes that got a bit flipped.
    pub corrupted_bytes: usize,
    /// Ranges the protocol carries (the others are sent as "no measurement").
    pub carried: usize,
}

fn normal(rng: &mut StdRng) -> f32 {
    // Box–Muller; u1 in (0, 1] so the log is finite.
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random::<f64>();
    ((-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()) as f32
}

/// Writes each scan (ranges in `layout`'s beam order) as one clockwise revolution of
/// [`POINTS_PER_REV`] points in `options.format`, after optional start-up garbage, with optional
/// range noise and bit flips.
///
/// # Errors
/// [`LidarCmdError::Assembler`] for a layout the assembler cannot bin,
/// [`LidarCmdError::BadOption`], [`LidarCmdError::Encode`].
pub fn encode_scans<const N: usize>(
    layout: &BeamLayout<N>,
    scans: &[Vec<f32>],
    options: &StreamOptions,
    mut progress: impl FnMut(usize),
) -> Result<(Vec<u8>, EncodeReport), LidarCmdError> {
    if !(options.rpm.is_finite() && options.rpm > 0.0 && options.rpm <= 3000.0) {
        return Err(LidarCmdError::BadOption(
            "--rpm must be in (0, 3000]".to_string(),
        ));
    }
    let ld06_rpm = |deg_per_s: u16| f32::from(deg_per_s) / 6.0;
    let (lo, hi) = (
        ld06_rpm(beamfield::lidar::ld06::MIN_SPEED_DEG_PER_S),
        ld06_rpm(beamfield::lidar::ld06::MAX_SPEED_DEG_PER_S),
    );
    if options.format == Format::Ld06 && !(lo..=hi).contains(&options.rpm) {
        return Err(LidarCmdError::BadOption(format!(
            "--rpm must be in [{lo}, {hi}] for ld06: the decoder takes frames at other speeds as implausible (docs/lidar.md)"
        )));
    }
    if !(options.noise_m.is_finite() && options.noise_m >= 0.0) {
        return Err(LidarCmdError::BadOption(
            "--noise must be a finite number of metres >= 0".to_string(),
        ));
    }
    if !(0.0..=1.0).contains(&options.corrupt_rate) {
        return Err(LidarCmdError::BadOption(
            "--corrupt must be a probability in [0, 1]".to_string(),
        ));
    }
    let mut rng = StdRng::seed_from_u64(options.seed);
    let mut out: Vec<u8> = (0..options.garbage).map(|_| rng.random::<u8>()).collect();
    let mut report = EncodeReport {
        garbage: options.garbage,
        ..EncodeReport::default()
    };
    let period_ms = 60_000.0 / f64::from(options.rpm);
    if options.format == Format::Rplidar {
        out.extend_from_slice(&rplidar::SCAN_DESCRIPTOR);
    }
    let mut rev = vec![0.0f32; POINTS_PER_REV];
    // YDLIDAR: the previous revolution's ranges (see `ydlidar_rotor_samples`).
    let mut prev: Option<Vec<f32>> = None;
    let mut frames = vec![0u8; POINTS_PER_REV * 8];
    for (k, ranges) in scans.iter().enumerate() {
        let scan = Scan::<N>::from_ranges(ranges).map_err(LidarCmdError::Layout)?;
        sample_revolution(layout, &scan, &mut rev).map_err(LidarCmdError::Assembler)?;
        for r in rev.iter_mut().filter(|r| r.is_finite()) {
            if options.noise_m > 0.0 {
                *r = (*r + options.noise_m * normal(&mut rng)).max(0.0);
            }
        }
        report.carried += rev
            .iter()
            .filter(|&&r| {
                let q = r / options.format.resolution_m();
                q >= 0.5 && r < options.format.field_max_m() + 0.5 * options.format.resolution_m()
            })
            .count();
        let n = match options.format {
            Format::Ld06 => {
                let samples: Vec<Ld06Sample> = rev
                    .iter()
                    .map(|&r| Ld06Sample::from_range_m(r, 200))
                    .collect();
                let speed = (options.rpm * 6.0).round().clamp(1.0, 65_535.0) as u16;
                let ts = ((k as f64 * period_ms).round() as u64 % 30_000) as u16;
                ld06::encode_revolution(&samples, speed, ts, &mut frames)
            }
            Format::Rplidar => rplidar::encode_revolution(&rev, 47, &mut frames),
            Format::Xv11 => {
                let readings: [Xv11Reading; 360] =
                    std::array::from_fn(|a| Xv11Reading::from_range_m(rev[a], 1000));
                let speed = (options.rpm * 64.0).round().clamp(0.0, 65_535.0) as u16;
                xv11::encode_revolution(&readings, speed, &mut frames)
            }
            Format::Ydlidar => {
                let freq = (options.rpm / 6.0).round().clamp(0.0, 127.0) as u8;
                let q2 = ydlidar_rotor_samples(prev.as_deref(), &rev);
                ydlidar::encode_revolution(&q2, YDLIDAR_PER_PACKET, freq, &mut frames)
            }
        }
        .map_err(LidarCmdError::Encode)?;
        out.extend_from_slice(&frames[..n]);
        if out.len() as u64 > crate::input::limits::MAX_CAPTURE_BYTES {
            return Err(LidarCmdError::StreamTooLarge);
        }
        if options.format == Format::Ydlidar {
            prev = Some(rev.clone());
        }
        report.revolutions += 1;
        progress(k + 1);
    }
    if options.corrupt_rate > 0.0 {
        for b in out.iter_mut().skip(options.garbage) {
            if rng.random::<f64>() < options.corrupt_rate {
                *b ^= 1 << rng.random_range(0..8u32);
                report.corrupted_bytes += 1;
            }
        }
    }
    report.bytes = out.len();
    Ok((out, report))
}

/// Samples per YDLIDAR cloud packet written by the encoder (an X4 sends up to 40).
pub const YDLIDAR_PER_PACKET: usize = 40;

/// Largest miss, degrees, between where a YDLIDAR sample's corrected angle lands and the beam whose
/// range it carries (below half the 1° step, so the assembler bins it on that beam).
pub const YDLIDAR_MAX_MISS_DEG: f64 = 0.495;

/// What a triangulation YDLIDAR measures at rotor angles 0°, 1°, … 359° (clockwise) when the
/// world is the revolution `rev` (`rev[a]`: the range at clockwise bearing `a`°, NaN for none).
///
/// The decoder moves a sample of distance `d` from its rotor angle `k` to `k + c(d)`
/// ([`ydlidar::angle_correction_deg`]: about −7° from 0.5 m on). So the sample at rotor angle `k`
/// carries the range of the bearing `a` whose `a − c(r_a)` is nearest `k`, when that lands within
/// [`YDLIDAR_MAX_MISS_DEG`] of `a` (the corrected angle falls in `a`'s beam); otherwise it reads
/// "no measurement". Some bearings are then carried by no rotor angle, some by two: as with the
/// real sensor, whose corrected points do not fall on a uniform grid.
///
/// The first rotor angles see bearings just short of 360°: their corrected points arrive before
/// the assembler's 0° crossing, so they belong with the previous revolution and carry `prev`'s
/// ranges ("no measurement" without one); a sample is only sent when its corrected angle falls on
/// the same side of 0° as its bearing, never past 360°, and the samples before 0° only in an
/// unbroken run from rotor angle 0° (any other point, even an empty one read at its rotor angle,
/// is the assembler's 0° crossing). Decoded on the assembler, revolution
/// `r` then comes back whole as scan `r`.
pub fn ydlidar_rotor_samples(prev: Option<&[f32]>, rev: &[f32]) -> Vec<u16> {
    let n = rev.len() as i64;
    let quarter_mm = |r: &[f32]| -> Vec<u16> {
        r.iter()
            .map(|&x| ydlidar::distance_q2_from_range_m(x))
            .collect()
    };
    let q2 = quarter_mm(rev);
    let q2_prev = prev.map_or_else(|| vec![0; rev.len()], quarter_mm);
    let corr = |q: u16| {
        let d = f64::from(q) / 4.0;
        (21.8 * (155.3 - d) / (155.3 * d)).atan().to_degrees()
    };
    let mut before_zero = true;
    (0..n)
        .map(|k| {
            // (miss, sample, lands before 0°)
            let mut best = (f64::INFINITY, 0u16, false);
            for off in -30..=30i64 {
                let a = k + off;
                let q = if a < 0 {
                    q2_prev.get((a + n) as usize).copied().unwrap_or(0)
                } else {
                    q2.get(a as usize).copied().unwrap_or(0)
                };
                if q == 0 {
                    continue;
                }
                let landed = k as f64 + corr(q);
                // Before 0° (previous revolution) exactly when the bearing is; never past 360°.
                if (landed < 0.0) != (a < 0) || landed >= n as f64 {
                    continue;
                }
                let miss = (landed - a as f64).abs();
                if miss < best.0 {
                    best = (miss, q, a < 0);
                }
            }
            let (miss, q, before) = best;
            // The assembler closes the revolution at the first point past 0° (an empty sample
            // reads at its rotor angle, k ≥ 0°): points before 0° must come first, in one run.
            let send = miss <= YDLIDAR_MAX_MISS_DEG && (before_zero || !before);
            if !(send && before) {
                before_zero = false;
            }
            if send {
                q
            } else {
                0
            }
        })
        .collect()
}

/// One of the four decoders.
#[derive(Clone, Debug)]
pub enum AnyDecoder {
    /// LD06 family.
    Ld06(Ld06Decoder),
    /// RPLIDAR (waiting for the scan descriptor).
    Rplidar(RplidarDecoder),
    /// XV-11.
    Xv11(Xv11Decoder),
    /// YDLIDAR, triangulation angle correction (boxed: it holds a 520-byte packet buffer).
    Ydlidar(Box<YdlidarDecoder>),
}

impl AnyDecoder {
    /// A fresh decoder for `format`.
    pub fn new(format: Format) -> Self {
        match format {
            Format::Ld06 => Self::Ld06(Ld06Decoder::new()),
            Format::Rplidar => Self::Rplidar(RplidarDecoder::new()),
            Format::Xv11 => Self::Xv11(Xv11Decoder::new()),
            Format::Ydlidar => Self::Ydlidar(Box::new(YdlidarDecoder::new())),
        }
    }

    /// Feeds bytes (see each decoder's `feed`).
    pub fn feed(&mut self, bytes: &[u8], on_point: impl FnMut(LidarPoint)) {
        match self {
            Self::Ld06(d) => d.feed(bytes, on_point),
            Self::Rplidar(d) => d.feed(bytes, on_point),
            Self::Xv11(d) => d.feed(bytes, on_point),
            Self::Ydlidar(d) => d.feed(bytes, on_point),
        }
    }

    /// The end of a recording: hands out what a decoder holds back (the YDLIDAR decoder's last
    /// packet, which waits for the next packet's header); nothing for the others.
    pub fn finish(&mut self, on_point: impl FnMut(LidarPoint)) {
        if let Self::Ydlidar(d) = self {
            d.flush(on_point);
        }
    }

    /// The decoder's counters.
    pub fn stats(&self) -> DecoderStats {
        match self {
            Self::Ld06(d) => d.stats(),
            Self::Rplidar(d) => d.stats(),
            Self::Xv11(d) => d.stats(),
            Self::Ydlidar(d) => d.stats(),
        }
    }
}

/// The scans decoded from a stream.
#[derive(Clone, Debug)]
pub struct Decoded {
    /// Each emitted scan's ranges (NaN for empty beams).
    pub scans: Vec<Vec<f32>>,
    /// Each emitted scan's revolution record.
    pub revolutions: Vec<Revolution>,
    /// The decoder's counters at the end.
    pub decoder: DecoderStats,
    /// The assembler's counters at the end.
    pub assembler: AssemblerStats,
}

/// A decoder and an assembler fed a stream chunk by chunk, keeping at most `max_scans` scans.
pub struct StreamDecoder<const N: usize> {
    decoder: AnyDecoder,
    assembler: ScanAssembler<N>,
    scans: Vec<Vec<f32>>,
    revolutions: Vec<Revolution>,
    max_scans: usize,
    overflow: bool,
}

impl<const N: usize> StreamDecoder<N> {
    /// A decoder for `format` assembling on `layout`, keeping at most `max_scans` scans.
    ///
    /// # Errors
    /// [`LidarCmdError::Assembler`] for a layout the assembler cannot bin.
    pub fn new(
        format: Format,
        layout: &BeamLayout<N>,
        config: AssemblerConfig,
        max_scans: usize,
    ) -> Result<Self, LidarCmdError> {
        Ok(Self {
            decoder: AnyDecoder::new(format),
            assembler: ScanAssembler::new(layout, config).map_err(LidarCmdError::Assembler)?,
            scans: Vec::new(),
            revolutions: Vec::new(),
            max_scans,
            overflow: false,
        })
    }

    /// Feeds `bytes` (`None`: the end of the stream) and keeps the scans completed.
    fn run(&mut self, bytes: Option<&[u8]>) -> Result<(), LidarCmdError> {
        let Self {
            decoder,
            assembler,
            scans,
            revolutions,
            max_scans,
            overflow,
        } = self;
        let mut keep = |assembler: &ScanAssembler<N>| {
            if scans.len() >= *max_scans {
                *overflow = true;
            } else {
                scans.push(assembler.scan().ranges_m().to_vec());
                revolutions.push(assembler.revolution());
            }
        };
        let mut on_point = |p| {
            if assembler.push(p).is_some() {
                keep(assembler);
            }
        };
        match bytes {
            Some(b) => decoder.feed(b, &mut on_point),
            None => {
                decoder.finish(&mut on_point);
                if assembler.finish().is_some() {
                    keep(assembler);
                }
            }
        }
        if *overflow {
            Err(LidarCmdError::TooManyScans)
        } else {
            Ok(())
        }
    }

    /// Feeds the next bytes of the stream.
    ///
    /// # Errors
    /// [`LidarCmdError::TooManyScans`] once more than `max_scans` scans were assembled.
    pub fn feed(&mut self, bytes: &[u8]) -> Result<(), LidarCmdError> {
        self.run(Some(bytes))
    }

    /// The end of the stream: what the decoder held back, and the last, unfinished revolution.
    ///
    /// # Errors
    /// [`LidarCmdError::TooManyScans`].
    pub fn finish(mut self) -> Result<Decoded, LidarCmdError> {
        self.run(None)?;
        Ok(Decoded {
            decoder: self.decoder.stats(),
            assembler: self.assembler.stats(),
            scans: self.scans,
            revolutions: self.revolutions,
        })
    }
}

/// Decodes `bytes` in `format` and assembles the points on `layout` (the last, unfinished
/// revolution is emitted too).
///
/// # Errors
/// [`LidarCmdError::Assembler`] for a layout the assembler cannot bin,
/// [`LidarCmdError::TooManyScans`] past [`crate::input::limits::MAX_DECODED_SCANS`].
pub fn decode_stream<const N: usize>(
    format: Format,
    layout: &BeamLayout<N>,
    config: AssemblerConfig,
    bytes: &[u8],
) -> Result<Decoded, LidarCmdError> {
    let mut d = StreamDecoder::new(
        format,
        layout,
        config,
        crate::input::limits::MAX_DECODED_SCANS,
    )?;
    d.feed(bytes)?;
    d.finish()
}

/// Decodes the capture at `path` (a file, a FIFO or a device: read as a stream, in chunks, never
/// held whole) in `format` on `layout`; returns the scans and the number of bytes read.
///
/// # Errors
/// [`LidarCmdError::Io`], [`LidarCmdError::CaptureTooLarge`] past `max_bytes`,
/// [`LidarCmdError::TooManyScans`] past `max_scans`, [`LidarCmdError::Assembler`].
pub fn decode_path<const N: usize>(
    path: &Path,
    format: Format,
    layout: &BeamLayout<N>,
    config: AssemblerConfig,
    max_bytes: u64,
    max_scans: usize,
) -> Result<(Decoded, u64), LidarCmdError> {
    use std::io::Read;
    let io = |e| LidarCmdError::Io(path.to_path_buf(), e);
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut d = StreamDecoder::new(format, layout, config, max_scans)?;
    let mut chunk = vec![0u8; 64 * 1024];
    let mut total = 0u64;
    loop {
        let n = match file.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(io(e)),
        };
        total += n as u64;
        if total > max_bytes {
            return Err(LidarCmdError::CaptureTooLarge(path.to_path_buf()));
        }
        d.feed(chunk.get(..n).unwrap_or(&[]))?;
    }
    Ok((d.finish()?, total))
}

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
/// [`LidarCmdError::Layout`] for a bad maximum range.
pub fn layout(
    choice: LayoutChoice,
    max_range_m: f32,
) -> Result<BeamLayout<MAX_BEAMS>, LidarCmdError> {
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
    .map_err(LidarCmdError::Layout)
}

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
    Encode(EncodeArgs),
    /// Decode a LiDAR byte stream into scans and report the decoder's and the assembler's
    /// counters; optionally draw one scan as a polar plot.
    Decode(DecodeArgs),
}

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

/// Arguments of `beamfield lidar decode`.
#[derive(Args, Debug)]
pub struct DecodeArgs {
    /// The stream file.
    pub stream: PathBuf,
    /// The sensor protocol.
    #[arg(long, value_enum)]
    pub format: Format,
    /// The beams to assemble on.
    #[arg(long, value_enum, default_value = "full")]
    pub layout: LayoutChoice,
    /// Maximum range of the layout, metres (default: the protocol's largest distance).
    #[arg(long, value_name = "M")]
    pub max_range: Option<f32>,
    /// Reject points nearer than this, metres.
    #[arg(long, default_value_t = 0.0, value_name = "M")]
    pub min_range: f32,
    /// Reject points whose quality is below this (protocol units).
    #[arg(long, default_value_t = 0, value_name = "Q")]
    pub min_quality: u16,
    /// Draw this scan (index among the decoded ones; default: the last) as a polar plot.
    #[arg(long, value_name = "K")]
    pub scan: Option<usize>,
    /// Also print every scan's ranges (JSON: `scans[k].ranges_m`, null for empty beams).
    #[arg(long)]
    pub ranges: bool,
    /// Polar plot of one scan (PNG).
    #[arg(short, long, value_name = "polar.png")]
    pub output: Option<PathBuf>,
}

/// Runs a `lidar` subcommand; returns what to print on stdout.
///
/// # Errors
/// Every failure as a [`LidarCmdError`].
pub fn run(command: &LidarCommand, json: bool) -> Result<String, LidarCmdError> {
    match command {
        LidarCommand::Encode(a) => run_encode(a, json),
        LidarCommand::Decode(a) => run_decode(a, json),
    }
}

fn run_encode(a: &EncodeArgs, json: bool) -> Result<String, LidarCmdError> {
    crate::progress::note(&format!("reading {} …", a.log.display()));
    let log = CarmenLog::read_path(&a.log, ReadOptions::default()).map_err(LidarCmdError::Log)?;
    let layout: BeamLayout<MAX_BEAMS> = log
        .layout_with_mount(SensorMount::CENTERED)
        .map_err(LidarCmdError::Layout)?;
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
    let (bytes, report) = encode_scans(&layout, &scans, &options, |k| {
        if k % 200 == 0 || k == total {
            crate::progress::note(&format!("encoded {k}/{total} scans"));
        }
    })?;
    std::fs::write(&a.output, &bytes).map_err(|e| LidarCmdError::Io(a.output.clone(), e))?;
    if json {
        return Ok(serde_json::json!({
            "format": a.format.name(),
            "output": a.output.display().to_string(),
            "revolutions": report.revolutions,
            "points_per_revolution": POINTS_PER_REV,
            "bytes": report.bytes,
            "garbage": report.garbage,
            "corrupted_bytes": report.corrupted_bytes,
            "ranges_carried": report.carried,
            "rpm": a.rpm,
            "seed": a.seed,
        })
        .to_string());
    }
    Ok(format!(
        "{}: {} revolutions of {} points, {} bytes ({} garbage, {} corrupted), {} ranges carried → {}",
        a.format.name(),
        report.revolutions,
        POINTS_PER_REV,
        report.bytes,
        report.garbage,
        report.corrupted_bytes,
        report.carried,
        a.output.display()
    ))
}

fn stats_json(d: &DecoderStats) -> serde_json::Value {
    serde_json::json!({
        "bytes": d.bytes,
        "frames_ok": d.frames_ok,
        "bad_checksum": d.bad_checksum,
        "bad_frames": d.bad_frames,
        "implausible_frames": d.implausible_frames,
        "skipped_bytes": d.skipped_bytes,
        "resyncs": d.resyncs,
        "points": d.points,
    })
}

fn assembler_json(a: &AssemblerStats) -> serde_json::Value {
    serde_json::json!({
        "points": a.points,
        "accepted": a.accepted,
        "flagged_invalid": a.flagged_invalid,
        "out_of_range": a.out_of_range,
        "low_quality": a.low_quality,
        "bad_angle": a.bad_angle,
        "outside_layout": a.outside_layout,
        "replaced": a.replaced,
        "revolutions": a.revolutions,
        "missed_revolutions": a.missed_revolutions,
    })
}

fn run_decode(a: &DecodeArgs, json: bool) -> Result<String, LidarCmdError> {
    let max_range = a.max_range.unwrap_or(a.format.field_max_m() + 1.0);
    let layout = layout(a.layout, max_range)?;
    let config = AssemblerConfig {
        min_range_m: a.min_range,
        max_range_m: max_range,
        min_quality: a.min_quality,
        ..AssemblerConfig::for_layout(&layout)
    };
    crate::progress::note(&format!("decoding {} …", a.stream.display()));
    let (d, bytes) = decode_path(
        &a.stream,
        a.format,
        &layout,
        config,
        crate::input::limits::MAX_CAPTURE_BYTES,
        crate::input::limits::MAX_DECODED_SCANS,
    )?;
    if let Some(path) = &a.output {
        let k = a.scan.unwrap_or(d.scans.len().saturating_sub(1));
        let ranges = d.scans.get(k).ok_or_else(|| {
            LidarCmdError::BadOption(format!("--scan {k}: only {} scans decoded", d.scans.len()))
        })?;
        polar_png(
            path,
            &layout,
            ranges,
            &format!("{} scan {k}", a.format.name()),
        )?;
    }
    if json {
        let scans: Vec<serde_json::Value> = d
            .revolutions
            .iter()
            .zip(&d.scans)
            .map(|(r, s)| {
                let mut v = serde_json::json!({
                    "index": r.index,
                    "points": r.points,
                    "filled": r.filled,
                    "start_timestamp_ms": r.start_timestamp_ms,
                    "end_timestamp_ms": r.end_timestamp_ms,
                });
                if a.ranges {
                    v["ranges_m"] = s
                        .iter()
                        .map(|&x| {
                            if x.is_finite() {
                                serde_json::Value::from(f64::from(x))
                            } else {
                                serde_json::Value::Null
                            }
                        })
                        .collect();
                }
                v
            })
            .collect();
        return Ok(serde_json::json!({
            "format": a.format.name(),
            "bytes": bytes,
            "decoder": stats_json(&d.decoder),
            "assembler": assembler_json(&d.assembler),
            "scans": scans,
        })
        .to_string());
    }
    let s = &d.decoder;
    let asm = &d.assembler;
    let mut out = format!(
        "{}: {} bytes, {} frames ok, {} bad checksum, {} bad frames, {} implausible frames, {} bytes skipped ({} resyncs)\n\
         {} points: {} binned, {} flagged invalid, {} out of range, {} low quality, {} outside the layout, {} replaced\n\
         {} scans ({} revolutions missed)",
        a.format.name(),
        bytes,
        s.frames_ok,
        s.bad_checksum,
        s.bad_frames,
        s.implausible_frames,
        s.skipped_bytes,
        s.resyncs,
        asm.points,
        asm.accepted,
        asm.flagged_invalid,
        asm.out_of_range,
        asm.low_quality,
        asm.outside_layout,
        asm.replaced,
        d.scans.len(),
        asm.missed_revolutions,
    );
    if a.ranges {
        for r in &d.scans {
            out.push('\n');
            let line: Vec<String> = r.iter().map(|x| format!("{x}")).collect();
            out.push_str(&line.join(" "));
        }
    }
    Ok(out)
}

/// Draws one scan's end points (sensor frame, x forward, y left) as a PNG.
///
/// # Errors
/// [`LidarCmdError::Plot`].
pub fn polar_png<const N: usize>(
    path: &Path,
    layout: &BeamLayout<N>,
    ranges: &[f32],
    title: &str,
) -> Result<(), LidarCmdError> {
    use plotters::prelude::*;
    let perr = |e: &dyn std::fmt::Display| LidarCmdError::Plot(PlotError(e.to_string()));
    register_fonts();
    let pts: Vec<(f64, f64)> = layout
        .beams()
        .iter()
        .zip(ranges)
        .filter(|(_, r)| r.is_finite() && **r < layout.max_range_m())
        .map(|(b, &r)| (f64::from(r * b.cos), f64::from(r * b.sin)))
        .collect();
    let extent = pts
        .iter()
        .fold(1.0f64, |m, &(x, y)| m.max(x.abs()).max(y.abs()))
        * 1.05;
    let root = BitMapBackend::new(path, (700, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| perr(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(-extent..extent, -extent..extent)
        .map_err(|e| perr(&e))?;
    chart
        .configure_mesh()
        .x_desc("x forward (m)")
        .y_desc("y left (m)")
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(|e| perr(&e))?;
    chart
        .draw_series(
            pts.iter()
                .map(|&p| Circle::new(p, 2, RGBColor(31, 119, 180).filled())),
        )
        .map_err(|e| perr(&e))?;
    chart
        .draw_series(std::iter::once(Circle::new((0.0, 0.0), 4, RED.filled())))
        .map_err(|e| perr(&e))?;
    root.present().map_err(|e| perr(&e))?;
    Ok(())
}
