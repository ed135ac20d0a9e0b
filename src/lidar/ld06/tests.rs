//! Unit tests of the LD06 frame, its CRC, its plausibility check, the decoder and the
//! revolution encoder (by hand from the manuals, and round trips).

use super::*;
use crate::lidar::{DecoderStats, EncodeError, LidarPoint};

/// Bit-by-bit CRC-8 (polynomial 0x4D, MSB first), independent of the `crc` crate's table.
fn crc8_bitwise(bytes: &[u8]) -> u8 {
    let mut c = 0u8;
    for &b in bytes {
        c ^= b;
        for _ in 0..8 {
            c = if c & 0x80 != 0 {
                (c << 1) ^ 0x4D
            } else {
                c << 1
            };
        }
    }
    c
}

#[test]
fn crc_matches_bitwise_definition_and_published_table_entries() {
    assert_eq!(crc8(b"123456789"), crc8_bitwise(b"123456789"));
    assert_eq!(crc8(b"123456789"), 0xC3);
    // LDROBOT's published table starts 0x00, 0x4d, 0x9a, 0xd7: the CRC of one byte 0..=3.
    for (b, want) in [(0u8, 0x00u8), (1, 0x4D), (2, 0x9A), (3, 0xD7)] {
        assert_eq!(crc8(&[b]), want);
    }
    for len in 0..64u8 {
        let v: Vec<u8> = (0..len).map(|i| i.wrapping_mul(37) ^ 0xA5).collect();
        assert_eq!(crc8(&v), crc8_bitwise(&v));
    }
}

#[test]
fn crc_table_matches_the_crc_crate_and_the_frame_check_matches_crc8() {
    let reference = crc::Crc::<u8>::new(&CRC_8_LD06);
    for len in 0..64u8 {
        let v: Vec<u8> = (0..len).map(|i| i.wrapping_mul(91) ^ 0x3C).collect();
        assert_eq!(crc8(&v), reference.checksum(&v));
    }
    for b in 0..=255u8 {
        assert_eq!(crc8(&[b]), reference.checksum(&[b]));
    }
    for seed in 0..200u32 {
        let frame: [u8; FRAME_LEN] = core::array::from_fn(|i| {
            (seed.wrapping_mul(2_654_435_761) >> (i % 24)) as u8 ^ i as u8
        });
        assert_eq!(crc8_frame(&frame), crc8(&frame[..46]));
    }
}

fn sample_frame() -> Ld06Frame {
    let mut samples = [Ld06Sample::default(); 12];
    for (i, s) in samples.iter_mut().enumerate() {
        s.distance_mm = 1000 + i as u16 * 7;
        s.intensity = 200 - i as u8;
    }
    Ld06Frame {
        speed_deg_per_s: 3600,
        start_angle_cdeg: 35_500,
        samples,
        end_angle_cdeg: 600,
        timestamp_ms: 29_999,
    }
}

#[test]
fn emit_then_parse_round_trips_and_layout_is_little_endian() {
    let f = sample_frame();
    let mut out = [0u8; 50];
    assert_eq!(f.emit(&mut out), Ok(FRAME_LEN));
    assert_eq!(&out[..6], &[0x54, 0x2C, 0x10, 0x0E, 0xAC, 0x8A]);
    assert_eq!(&out[6..9], &[0xE8, 0x03, 200]);
    assert_eq!(out[46], crc8_bitwise(&out[..46]));
    assert_eq!(Ld06Frame::parse(&out), Ok(f));
    assert_eq!(
        f.emit(&mut [0u8; 46]),
        Err(EncodeError::BufferTooSmall {
            needed: 47,
            given: 46
        })
    );
}

#[test]
fn interpolation_wraps_across_zero() {
    // 355.00° .. 6.00°: span 11°, 1° per point; point 5 is at 360 → 0°.
    let f = sample_frame();
    assert_eq!(f.span_cdeg(), 1100);
    let want = [
        355.0, 356.0, 357.0, 358.0, 359.0, 0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0,
    ];
    for (i, w) in want.iter().enumerate() {
        let p = f.point(i);
        assert!((p.angle_cw_deg - w).abs() < 1e-4, "{i}: {}", p.angle_cw_deg);
        assert!((0.0..360.0).contains(&p.angle_cw_deg));
    }
    assert_eq!(f.point(3).timestamp_ms, Some(29_999));
    assert!((f.point(1).range_m - 1.007).abs() < 1e-6);
}

#[test]
fn decoder_skips_garbage_and_rejects_bad_crc() {
    let f = sample_frame();
    let mut frame = [0u8; FRAME_LEN];
    f.emit(&mut frame).unwrap();
    let mut stream = vec![0x00, 0x54, 0x54, 0x11];
    stream.extend_from_slice(&frame);
    let mut bad = frame;
    bad[20] ^= 0x04;
    stream.extend_from_slice(&bad);
    stream.extend_from_slice(&frame[..30]); // truncated
    stream.extend_from_slice(&frame);
    let mut d = Ld06Decoder::new();
    let mut pts = Vec::new();
    d.feed(&stream, |p| pts.push(p));
    let s = d.stats();
    assert_eq!(s.frames_ok, 2);
    assert_eq!(pts.len(), 24);
    assert_eq!(s.bad_checksum, 2);
    assert_eq!(s.bytes as usize, stream.len());
    assert_eq!(
        s.bytes as usize,
        FRAME_LEN * (s.frames_ok + s.bad_frames) as usize + s.skipped_bytes as usize + d.buffered()
    );
    for p in &pts {
        assert_eq!(p.timestamp_ms, Some(29_999));
    }
}

#[test]
fn block_feed_equals_byte_feed_and_points_equal_point() {
    let f = sample_frame();
    let mut pts = Vec::new();
    f.points(&mut |p| pts.push(p));
    assert_eq!(pts, (0..12).map(|i| f.point(i)).collect::<Vec<_>>());
    let mut frame = [0u8; FRAME_LEN];
    f.emit(&mut frame).unwrap();
    let mut stream = vec![0x54, 0x01, 0x54];
    for _ in 0..5 {
        stream.extend_from_slice(&frame);
        stream.extend_from_slice(&frame[..13]);
    }
    for piece in [1usize, 2, 5, 46, 47, 48, 1000] {
        let mut a = Ld06Decoder::new();
        let mut got = Vec::new();
        for c in stream.chunks(piece) {
            a.feed(c, |p| got.push(p));
        }
        let mut b = Ld06Decoder::new();
        let mut want = Vec::new();
        for &x in &stream {
            b.push_byte(x, &mut |p| want.push(p));
        }
        assert_eq!(got, want, "pieces of {piece}");
        assert_eq!(a.stats(), b.stats());
        assert_eq!(a.buffered(), b.buffered());
    }
}

/// Frames judged where they lie in the fed slice (the block path) and frames assembled byte by
/// byte agree on every point, counter and kept frame, whatever the verdicts.
#[test]
fn block_feed_equals_byte_feed_for_every_verdict() {
    let good = frame_bytes(&sample_frame());
    let mut bad_crc = good;
    bad_crc[20] ^= 0x10;
    let out_of_range = frame_bytes(&with(3600, 36_000, 100));
    let implausible = frame_bytes(&with(3600, 0, 20_000));
    let mut stream = Vec::new();
    for (k, f) in [
        good,
        bad_crc,
        good,
        out_of_range,
        implausible,
        good,
        good,
        bad_crc,
    ]
    .iter()
    .enumerate()
    {
        stream.extend_from_slice(f);
        if k % 3 == 1 {
            // A header candidate inside garbage between frames.
            stream.extend_from_slice(&[0x54, 0x2C, 0x00, 0x54]);
        }
    }
    stream.extend_from_slice(&good[..30]);
    for piece in [1usize, 3, 46, 47, 48, 94, 95, 1000] {
        let mut a = Ld06Decoder::new();
        let mut got = Vec::new();
        for c in stream.chunks(piece) {
            a.feed(c, |p| got.push(p));
        }
        let mut b = Ld06Decoder::new();
        let mut want = Vec::new();
        for &x in &stream {
            b.push_byte(x, &mut |p| want.push(p));
        }
        assert_eq!(got, want, "pieces of {piece}");
        assert_eq!(a.stats(), b.stats(), "pieces of {piece}");
        assert_eq!(a.buffered(), b.buffered(), "pieces of {piece}");
        assert_eq!(a.last_frame(), b.last_frame(), "pieces of {piece}");
    }
}

#[test]
fn angle_out_of_range_with_good_crc_is_counted_not_emitted() {
    let mut f = sample_frame();
    f.end_angle_cdeg = 36_000;
    let mut frame = [0u8; FRAME_LEN];
    f.emit(&mut frame).unwrap();
    let mut d = Ld06Decoder::new();
    let mut n = 0;
    d.feed(&frame, |_| n += 1);
    assert_eq!((n, d.stats().bad_frames, d.stats().frames_ok), (0, 1, 0));
    // `last_frame` keeps only accepted frames.
    assert!(d.last_frame().is_none());
    let good = sample_frame();
    let mut g = [0u8; FRAME_LEN];
    good.emit(&mut g).unwrap();
    d.feed(&g, |_| n += 1);
    d.feed(&frame, |_| n += 1);
    assert_eq!(d.last_frame(), Some(&good));
    assert_eq!(n, 12);
}

fn frame_bytes(f: &Ld06Frame) -> [u8; FRAME_LEN] {
    let mut b = [0u8; FRAME_LEN];
    f.emit(&mut b).unwrap();
    b
}

fn with(speed_deg_per_s: u16, start_angle_cdeg: u16, end_angle_cdeg: u16) -> Ld06Frame {
    Ld06Frame {
        speed_deg_per_s,
        start_angle_cdeg,
        end_angle_cdeg,
        ..sample_frame()
    }
}

/// Decodes `bytes` in one call: (points, stats, the byte accounting holds).
fn decode(bytes: &[u8]) -> (Vec<LidarPoint>, DecoderStats, Option<Ld06Frame>) {
    let mut d = Ld06Decoder::new();
    let mut pts = Vec::new();
    d.feed(bytes, |p| pts.push(p));
    let s = d.stats();
    assert_eq!(
        s.bytes as usize,
        FRAME_LEN * (s.frames_ok + s.bad_frames) as usize + s.skipped_bytes as usize + d.buffered()
    );
    (pts, s, d.last_frame().copied())
}

#[test]
fn span_bound_is_twelve_samples_at_2250_hz_plus_half() {
    // 1.5 · 12 · v / 2,250 degrees, by hand: 3,600 °/s → 28.8°; 4,680 °/s → 37.44°;
    // 1,800 °/s → 14.4°; 2,152 °/s → 17.216° (rounded down to the hundredth).
    assert_eq!(Ld06Frame::max_span_cdeg(3600), 2880);
    assert_eq!(Ld06Frame::max_span_cdeg(4680), 3744);
    assert_eq!(Ld06Frame::max_span_cdeg(1800), 1440);
    assert_eq!(Ld06Frame::max_span_cdeg(2152), 1721);
}

#[test]
fn plausibility_limits_on_speed_and_span() {
    // (speed, start, end, plausible)
    for (v, a, b, want) in [
        (3600, 1000, 3880, true),    // span 28.80°, the bound
        (3600, 1000, 3881, false),   // 28.81°
        (3600, 35_000, 1880, true),  // 350° → 18.8°, across 0°: 28.80°
        (3600, 35_000, 1881, false), // 28.81° across 0°
        (1800, 0, 1100, true),       // the slowest speed
        (1799, 0, 1100, false),
        (4680, 0, 1100, true), // the fastest
        (4681, 0, 1100, false),
        (0, 0, 0, false),
        (u16::MAX, 0, 1100, false),
        (3600, 10_000, 9_999, false), // 359.99°: the end just behind the start
    ] {
        let f = with(v, a, b);
        assert_eq!(f.is_plausible(), want, "{v} °/s, {a} → {b}");
        let parsed = Ld06Frame::parse(&frame_bytes(&f));
        if want {
            assert_eq!(parsed, Ok(f));
        } else {
            assert_eq!(
                parsed,
                Err(Ld06Error::Implausible {
                    speed_deg_per_s: v,
                    span_cdeg: f.span_cdeg()
                })
            );
        }
    }
}

#[test]
fn crc_valid_frame_with_absurd_span_is_counted_and_yields_no_points() {
    let good = sample_frame();
    // 100° → 300°: twelve points over 200° at 10 Hz; the CRC is right.
    let absurd = with(3600, 10_000, 30_000);
    let mut stream = frame_bytes(&absurd).to_vec();
    let (pts, s, last) = decode(&stream);
    assert!(pts.is_empty());
    assert_eq!(
        (s.frames_ok, s.implausible_frames, s.bad_checksum),
        (0, 1, 0)
    );
    assert_eq!((s.bad_frames, s.points), (0, 0));
    assert_eq!(last, None);
    // A good frame after it is decoded, and `last_frame` is the good one.
    stream.extend_from_slice(&frame_bytes(&good));
    stream.extend_from_slice(&frame_bytes(&absurd));
    let (pts, s, last) = decode(&stream);
    assert_eq!(pts, (0..12).map(|i| good.point(i)).collect::<Vec<_>>());
    assert_eq!((s.frames_ok, s.implausible_frames), (1, 2));
    assert_eq!(last, Some(good));
    // A CRC-valid frame whose speed is out of range, with a normal span.
    let (pts, s, _) = decode(&frame_bytes(&with(20_000, 0, 1100)));
    assert!(pts.is_empty());
    assert_eq!(s.implausible_frames, 1);
}

#[test]
fn implausible_window_gives_back_the_frame_that_starts_inside_it() {
    // A window that opens with `54 2C`, passes its CRC by chance and ends with the first 20
    // bytes of a good frame: its end angle is made of the good frame's bytes 15..17 (sample
    // 3's distance, 1,021 mm → 10.21°), its start is 200°, so its span is 170.21°.
    let good = sample_frame();
    let g = frame_bytes(&good);
    let k = 20;
    let mut w = [0u8; FRAME_LEN];
    w[..6].copy_from_slice(&[HEADER, VER_LEN, 0x10, 0x0E, 0x20, 0x4E]); // 3,600 °/s, 200°
    w[FRAME_LEN - k..].copy_from_slice(&g[..k]);
    // Choose byte 10 so the CRC over bytes 0..46 equals the byte at 46 (one value does: the
    // CRC of a fixed-length message is a bijection of any one of its bytes).
    let fit: Vec<u8> = (0..=255u8)
        .filter(|&x| {
            w[10] = x;
            crc8_bitwise(&w[..46]) == w[46]
        })
        .collect();
    assert_eq!(fit.len(), 1);
    w[10] = fit[0];
    let window = Ld06Frame::parse(&w);
    assert_eq!(
        window,
        Err(Ld06Error::Implausible {
            speed_deg_per_s: 3600,
            span_cdeg: 17_021
        })
    );
    assert!(!w[1..FRAME_LEN - k]
        .windows(2)
        .any(|p| p == [HEADER, VER_LEN]));
    let mut stream = w[..FRAME_LEN - k].to_vec();
    stream.extend_from_slice(&g);
    let (pts, s, last) = decode(&stream);
    assert_eq!(pts, (0..12).map(|i| good.point(i)).collect::<Vec<_>>());
    assert_eq!((s.frames_ok, s.implausible_frames), (1, 1));
    assert_eq!(s.skipped_bytes as usize, FRAME_LEN - k);
    assert_eq!(last, Some(good));
}

#[test]
fn revolution_encoder_lays_out_whole_degrees() {
    let samples: Vec<Ld06Sample> = (0..360)
        .map(|k| Ld06Sample {
            distance_mm: k as u16 + 1,
            intensity: 100,
        })
        .collect();
    let mut out = vec![0u8; revolution_len(360)];
    assert_eq!(
        encode_revolution(&samples, 3600, 100, &mut out),
        Ok(30 * 47)
    );
    let mut d = Ld06Decoder::new();
    let mut pts = Vec::new();
    d.feed(&out, |p| pts.push(p));
    assert_eq!(pts.len(), 360);
    for (k, p) in pts.iter().enumerate() {
        assert!(
            (p.angle_cw_deg - k as f32).abs() < 1e-3,
            "{k}: {}",
            p.angle_cw_deg
        );
        assert!((p.range_m - (k as f32 + 1.0) * 1e-3).abs() < 1e-7);
    }
    // Frame 15 starts at 180°: half a turn at 3,600 °/s is 50 ms after frame 0.
    assert_eq!(pts[180].timestamp_ms, Some(150));
    assert_eq!(
        encode_revolution(&samples[..350], 3600, 0, &mut out),
        Err(EncodeError::BadSampleCount(350))
    );
}

#[test]
fn a_whole_frame_with_impossible_content_ends_a_run_of_skipped_bytes() {
    // Garbage, a frame whose CRC passes but whose end angle is 360°, garbage: two runs of
    // skipped bytes with a whole frame (counted in `bad_frames`, not skipped) between them.
    let mut f = sample_frame();
    f.end_angle_cdeg = 36_000;
    let mut stream = vec![0x00, 0x11];
    stream.extend_from_slice(&frame_bytes(&f));
    stream.extend_from_slice(&[0x22, 0x33, 0x44]);
    let (pts, s, _) = decode(&stream);
    assert!(pts.is_empty());
    assert_eq!((s.bad_frames, s.skipped_bytes, s.resyncs), (1, 5, 2));
}

#[test]
fn assembler_timing_anchors_are_the_first_points_of_the_first_and_last_frames() {
    use crate::lidar::assembler::{full_turn_layout, AssemblerConfig, ScanAssembler};
    let samples: Vec<Ld06Sample> = (0..360)
        .map(|_| Ld06Sample {
            distance_mm: 1000,
            intensity: 100,
        })
        .collect();
    let layout = full_turn_layout::<360>(360, 12.0, crate::pose::SensorMount::CENTERED).unwrap();
    let mut asm = ScanAssembler::new(&layout, AssemblerConfig::for_layout(&layout)).unwrap();
    let mut d = Ld06Decoder::new();
    let mut out = vec![0u8; revolution_len(360)];
    let mut emitted = 0;
    for rev in 0..3u16 {
        encode_revolution(&samples, 3600, 100 + 100 * rev, &mut out).unwrap();
        d.feed(&out, |p| emitted += usize::from(asm.push(p).is_some()));
    }
    assert_eq!(emitted, 2);
    let t = asm.timing().unwrap();
    // Revolution 1 (stamps 200 … 297 ms): frame 0 at 0°, frame 29 at 348°.
    assert_eq!((t.start_timestamp_ms, t.end_timestamp_ms), (200, 297));
    assert!(t.start_deg.abs() < 1e-3, "{t:?}");
    assert!((t.end_deg - 348.0).abs() < 1e-3, "{t:?}");
    // 348° in 97 ms: the encoder's rounding of 96.67 ms.
    assert_eq!(asm.revolution().end_timestamp_ms, Some(297));
}
