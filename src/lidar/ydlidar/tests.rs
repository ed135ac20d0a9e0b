//! Unit tests: the manual's example by hand, the SDK document's zero packet, each error
//! variant, revolution round trips with and without the angle correction, a false header.

use super::*;
use crate::lidar::EncodeError;

/// The manual's worked example: bytes 3..8 of a packet are `28 E5 6F BD 79`.
fn manual_packet(first_mm_q2: u16, last_mm_q2: u16) -> Vec<u8> {
    let mut s = vec![0x6FE5u16; 40];
    s[0] = first_mm_q2;
    s[39] = last_mm_q2;
    let mut out = vec![0u8; packet_len(40)];
    // FSA 0x6FE5 = (0x37F2 << 1) | 1, LSA 0x79BD = (0x3CDE << 1) | 1.
    emit_packet(0, 0x37F2, 0x3CDE, &s, &mut out).unwrap();
    out
}

#[test]
fn the_manual_example_by_hand() {
    let b = manual_packet(4000, 32_000);
    assert_eq!(&b[3..8], &[0x28, 0xE5, 0x6F, 0xBD, 0x79]);
    let p = YdlidarPacket::parse(&b).unwrap();
    assert_eq!(p.sample_count(), 40);
    // FSA: 0x37F2 = 14,322 → 223.78125°; LSA: 0x3CDE = 15,582 → 243.46875°; diff 19.6875°.
    assert_eq!(p.span_q6(), 1260);
    let raw = p.point(0, AngleCorrection::None);
    assert_eq!(raw.angle_cw_deg, 223.781_25);
    assert_eq!(p.point(39, AngleCorrection::None).angle_cw_deg, 243.468_75);
    // Sample 2 (i = 1): 223.78125 + 19.6875/39 = 224.286057…°.
    assert!((p.point(1, AngleCorrection::None).angle_cw_deg - 224.286_06).abs() < 1e-4);
    // Second level, the manual's distances 1,000 and 8,000 mm: AngCorrect −6.7622° and
    // −7.8374° (atan(21.8·(155.3 − 1000)/155,300) = atan(−0.118576) = −6.76219°), so
    // 217.0191° and 235.6313° (the manual prints 217.0178° and 235.6326°, from first-level
    // angles rounded to 223.78° and 243.47°).
    let first = p.point(0, AngleCorrection::Triangulation);
    let last = p.point(39, AngleCorrection::Triangulation);
    assert!((first.angle_cw_deg - 217.019_06).abs() < 2e-4, "{first:?}");
    assert!((last.angle_cw_deg - 235.631_32).abs() < 2e-4, "{last:?}");
    assert!((first.angle_cw_deg - 217.0178).abs() < 0.002);
    assert!((last.angle_cw_deg - 235.6326).abs() < 0.002);
    assert_eq!(first.range_m, 1.0);
    assert_eq!(last.range_m, 8.0);
    // The manual's sample E5 6F: 0x6FE5 / 4 = 7,161.25 mm.
    assert!((p.point(5, AngleCorrection::None).range_m - 7.161_25).abs() < 1e-6);
}

#[test]
fn the_sdk_document_zero_packet() {
    // The YDLidar-SDK protocol document's example zero packet: CS 0x54AB =
    // 0x55AA ^ 0x0101 ^ 0xAE53 ^ 0xAE53 ^ 0x0000; FSA 0xAE53 >> 1 = 22,313 → 348.640625°.
    let b = [
        0xAA, 0x55, 0x01, 0x01, 0x53, 0xAE, 0x53, 0xAE, 0xAB, 0x54, 0x00, 0x00,
    ];
    let p = YdlidarPacket::parse(&b).unwrap();
    assert!(p.is_start());
    assert_eq!(p.scan_freq_decihz(), None);
    let pt = p.point(0, AngleCorrection::Triangulation);
    assert_eq!(pt.angle_cw_deg, 22_313.0 / 64.0);
    assert!(!pt.valid);
    let mut out = [0u8; 12];
    assert_eq!(emit_packet(1, 22_313, 22_313, &[0], &mut out), Ok(12));
    assert_eq!(out, b);
}

#[test]
fn bad_fields_are_typed() {
    let mut b = manual_packet(4000, 4000);
    assert_eq!(
        YdlidarPacket::parse(&b[..50]),
        Err(YdlidarError::Truncated(50))
    );
    assert_eq!(
        YdlidarPacket::parse(&b[..3]),
        Err(YdlidarError::Truncated(3))
    );
    b[20] ^= 0x10;
    assert!(matches!(
        YdlidarPacket::parse(&b),
        Err(YdlidarError::BadChecksum { .. })
    ));
    let mut out = [0u8; 12];
    emit_packet(0, 23_040, 0, &[8], &mut out).unwrap();
    assert_eq!(
        YdlidarPacket::parse(&out),
        Err(YdlidarError::AngleOutOfRange)
    );
    emit_packet(0, 0, 0, &[], &mut out).unwrap();
    assert_eq!(
        YdlidarPacket::parse(&out[..10]),
        Err(YdlidarError::NoSamples)
    );
    emit_packet(0, 5, 5, &[8], &mut out).unwrap();
    out[4] &= !1;
    let cs = checksum(&out).to_le_bytes();
    out[8..10].copy_from_slice(&cs);
    assert_eq!(YdlidarPacket::parse(&out), Err(YdlidarError::BadCheckBit));
    out[0] = 0x55;
    assert_eq!(YdlidarPacket::parse(&out), Err(YdlidarError::BadHeader));
    assert_eq!(
        emit_packet(0, 0, 0, &[0; 256], &mut [0u8; 600]),
        Err(EncodeError::BadSampleCount(256))
    );
}

#[test]
fn revolution_round_trip_and_accounting() {
    let d: Vec<u16> = (0..360).map(|k| 2000 + 40 * k as u16).collect();
    let mut out = vec![0u8; revolution_len(360, 40)];
    assert_eq!(out.len(), 12 + 9 * 10 + 2 * 359);
    assert_eq!(encode_revolution(&d, 40, 70, &mut out), Ok(out.len()));
    let mut stream = vec![0x00, 0xAA, 0x13, 0xAA];
    stream.extend_from_slice(&out);
    // Then the zero packet (12 bytes) and 88 of the 90 bytes of the next packet.
    stream.extend_from_slice(&out[..100]);
    let mut dec = YdlidarDecoder::with_correction(AngleCorrection::None);
    let mut pts = Vec::new();
    dec.feed(&stream, |p| pts.push(p));
    assert_eq!(pts.len(), 360 + 1);
    assert_eq!(dec.buffered(), 88);
    for (k, p) in pts.iter().take(360).enumerate() {
        assert_eq!(p.angle_cw_deg, k as f32);
        assert_eq!(p.range_m, f32::from(d[k]) * 0.25e-3);
    }
    assert_eq!(dec.start_packets(), 2);
    assert_eq!(dec.scan_freq_decihz(), Some(70));
    let s = dec.stats();
    assert_eq!(s.skipped_bytes, 4);
    assert_eq!(
        s.bytes as usize,
        dec.frame_bytes() as usize + s.skipped_bytes as usize + dec.buffered()
    );
    // With the correction, each point moves by the correction of its own distance.
    let mut c = YdlidarDecoder::new();
    let mut cpts = Vec::new();
    c.feed(&out, |p| cpts.push(p));
    c.flush(|p| cpts.push(p));
    assert_eq!(cpts.len(), 360);
    for (k, p) in cpts.iter().enumerate().skip(1) {
        let dmm = f64::from(d[k]) / 4.0;
        let corr = (21.8 * (155.3 - dmm) / (155.3 * dmm)).atan().to_degrees();
        let want = (k as f64 + corr).rem_euclid(360.0);
        assert!(
            (f64::from(p.angle_cw_deg) - want).abs() < 1e-3,
            "{k}: {p:?}"
        );
    }
}

#[test]
fn a_false_header_with_a_long_packet_gives_back_what_it_swallowed() {
    let d: Vec<u16> = (0..360).map(|k| 1000 + k as u16).collect();
    let mut rev = vec![0u8; revolution_len(360, 40)];
    encode_revolution(&d, 40, 0, &mut rev).unwrap();
    // `AA 55`, CT 0, LSN 250: announces 510 bytes, swallows the whole revolution.
    let mut stream = vec![0xAA, 0x55, 0x00, 250];
    stream.extend_from_slice(&rev);
    stream.extend_from_slice(&rev);
    let mut dec = YdlidarDecoder::with_correction(AngleCorrection::None);
    let mut pts = Vec::new();
    dec.feed(&stream, |p| pts.push(p));
    // The last packet waits for the header that would follow it.
    assert_eq!(pts.len(), 720 - 39);
    assert_eq!(dec.buffered(), 88);
    dec.flush(|p| pts.push(p));
    assert_eq!(pts.len(), 720);
    let s = dec.stats();
    assert_eq!(s.bad_checksum, 1);
    assert_eq!(s.skipped_bytes, 4);
    assert_eq!(dec.buffered(), 0);
    assert_eq!(dec.frame_bytes() as usize, 2 * rev.len());
}
