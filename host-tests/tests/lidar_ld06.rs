//! LD06 stream round trip on the real Intel lab log, and the decoder/assembler against corrupted
//! real streams.
//!
//! Every FLASER scan of the log (180 beams, −90° … +89° counter-clockwise) is laid out as one
//! clockwise LD06 revolution of 360 points 1° apart (the rear half reads "no measurement"),
//! written as 30 frames with `ld06::encode_revolution`, and the whole log becomes one byte
//! stream behind some start-up garbage. Decoding it with `Ld06Decoder` and assembling with
//! `ScanAssembler` on the log's own layout must give back, scan by scan and beam by beam, the
//! logged range rounded to the protocol's millimetre (|error| ≤ 0.5 mm plus f32 rounding); beams
//! the protocol cannot carry (the 81.83 m max-range sentinel is past the u16 millimetre field)
//! must come back NaN.

use beamfield::lidar::assembler::sample_revolution;
use beamfield::lidar::ld06::{self, Ld06Decoder, Ld06Sample};
use beamfield::lidar::{AssemblerConfig, LidarPoint, ScanAssembler};
use beamfield::{BeamLayout, Scan, SensorMount};
use beamfield_tools::input::carmen::{CarmenLog, ReadOptions};
use proptest::prelude::*;
use std::sync::OnceLock;

const N: usize = 180;
const POINTS: usize = 360;

struct Intel {
    layout: BeamLayout<N>,
    ranges: Vec<Vec<f32>>,
}

fn intel() -> &'static Intel {
    static CELL: OnceLock<Intel> = OnceLock::new();
    CELL.get_or_init(|| {
        let path = host_tests::data_dir().join("laser_intel_lab/intel-corrected.log");
        let log = CarmenLog::read_path(&path, ReadOptions::default()).unwrap();
        Intel {
            layout: log.layout_with_mount(SensorMount::CENTERED).unwrap(),
            ranges: log.scans.iter().map(|s| s.ranges_m.clone()).collect(),
        }
    })
}

/// Each scan as one LD06 revolution at 10 Hz (3,600 °/s, 100 ms per turn).
fn encode(scans: &[Vec<f32>], layout: &BeamLayout<N>) -> Vec<u8> {
    let mut out = Vec::new();
    let mut rev = vec![0.0f32; POINTS];
    let mut frames = vec![0u8; ld06::revolution_len(POINTS)];
    for (k, r) in scans.iter().enumerate() {
        let scan = Scan::<N>::from_ranges(r).unwrap();
        sample_revolution(layout, &scan, &mut rev).unwrap();
        let samples: Vec<Ld06Sample> = rev
            .iter()
            .map(|&r| Ld06Sample::from_range_m(r, 200))
            .collect();
        let ts = ((k * 100) % 30_000) as u16;
        let n = ld06::encode_revolution(&samples, 3600, ts, &mut frames).unwrap();
        out.extend_from_slice(&frames[..n]);
    }
    out
}

struct Decoded {
    scans: Vec<Vec<f32>>,
    points: Vec<LidarPoint>,
    decoder: Ld06Decoder,
    assembler: ScanAssembler<N>,
}

fn decode(stream: &[u8], layout: &BeamLayout<N>, chunk: usize) -> Decoded {
    let mut decoder = Ld06Decoder::new();
    let mut assembler = ScanAssembler::new(layout, AssemblerConfig::for_layout(layout)).unwrap();
    let mut scans = Vec::new();
    let mut points = Vec::new();
    for c in stream.chunks(chunk.max(1)) {
        decoder.feed(c, |p| {
            points.push(p);
            if let Some(s) = assembler.push(p) {
                scans.push(s.ranges_m().to_vec());
            }
        });
    }
    if let Some(s) = assembler.finish() {
        scans.push(s.ranges_m().to_vec());
    }
    Decoded {
        scans,
        points,
        decoder,
        assembler,
    }
}

/// True when the LD06 field can carry the range (1 ..= 65,535 mm after rounding).
fn representable(r: f32) -> bool {
    let mm = f64::from(r) * 1000.0;
    (0.5..65_535.5).contains(&mm)
}

#[test]
fn whole_intel_log_round_trips_to_the_millimetre() {
    let intel = intel();
    let mut stream = vec![0x54, 0x00, 0x2C, 0x54, 0x54, 0xFF, 0x13, 0x37]; // start-up garbage
    let garbage = stream.len();
    stream.extend(encode(&intel.ranges, &intel.layout));
    let d = decode(&stream, &intel.layout, 64);
    assert_eq!(d.scans.len(), intel.ranges.len());
    let (mut carried, mut nan, mut worst) = (0usize, 0usize, 0.0f64);
    for (k, (got, want)) in d.scans.iter().zip(&intel.ranges).enumerate() {
        assert_eq!(got.len(), want.len());
        for (i, (&g, &w)) in got.iter().zip(want).enumerate() {
            if representable(w) {
                let err = (f64::from(g) - f64::from(w)).abs();
                // Half a millimetre of quantisation plus the f32 rounding of both values.
                let tol = 0.5e-3 + 2.0 * f64::from(f32::EPSILON) * f64::from(w);
                assert!(err <= tol, "scan {k} beam {i}: got {g}, logged {w}");
                worst = worst.max(err);
                carried += 1;
            } else {
                assert!(g.is_nan(), "scan {k} beam {i}: got {g}, logged {w}");
                nan += 1;
            }
        }
    }
    let s = d.decoder.stats();
    assert_eq!(s.frames_ok as usize, intel.ranges.len() * 30);
    assert_eq!((s.bad_checksum, s.bad_frames), (0, 0));
    assert_eq!(s.skipped_bytes as usize, garbage);
    let a = d.assembler.stats();
    assert_eq!(a.revolutions as usize, intel.ranges.len());
    assert_eq!(a.accepted as usize, carried);
    assert_eq!(a.replaced, 0);
    println!(
        "{} scans, {carried} ranges carried (worst error {:.3} mm), {nan} not representable, {} bytes",
        intel.ranges.len(),
        worst * 1e3,
        stream.len()
    );
}

#[test]
fn revolution_times_follow_the_frame_timestamps() {
    let intel = intel();
    let stream = encode(&intel.ranges[..5], &intel.layout);
    let mut decoder = Ld06Decoder::new();
    let mut assembler =
        ScanAssembler::new(&intel.layout, AssemblerConfig::for_layout(&intel.layout)).unwrap();
    let mut revs = Vec::new();
    decoder.feed(&stream, |p| {
        if assembler.push(p).is_some() {
            revs.push(assembler.revolution());
        }
    });
    assert_eq!(revs.len(), 4);
    for (k, r) in revs.iter().enumerate() {
        // Revolution k starts at k·100 ms; its last frame starts at 348° → 96.67 → 97 ms later.
        assert_eq!(r.index as usize, k);
        assert_eq!(r.start_timestamp_ms, Some(k as u16 * 100));
        assert_eq!(r.end_timestamp_ms, Some(k as u16 * 100 + 97));
        assert_eq!(r.points, 360);
    }
}

/// A corruption of a real stream.
#[derive(Clone, Debug)]
enum Damage {
    Flip { at: usize, bit: u8 },
    Insert { at: usize, byte: u8 },
    Delete { at: usize, len: usize },
}

fn damage() -> impl Strategy<Value = Damage> {
    prop_oneof![
        (any::<usize>(), 0u8..8).prop_map(|(at, bit)| Damage::Flip { at, bit }),
        (any::<usize>(), any::<u8>()).prop_map(|(at, byte)| Damage::Insert { at, byte }),
        (any::<usize>(), 1usize..60).prop_map(|(at, len)| Damage::Delete { at, len }),
    ]
}

/// Frames of the clean stream whose bytes were all left intact and in place relative to each
/// other (their start offset in the clean stream), after applying `damages`.
fn apply(clean: &[u8], damages: &[Damage]) -> (Vec<u8>, Vec<bool>) {
    // Track, for every byte of the damaged stream, the clean index it came from (None if new).
    let mut bytes: Vec<(u8, Option<usize>)> = clean
        .iter()
        .enumerate()
        .map(|(i, &b)| (b, Some(i)))
        .collect();
    let mut touched = vec![false; clean.len()];
    for d in damages {
        let n = bytes.len().max(1);
        match *d {
            Damage::Flip { at, bit } => {
                let at = at % n;
                if let Some((b, src)) = bytes.get_mut(at) {
                    *b ^= 1 << bit;
                    if let Some(s) = src {
                        touched[*s] = true;
                    }
                }
            }
            Damage::Insert { at, byte } => {
                let at = at % (bytes.len() + 1);
                // The neighbours' frames lose their contiguity.
                for j in [at.wrapping_sub(1), at] {
                    if let Some((_, Some(s))) = bytes.get(j) {
                        touched[*s] = true;
                    }
                }
                bytes.insert(at, (byte, None));
            }
            Damage::Delete { at, len } => {
                let at = at % n;
                let end = (at + len).min(bytes.len());
                for j in at.wrapping_sub(1)..=end {
                    if let Some((_, Some(s))) = bytes.get(j) {
                        touched[*s] = true;
                    }
                }
                bytes.drain(at..end);
            }
        }
    }
    let frames = clean.len() / ld06::FRAME_LEN;
    let intact = (0..frames)
        .map(|f| {
            !touched[f * ld06::FRAME_LEN..(f + 1) * ld06::FRAME_LEN]
                .iter()
                .any(|&t| t)
        })
        .collect();
    (bytes.into_iter().map(|(b, _)| b).collect(), intact)
}

/// A fixed seed. LD06 frames carry an 8-bit CRC, so a misaligned window that happens to start
/// with `0x54 0x2C` passes it one time in 256: with random seeds this test finds such a frame now
/// and then (for example, 31 bytes deleted at offset 6 of frame 555 of the log's first 20 scans
/// make a bogus frame whose CRC matches). That is the protocol's limit, not the decoder's.
fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x1D06_5EED),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// Every finite range of every scan equals that beam's range in one single logged scan.
fn no_mixed_revolutions(scans_got: &[Vec<f32>], logged: &[Vec<f32>]) -> bool {
    scans_got.iter().all(|got| {
        logged.iter().any(|want| {
            got.iter().zip(want).all(|(&g, &w)| {
                g.is_nan() || (f64::from(g) - f64::from(w)).abs() <= 0.5e-3 + 1e-5 * f64::from(w)
            })
        })
    })
}

proptest! {
    #![proptest_config(config())]

    /// One bit flipped in each of up to 12 different frames of a real 20-scan stream: exactly
    /// the damaged frames are lost (a CRC catches every single-bit error, and the decoder's rescan
    /// keeps the next frame), every emitted point is a clean one, no scan mixes revolutions.
    #[test]
    fn one_flip_per_frame_costs_exactly_that_frame(
        start in 0usize..880,
        flips in prop::collection::btree_map(0usize..600, (0usize..47, 0u8..8), 1..12),
        chunk in 1usize..100,
    ) {
        let intel = intel();
        let scans = &intel.ranges[start..start + 20];
        let clean = encode(scans, &intel.layout);
        let mut clean_pts = Vec::new();
        Ld06Decoder::new().feed(&clean, |p| clean_pts.push(p));
        let mut bad = clean.clone();
        for (&frame, &(offset, bit)) in &flips {
            bad[frame * ld06::FRAME_LEN + offset] ^= 1 << bit;
        }
        let d = decode(&bad, &intel.layout, chunk);
        let s = d.decoder.stats();
        prop_assert_eq!(s.frames_ok as usize, 600 - flips.len());
        prop_assert_eq!(d.points.len(), 12 * (600 - flips.len()));
        for p in &d.points {
            prop_assert!(clean_pts.contains(p), "point {:?} not in the clean stream", p);
        }
        prop_assert_eq!(
            s.bytes as usize,
            ld06::FRAME_LEN * (s.frames_ok + s.bad_frames) as usize
                + s.skipped_bytes as usize + d.decoder.buffered()
        );
        prop_assert!(no_mixed_revolutions(&d.scans, scans), "a scan matches no single logged scan");
    }

    /// Bit flips, inserted and deleted bytes anywhere: no panic, exact byte accounting, every
    /// intact frame decoded, the assembler's counters adding up. A window that the damage makes
    /// start with `0x54 0x2C` passes the 8-bit CRC one time in 256 and is then emitted: the test
    /// counts such frames (points not in the clean stream) and checks the other properties around
    /// them; when there is none, no scan may mix revolutions.
    #[test]
    fn corrupted_real_streams(start in 0usize..880, damages in prop::collection::vec(damage(), 1..12), chunk in 1usize..100) {
        let intel = intel();
        let scans = &intel.ranges[start..start + 20];
        let clean = encode(scans, &intel.layout);
        let mut clean_pts = Vec::new();
        Ld06Decoder::new().feed(&clean, |p| clean_pts.push(p));
        let (bad, intact) = apply(&clean, damages.as_slice());
        let d = decode(&bad, &intel.layout, chunk);

        let s = d.decoder.stats();
        prop_assert_eq!(d.points.len() as u32, s.points);
        prop_assert_eq!(s.points, 12 * s.frames_ok);
        let bogus = d.points.iter().filter(|p| !clean_pts.contains(p)).count();
        // A lucky frame may swallow the start of the next real one.
        let bogus_frames = bogus.div_ceil(12) as u32;
        let intact_frames = intact.iter().filter(|&&t| t).count() as u32;
        prop_assert!(
            s.frames_ok + bogus_frames >= intact_frames,
            "{} ok, {} bogus < {} intact", s.frames_ok, bogus_frames, intact_frames
        );
        prop_assert_eq!(
            s.bytes as usize,
            ld06::FRAME_LEN * (s.frames_ok + s.bad_frames) as usize
                + s.skipped_bytes as usize + d.decoder.buffered()
        );
        prop_assert_eq!(s.bytes as usize, bad.len());
        if bogus == 0 {
            prop_assert!(no_mixed_revolutions(&d.scans, scans), "a scan matches no single logged scan");
        }
        let a = d.assembler.stats();
        prop_assert_eq!(
            a.points,
            a.accepted + a.flagged_invalid + a.out_of_range + a.low_quality + a.bad_angle + a.outside_layout
        );
    }
}

#[test]
fn wrong_sensor_bytes_give_no_points() {
    // An XV11-like stream (0xFA packets) and random bytes fed to the LD06 decoder.
    let mut state = 0x1234_5678u32;
    let mut junk = Vec::new();
    for i in 0..100_000u32 {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        junk.push(if i % 22 == 0 { 0xFA } else { state as u8 });
    }
    let mut d = Ld06Decoder::new();
    let mut n = 0;
    d.feed(&junk, |_| n += 1);
    let s = d.stats();
    // A random 47-byte frame passes an 8-bit CRC one time in 256: with about 100,000/47/256
    // header-shaped candidates (0x54 0x2C at random: 1 in 65,536 byte pairs) a false frame is
    // possible but should not appear here; whatever passes must be counted consistently.
    assert_eq!(n, 12 * s.frames_ok);
    assert_eq!(
        s.bytes as usize,
        47 * (s.frames_ok + s.bad_frames) as usize + s.skipped_bytes as usize + d.buffered()
    );
    assert_eq!(s.frames_ok, 0);
    assert!(s.skipped_bytes > 99_000);
}
