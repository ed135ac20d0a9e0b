//! The host side of `cargo xtask lidar`: the LD06 stream sent into the emulated USART (a real
//! segment of consecutive Intel-lab scans, `fixtures/assets/lidar_segment.rs`, written by the library's LD06 encoder, with start-up noise and a few
//! corrupted frames), what the plan alone says the device must find in it, and the host's
//! recomputation of the device's report with the same crate and the same plan
//! (`fixtures/src/lidar_plan.rs`, shared word for word with the firmware).

use crate::error::{Error, Result};
use beamfield_fixtures::{demo_plan, lidar_plan};

use beamfield::lidar::ld06::{self, Ld06Decoder, Ld06Sample};
use beamfield::Pose;
use demo_plan::POSES;
use host_tests::splitmix::Draws;
use lidar_plan::segment::{MAX_RANGE_M, SCANS};
use lidar_plan::BEAMS;

/// Points per LD06 revolution in the stream: one per degree (the encoder's 1° layout).
const SAMPLES: usize = 360;
/// Rotation speed written into the frames: 3,600 °/s, the LD06's nominal 10 Hz.
const SPEED_DEG_PER_S: u16 = 3_600;
/// Intensity of a point with a return (the LD06 reports 0..=255).
const INTENSITY: u8 = 200;
/// Frames per revolution.
pub const FRAMES_PER_REV: usize = SAMPLES / ld06::POINTS_PER_FRAME;
/// Frames whose checksum the stream breaks, `(scan, frame, byte, bit)`: a distance byte of a
/// frame in the middle of scan 1, the first frame of scan 3 (the one whose points close the
/// previous revolution) and the last frame of scan 6 (its timestamp).
pub const FLIPS: [(usize, usize, usize, u8); 3] = [(1, 4, 20, 3), (3, 0, 10, 0), (6, 29, 44, 7)];
/// Bytes of line noise before the first frame (the receiver starts mid-stream).
pub const STARTUP_NOISE: usize = 40;
/// Bytes of line noise inserted between frames 10 and 11 of scan 4.
pub const INSERTED_NOISE: (usize, usize, usize) = (4, 10, 5);

/// The stream and what the plan alone says about it.
pub struct Stream {
    /// The bytes sent into the USART.
    pub bytes: Vec<u8>,
    /// Revolutions (scans) written.
    pub scans: usize,
    /// Frames written.
    pub frames: usize,
    /// Per scan: beams of the log with a return whose frame is corrupted (the device must
    /// report them missing, and every other beam matching).
    pub missing: Vec<u16>,
    /// Bytes of noise (start-up and inserted).
    pub noise: usize,
}

/// Noise that contains no LD06 header byte (0x54), so the counters it causes follow from the
/// plan alone (a header byte in noise is the library's corruption tests' business).
fn noise(rng: &mut host_tests::splitmix::SplitMix64, n: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let b = rng.next_u64() as u8;
        if b != ld06::HEADER {
            out.push(b);
        }
    }
    out
}

/// The Intel beam at clockwise angle `cw_deg` of the sensor: beam `i` looks at −90° + i°
/// counter-clockwise, i.e. `90 − i` degrees clockwise. `None` behind the laser.
fn beam_at(cw_deg: usize) -> Option<usize> {
    let i = (90 + 360 - cw_deg) % 360;
    (i < BEAMS).then_some(i)
}

/// Writes the 24 consecutive real scans of `fixtures/assets/lidar_segment.rs` (Intel log
/// FLASER scans 300 … 323) as LD06 revolutions (one point per degree, clockwise from
/// 0°; no return behind the laser and for the log's max-range readings), with the noise and
/// the corrupted frames of the plan.
pub fn stream() -> Result<Stream> {
    let mut rng = host_tests::splitmix::SplitMix64::new(0x1d06_0000_5eed);
    let mut bytes = noise(&mut rng, STARTUP_NOISE);
    let mut noise_total = STARTUP_NOISE;
    let mut missing = vec![0u16; SCANS.len()];
    let mut rev = vec![0u8; ld06::revolution_len(SAMPLES)];
    for (k, scan) in SCANS.iter().enumerate() {
        let samples: Vec<Ld06Sample> = (0..SAMPLES)
            .map(|cw| match beam_at(cw).map(|i| scan.ranges_m[i]) {
                // The library's rule: the distance rounded to the millimetre.
                Some(r) if r < MAX_RANGE_M => Ld06Sample::from_range_m(r, INTENSITY),
                _ => Ld06Sample::default(),
            })
            .collect();
        if let Some(r) = scan
            .ranges_m
            .iter()
            .find(|&&r| r < MAX_RANGE_M && r > 65.535)
        {
            return Err(Error::Host(format!(
                "scan {k}: range {r} m does not fit an LD06 distance"
            )));
        }
        let n = ld06::encode_revolution(&samples, SPEED_DEG_PER_S, (k * 100) as u16, &mut rev)
            .map_err(|e| Error::Host(format!("LD06 encoder: {e}")))?;
        for (f, frame) in rev[..n].chunks(ld06::FRAME_LEN).enumerate() {
            let mut frame = frame.to_vec();
            for &(fs, ff, byte, bit) in &FLIPS {
                if (fs, ff) == (k, f) {
                    frame[byte] ^= 1 << bit;
                    missing[k] += (f * 12..f * 12 + 12)
                        .filter_map(beam_at)
                        .filter(|&i| scan.ranges_m[i] < MAX_RANGE_M)
                        .count() as u16;
                }
            }
            bytes.extend_from_slice(&frame);
            if (k, f) == (INSERTED_NOISE.0, INSERTED_NOISE.1) {
                bytes.extend(noise(&mut rng, INSERTED_NOISE.2));
                noise_total += INSERTED_NOISE.2;
            }
        }
    }
    Ok(Stream {
        bytes,
        scans: SCANS.len(),
        frames: SCANS.len() * FRAMES_PER_REV,
        missing,
        noise: noise_total,
    })
}

/// The host's version of one scan line of the device's report.
pub struct ScanRef {
    /// Everything up to the best pose, integers only: must equal the device's text.
    pub head: String,
    /// Best pose of the coarse grid.
    pub best: Pose,
    /// Tempered log-likelihood at the best pose.
    pub log_likelihood: f32,
    /// Effective sample size of the grid's weights.
    pub ess: f32,
    /// The best pose's distance (m) and heading difference (°) from the logged pose.
    pub offset: (f32, f32),
    /// Beams missing against the log (for the plan's check).
    pub missing: u16,
    /// Beams that differ from the log.
    pub wrong: u16,
}

/// The host's run of the device's pipeline over `bytes`: per scan line and the two counter
/// lines, as the device prints them (integers), or the floats to compare.
pub struct Reference {
    /// One per assembled scan, in order.
    pub scans: Vec<ScanRef>,
    /// The decoder's counter line.
    pub decoder: String,
    /// The assembler's counter line.
    pub assembler: String,
    /// Frames whose checksum passed, and failed.
    pub frames_ok: u32,
    /// See `frames_ok`.
    pub bad_checksum: u32,
    /// Frames whose checksum passed but that no LD06 can send (speed or span out of bounds).
    pub implausible_frames: u32,
}

/// Decodes, assembles and scores `bytes` on the host exactly as the firmware does.
pub fn reference(bytes: &[u8], blob: &[u8]) -> Result<Reference> {
    let setup = lidar_plan::setup(blob, MAX_RANGE_M).map_err(|e| Error::Host(e.into()))?;
    let mut assembler = lidar_plan::assembler(&setup)
        .map_err(|e| Error::Host(format!("assembler rejected: {e}")))?;
    let mut decoder = Ld06Decoder::new();
    let mut weights = Box::new([0.0f32; POSES]);
    let mut scans = Vec::new();
    let mut one = |assembler: &beamfield::lidar::ScanAssembler<BEAMS>,
                   scans: &mut Vec<ScanRef>|
     -> Result<()> {
        let k = scans.len();
        let demo = SCANS.get(k).ok_or_else(|| {
            Error::Host(format!(
                "the host assembled more than {} scans",
                SCANS.len()
            ))
        })?;
        let scan = assembler.scan();
        let logged = Pose::new(demo.pose[0], demo.pose[1], demo.pose[2]);
        let m = lidar_plan::compare(scan, &demo.ranges_m, MAX_RANGE_M);
        let s = lidar_plan::score(&setup, scan, &logged, &mut weights)
            .map_err(|e| Error::Host(format!("scan {k}: {e}")))?;
        let (d_m, dth_deg, _) = demo_plan::offset(&s.best, &logged);
        scans.push(ScanRef {
            head: format!(
                "scan {k} (log line {}): {} points; {} beams valid; vs log: {} match, {} missing, {} wrong; best (",
                demo.log_index,
                assembler.revolution().points,
                s.valid,
                m.matching,
                m.missing,
                m.wrong
            ),
            best: s.best,
            log_likelihood: s.log_likelihood,
            ess: s.ess,
            offset: (d_m, dth_deg),
            missing: m.missing,
            wrong: m.wrong,
        });
        Ok(())
    };
    // The whole stream in one `feed` (the device feeds 4 KiB chunks): the results must not
    // depend on where the chunks end. Each finished scan is scored at once.
    let mut result = Ok(());
    decoder.feed(bytes, |p| {
        if assembler.push(p).is_some() {
            result =
                std::mem::replace(&mut result, Ok(())).and_then(|()| one(&assembler, &mut scans));
        }
    });
    if assembler.finish().is_some() {
        result = result.and_then(|()| one(&assembler, &mut scans));
    }
    result?;
    let d = decoder.stats();
    let a = assembler.stats();
    Ok(Reference {
        scans,
        decoder: format!(
            "decoder: {} bytes, {} frames ok, {} bad checksums, {} bad frames, {} bytes skipped in {} resyncs, {} points",
            d.bytes, d.frames_ok, d.bad_checksum, d.bad_frames, d.skipped_bytes, d.resyncs, d.points
        ),
        assembler: format!(
            "assembler: {} points, {} accepted, {} flagged invalid, {} out of range, {} low quality, {} bad angle, {} outside the layout, {} replaced, {} revolutions",
            a.points,
            a.accepted,
            a.flagged_invalid,
            a.out_of_range,
            a.low_quality,
            a.bad_angle,
            a.outside_layout,
            a.replaced,
            a.revolutions
        ),
        frames_ok: d.frames_ok,
        bad_checksum: d.bad_checksum,
        implausible_frames: d.implausible_frames,
    })
}

/// The text between `start` and the next `end` after it.
fn between<'a>(line: &'a str, start: &str, end: &str) -> Option<&'a str> {
    let from = line.find(start)? + start.len();
    let rest = line.get(from..)?;
    rest.get(..rest.find(end)?)
}

/// Checks a printed number against the host's value printed with `decimals` digits (the
/// firmware rounds to the nearest: they agree when within half a unit of the last digit).
fn close(what: &str, printed: &str, host: f32, decimals: i32) -> Result<()> {
    let p: f64 = printed
        .trim()
        .parse()
        .map_err(|_| Error::Output(format!("{what}: cannot read {printed:?}")))?;
    let tol = 0.5 * 10f64.powi(-decimals) + 1e-9;
    if (p - f64::from(host)).abs() <= tol {
        Ok(())
    } else {
        Err(Error::Mismatch(format!(
            "{what}: device printed {printed}, host computes {host:.6}"
        )))
    }
}

/// Checks the device's report `out` against the host's `reference`, line by line: the
/// integers exactly, the printed decimals to their last digit. Returns the number of scans.
pub fn check(out: &str, r: &Reference) -> Result<usize> {
    let lines: Vec<&str> = out.lines().collect();
    let scan_lines: Vec<&str> = lines
        .iter()
        .copied()
        .filter(|l| l.starts_with("scan "))
        .collect();
    if scan_lines.len() != r.scans.len() {
        return Err(Error::Mismatch(format!(
            "the device reported {} scans, the host assembles {}",
            scan_lines.len(),
            r.scans.len()
        )));
    }
    for (k, (line, s)) in scan_lines.iter().zip(&r.scans).enumerate() {
        if !line.starts_with(&s.head) {
            return Err(Error::Mismatch(format!(
                "scan {k}: the device printed\n  {line}\nthe host computes\n  {}…",
                s.head
            )));
        }
        let pose = between(line, "best (", " deg)")
            .ok_or_else(|| Error::Output(format!("scan {k}: no best pose in {line:?}")))?;
        let p: Vec<&str> = pose.split(", ").collect();
        let [x, y, t] = p.as_slice() else {
            return Err(Error::Output(format!(
                "scan {k}: cannot read the pose {pose:?}"
            )));
        };
        close(&format!("scan {k} best x"), x, s.best.x_m, 3)?;
        close(&format!("scan {k} best y"), y, s.best.y_m, 3)?;
        close(
            &format!("scan {k} best θ"),
            t,
            s.best.theta_rad.to_degrees(),
            1,
        )?;
        let ll = between(line, "log-likelihood ", " ")
            .ok_or_else(|| Error::Output(format!("scan {k}: no log-likelihood in {line:?}")))?;
        close(&format!("scan {k} log-likelihood"), ll, s.log_likelihood, 3)?;
        let ess = line
            .rsplit_once("ESS ")
            .map(|(_, e)| e)
            .ok_or_else(|| Error::Output(format!("scan {k}: no ESS in {line:?}")))?;
        close(&format!("scan {k} ESS"), ess, s.ess, 1)?;
    }
    for want in [&r.decoder, &r.assembler] {
        let key = want.split(':').next().unwrap_or("");
        let got = lines
            .iter()
            .find(|l| l.starts_with(&format!("{key}:")))
            .ok_or_else(|| Error::Output(format!("the device printed no `{key}:` line")))?;
        if got != want {
            return Err(Error::Mismatch(format!(
                "the device printed\n  {got}\nthe host computes\n  {want}"
            )));
        }
    }
    Ok(r.scans.len())
}

#[cfg(test)]
mod tests {
    use super::{beam_at, close, stream, FLIPS};

    #[test]
    fn clockwise_degrees_map_to_the_flaser_beams() {
        // Beam i looks at −90° + i° counter-clockwise = 90° − i° clockwise.
        assert_eq!(beam_at(90), Some(0));
        assert_eq!(beam_at(0), Some(90));
        assert_eq!(beam_at(271), Some(179));
        assert_eq!(beam_at(91), None);
        assert_eq!(beam_at(270), None);
    }

    #[test]
    fn the_plan_leaves_whole_frames_missing_and_sizes_the_stream() {
        let s = stream().unwrap();
        // Revolutions of 30 frames of 47 bytes, plus the noise.
        assert_eq!(s.bytes.len(), s.scans * 30 * 47 + s.noise);
        assert_eq!(s.missing.iter().filter(|&&m| m > 0).count(), FLIPS.len());
        assert!(s.missing.iter().all(|&m| m <= 12));
    }

    #[test]
    fn printed_digits_agree_within_half_a_unit() {
        assert!(close("x", "9.909", 9.9094, 3).is_ok());
        assert!(close("x", "9.909", 9.9096, 3).is_err());
        assert!(close("x", "-0.5", -0.54, 1).is_ok());
    }
}
