//! Writing scans as a LiDAR's byte stream: one clockwise revolution per scan in any of the four
//! protocols, with optional start-up garbage, range noise and bit flips.

use super::{Format, LidarError, POINTS_PER_REV};
use beamfield::lidar::assembler::sample_revolution;
use beamfield::lidar::ld06::{self, Ld06Sample};
use beamfield::lidar::rplidar;
use beamfield::lidar::xv11::{self, Xv11Reading};
use beamfield::lidar::ydlidar;
use beamfield::{BeamLayout, Scan};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

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
/// [`LidarError::Assembler`] for a layout the assembler cannot bin,
/// [`LidarError::BadOption`], [`LidarError::Encode`].
pub fn encode_scans<const N: usize>(
    layout: &BeamLayout<N>,
    scans: &[Vec<f32>],
    options: &StreamOptions,
    mut progress: impl FnMut(usize),
) -> Result<(Vec<u8>, EncodeReport), LidarError> {
    if !(options.rpm.is_finite() && options.rpm > 0.0 && options.rpm <= 3000.0) {
        return Err(LidarError::BadOption(
            "--rpm must be in (0, 3000]".to_string(),
        ));
    }
    let ld06_rpm = |deg_per_s: u16| f32::from(deg_per_s) / 6.0;
    let (lo, hi) = (
        ld06_rpm(beamfield::lidar::ld06::MIN_SPEED_DEG_PER_S),
        ld06_rpm(beamfield::lidar::ld06::MAX_SPEED_DEG_PER_S),
    );
    if options.format == Format::Ld06 && !(lo..=hi).contains(&options.rpm) {
        return Err(LidarError::BadOption(format!(
            "--rpm must be in [{lo}, {hi}] for ld06: the decoder takes frames at other speeds as implausible (docs/lidar.md)"
        )));
    }
    if !(options.noise_m.is_finite() && options.noise_m >= 0.0) {
        return Err(LidarError::BadOption(
            "--noise must be a finite number of metres >= 0".to_string(),
        ));
    }
    if !(0.0..=1.0).contains(&options.corrupt_rate) {
        return Err(LidarError::BadOption(
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
        let scan = Scan::<N>::from_ranges(ranges).map_err(LidarError::Layout)?;
        sample_revolution(layout, &scan, &mut rev).map_err(LidarError::Assembler)?;
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
        .map_err(LidarError::Encode)?;
        out.extend_from_slice(&frames[..n]);
        if out.len() as u64 > crate::input::limits::MAX_CAPTURE_BYTES {
            return Err(LidarError::StreamTooLarge);
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
