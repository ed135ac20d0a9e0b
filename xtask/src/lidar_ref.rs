//! The host side of `cargo xtask lidar`: the LD06 stream sent into the emulated USART (a real
//! segment of consecutive Intel-lab scans, `fixtures/assets/lidar_segment.rs`, written by the library's LD06 encoder, with start-up noise and a few
//! corrupted frames), what the plan alone says the device must find in it, and the host's
//! recomputation of the device's report with the same crate and the same plan
//! (`fixtures/src/lidar_plan.rs`, shared word for word with the firmware).

use crate::error::{Error, ReportFault, Result};
use crate::report::{same_bits, unexpected_report, Items};
use beamfield_fixtures::report::{LidarChunk, LidarEnd, LidarScan, Report};
use beamfield_fixtures::{demo_plan, lidar_plan};

use beamfield::lidar::ld06::{self, Ld06Decoder, Ld06Sample};
use beamfield::lidar::{AssemblerStats, DecoderStats};
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

/// The host's version of one scan of the device's report.
pub struct ScanRef {
    /// The report the device must send (integers exactly, floats to the tolerances of
    /// [`check`]).
    pub report: LidarScan,
    /// The best pose's distance (m) and heading difference (°) from the logged pose.
    pub offset: (f32, f32),
}

/// The host's run of the device's pipeline over `bytes`: per scan its report, and the
/// decoder's and the assembler's counters.
pub struct Reference {
    /// One per assembled scan, in order.
    pub scans: Vec<ScanRef>,
    /// The decoder's counters.
    pub decoder: DecoderStats,
    /// The assembler's counters.
    pub assembler: AssemblerStats,
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
            report: LidarScan::of(
                k as u32,
                demo.log_index,
                assembler.revolution().points,
                &m,
                &s,
            ),
            offset: (d_m, dth_deg),
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
    Ok(Reference {
        scans,
        decoder: decoder.stats(),
        assembler: assembler.stats(),
    })
}

/// What the device reported, decoded from its data lines: per scan, per chunk, at the end.
pub struct DeviceReport {
    /// The `LidarScan` reports, in order.
    pub scans: Vec<LidarScan>,
    /// The `LidarChunk` reports, in order.
    pub chunks: Vec<LidarChunk>,
    /// The `LidarEnd` report.
    pub end: LidarEnd,
}

impl DeviceReport {
    /// Reads the data of the program's output `out`: `LidarScan` and `LidarChunk` reports, then
    /// one `LidarEnd` and nothing after it; as many scans and chunks as the end report counts,
    /// the scans numbered in order, the chunks' bytes adding up to those received, the scans
    /// finished in chunks plus at most one at the end making up the scans.
    ///
    /// # Errors
    /// [`Error::Report`] for a line that does not decode, a report missing, of another kind,
    /// or one more.
    pub fn read(out: &str) -> Result<Self> {
        let mut items = Items::new(out)?;
        let (mut scans, mut chunks) = (Vec::new(), Vec::new());
        let what = "a LidarScan, LidarChunk or LidarEnd report";
        let end = loop {
            match items.report(what)? {
                Report::LidarScan(s) => {
                    if s.scan as usize != scans.len() {
                        return Err(unexpected_report(
                            &format!("the report of scan {}", scans.len()),
                            &Report::LidarScan(s),
                        ));
                    }
                    scans.push(s);
                }
                Report::LidarChunk(c) => chunks.push(c),
                Report::LidarEnd(e) => break e,
                other => return Err(unexpected_report(what, &other)),
            }
        };
        items.end()?;
        let counted = |n: usize, what: &str, reported: u32| -> Result {
            match n.cmp(&(reported as usize)) {
                std::cmp::Ordering::Equal => Ok(()),
                std::cmp::Ordering::Less => Err(Error::Report(ReportFault::Missing {
                    expected: format!(
                        "{reported} {what} reports (the LidarEnd's count), {n} were sent"
                    ),
                })),
                std::cmp::Ordering::Greater => Err(Error::Report(ReportFault::Unexpected {
                    expected: format!("{reported} {what} reports (the LidarEnd's count)"),
                    got: format!("{n}"),
                })),
            }
        };
        counted(scans.len(), "LidarScan", end.scans)?;
        counted(chunks.len(), "LidarChunk", end.chunks)?;
        let chunk_bytes: u64 = chunks.iter().map(|c| u64::from(c.bytes)).sum();
        let in_chunks: u64 = chunks.iter().map(|c| u64::from(c.scans)).sum();
        if chunk_bytes != u64::from(end.received)
            || !(in_chunks..=in_chunks + 1).contains(&(scans.len() as u64))
        {
            return Err(Error::Report(ReportFault::Unexpected {
                expected: format!(
                    "chunks of {} bytes in all with {} or {} scans",
                    end.received,
                    scans.len().saturating_sub(1),
                    scans.len()
                ),
                got: format!("chunks of {chunk_bytes} bytes with {in_chunks} scans"),
            }));
        }
        Ok(Self { scans, chunks, end })
    }
}

/// Checks the device's value `device` against the host's `host` to the tolerance of the
/// readable report: half a unit of its last digit with `decimals` digits (as when the device
/// printed them with `decimals` digits and the host compared those).
fn close(what: &str, device: f32, host: f32, decimals: i32) -> Result<()> {
    let tol = 0.5 * 10f64.powi(-decimals) + 1e-9;
    if (f64::from(device) - f64::from(host)).abs() <= tol {
        Ok(())
    } else {
        Err(Error::Mismatch(format!(
            "{what}: the device reports {device}, the host computes {host} (tolerance {tol:.1e})"
        )))
    }
}

/// Checks the device's report `d` against the host's `reference`: every scan's integers
/// (index, log line, points, beams valid, matching, missing, wrong) exactly, its best pose to
/// 0.5 mm and 0.05°, log-likelihood to 0.0005 and ESS to 0.05; the decoder's and the
/// assembler's counters exactly. Returns the number of scans and how many of them are equal
/// bit for bit as well.
pub fn check(d: &DeviceReport, r: &Reference) -> Result<(usize, usize)> {
    if d.scans.len() != r.scans.len() {
        return Err(Error::Mismatch(format!(
            "the device reported {} scans, the host assembles {}",
            d.scans.len(),
            r.scans.len()
        )));
    }
    let mut identical = 0;
    for (k, (got, s)) in d.scans.iter().zip(&r.scans).enumerate() {
        let want = &s.report;
        let ints = |x: &LidarScan| {
            (
                x.scan,
                x.log_index,
                x.points,
                x.valid,
                x.matching,
                x.missing,
                x.wrong,
            )
        };
        if ints(got) != ints(want) {
            return Err(Error::Mismatch(format!(
                "scan {k}: the device reports\n  {got:?}\nthe host computes\n  {want:?}"
            )));
        }
        close(&format!("scan {k} best x"), got.best.x_m, want.best.x_m, 3)?;
        close(&format!("scan {k} best y"), got.best.y_m, want.best.y_m, 3)?;
        close(
            &format!("scan {k} best θ (degrees)"),
            got.best.theta_rad.to_degrees(),
            want.best.theta_rad.to_degrees(),
            1,
        )?;
        close(
            &format!("scan {k} log-likelihood"),
            got.log_likelihood,
            want.log_likelihood,
            3,
        )?;
        close(&format!("scan {k} ESS"), got.ess, want.ess, 1)?;
        identical += usize::from(same_bits(
            &Report::LidarScan(*got),
            &Report::LidarScan(*want),
        ));
    }
    if d.end.decoder != r.decoder {
        return Err(Error::Mismatch(format!(
            "the decoder's counters differ:\n  device: {:?}\n  host:   {:?}",
            d.end.decoder, r.decoder
        )));
    }
    if d.end.assembler != r.assembler {
        return Err(Error::Mismatch(format!(
            "the assembler's counters differ:\n  device: {:?}\n  host:   {:?}",
            d.end.assembler, r.assembler
        )));
    }
    Ok((r.scans.len(), identical))
}

#[cfg(test)]
mod tests {
    use super::{beam_at, close, stream, DeviceReport, FLIPS};
    use crate::error::{Error, ReportFault};
    use crate::report::report_line;
    use beamfield_fixtures::report::{LidarChunk, LidarEnd, LidarScan, Report};

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

    /// The data lines of a run: scans, chunks and the end report.
    fn device_lines(scans: &[LidarScan], chunks: &[LidarChunk], end: &LidarEnd) -> Vec<String> {
        let mut out: Vec<String> = scans
            .iter()
            .map(|s| report_line(&Report::LidarScan(*s)))
            .collect();
        out.extend(chunks.iter().map(|c| report_line(&Report::LidarChunk(*c))));
        out.push(report_line(&Report::LidarEnd(*end)));
        out
    }

    #[test]
    fn the_device_report_is_read_whole_and_a_missing_or_extra_report_is_an_error() {
        let scan = |k: u32| LidarScan {
            scan: k,
            log_index: 300 + k,
            points: 360,
            valid: 180,
            matching: 180,
            missing: 0,
            wrong: 0,
            best: beamfield::Pose::new(1.0, 2.0, 0.5),
            log_likelihood: 30.0,
            ess: 20.0,
        };
        let scans = [scan(0), scan(1)];
        let chunks = [LidarChunk {
            bytes: 100,
            scans: 1,
        }];
        let end = LidarEnd {
            decoder: Default::default(),
            assembler: Default::default(),
            received: 100,
            chunks: 1,
            crc32: 7,
            scans: 2,
            regions: 3,
            dropped: 0,
        };
        let ok = device_lines(&scans, &chunks, &end).join("\n");
        let d = DeviceReport::read(&ok).expect("reads");
        assert_eq!((d.scans.len(), d.chunks.len(), d.end), (2, 1, end));
        let fault = |out: String| match DeviceReport::read(&out) {
            Err(Error::Report(f)) => f,
            Err(e) => panic!("another error: {e}"),
            Ok(_) => panic!("accepted"),
        };
        // A scan report missing, one more, out of order; the end missing or followed by more.
        assert!(matches!(
            fault(device_lines(&scans[..1], &chunks, &end).join("\n")),
            ReportFault::Missing { .. }
        ));
        assert!(matches!(
            fault(device_lines(&[scan(0), scan(1), scan(2)], &chunks, &end).join("\n")),
            ReportFault::Unexpected { .. }
        ));
        assert!(matches!(
            fault(device_lines(&[scan(1), scan(0)], &chunks, &end).join("\n")),
            ReportFault::Unexpected { .. }
        ));
        let mut no_end = device_lines(&scans, &chunks, &end);
        no_end.pop();
        assert!(matches!(
            fault(no_end.join("\n")),
            ReportFault::Missing { .. }
        ));
        assert!(matches!(
            fault(format!(
                "{ok}\n{}",
                report_line(&Report::LidarScan(scan(2)))
            )),
            ReportFault::Unexpected { .. }
        ));
        // Chunks that do not add up to the bytes received.
        let short = [LidarChunk {
            bytes: 99,
            scans: 1,
        }];
        assert!(matches!(
            fault(device_lines(&scans, &short, &end).join("\n")),
            ReportFault::Unexpected { .. }
        ));
        // A damaged line.
        let damaged = ok.replacen("report: 03", "report: 13", 1);
        assert!(matches!(fault(damaged), ReportFault::Malformed { .. }));
    }

    #[test]
    fn values_agree_within_half_a_unit_of_the_last_digit() {
        assert!(close("x", 9.909, 9.9094, 3).is_ok());
        assert!(close("x", 9.909, 9.9096, 3).is_err());
        assert!(close("x", -0.5, -0.54, 1).is_ok());
    }
}
