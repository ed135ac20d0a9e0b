//! Unit tests: commands, descriptors and nodes by hand from the protocol document, and the decoder
//! over a mixed response stream.

use super::*;

#[test]
fn commands_are_two_bytes_and_parse_back() {
    let all = [
        (Command::Stop, 0x25),
        (Command::Reset, 0x40),
        (Command::Scan, 0x20),
        (Command::ForceScan, 0x21),
        (Command::GetInfo, 0x50),
        (Command::GetHealth, 0x52),
    ];
    for (c, code) in all {
        let mut out = [0u8; 2];
        assert_eq!(c.emit(&mut out), Ok(2));
        assert_eq!(out, [0xA5, code]);
        assert_eq!(Command::parse(&out), Ok(c));
    }
    assert_eq!(
        Command::parse(&[0xA5, 0x99]),
        Err(RplidarError::UnknownCommand(0x99))
    );
    assert!(Command::Stop.emit(&mut [0u8; 1]).is_err());
}

#[test]
fn descriptors_match_the_protocol_bytes() {
    let mut out = [0u8; 7];
    Descriptor::SCAN.emit(&mut out).unwrap();
    assert_eq!(out, SCAN_DESCRIPTOR);
    Descriptor::INFO.emit(&mut out).unwrap();
    assert_eq!(out, [0xA5, 0x5A, 0x14, 0x00, 0x00, 0x00, 0x04]);
    Descriptor::HEALTH.emit(&mut out).unwrap();
    assert_eq!(out, [0xA5, 0x5A, 0x03, 0x00, 0x00, 0x00, 0x06]);
    assert_eq!(Descriptor::parse(&SCAN_DESCRIPTOR), Ok(Descriptor::SCAN));
}

#[test]
fn node_bits_by_hand() {
    // quality 15, S = 1; angle 90.5° = 5,792 q6; distance 1,234.25 mm = 4,937 q2.
    let n = RplidarNode {
        start: true,
        quality: 15,
        angle_q6: 5792,
        distance_q2: 4937,
    };
    let mut b = [0u8; 5];
    n.emit(&mut b).unwrap();
    // b0 = 15<<2 | !S<<1 | S = 0x3D; b1 = (5792 & 0x7F)<<1 | 1 = 0x41; b2 = 5792>>7 = 45.
    assert_eq!(b, [0x3D, 0x41, 0x2D, 0x49, 0x13]);
    assert_eq!(RplidarNode::parse(&b), Ok(n));
    let p = n.point();
    assert_eq!(p.angle_cw_deg, 90.5);
    // f32 spacing at 1.2 m is 1.2e-7 m: two roundings (the reciprocal and the product).
    assert!((p.range_m - 1.23425).abs() <= 2.5e-7);
    let mut bad = b;
    bad[0] |= 0x02;
    assert_eq!(RplidarNode::parse(&bad), Err(RplidarError::BadStartFlag));
    let mut bad = b;
    bad[1] &= !1;
    assert_eq!(RplidarNode::parse(&bad), Err(RplidarError::BadCheckBit));
}

#[test]
fn decoder_reads_info_health_then_scan() {
    let mut s = Vec::new();
    let mut buf = [0u8; 64];
    s.extend_from_slice(&[0x00, 0xA5, 0x13]); // garbage
    let info = DeviceInfo {
        model: 0x18,
        firmware_minor: 29,
        firmware_major: 1,
        hardware: 7,
        serial: [0xAB; 16],
    };
    let n = info.emit_response(&mut buf).unwrap();
    s.extend_from_slice(&buf[..n]);
    let health = Health {
        status: 1,
        error_code: 0x1234,
    };
    let n = health.emit_response(&mut buf).unwrap();
    s.extend_from_slice(&buf[..n]);
    s.extend_from_slice(&SCAN_DESCRIPTOR);
    let ranges: Vec<f32> = (0..360).map(|k| 0.5 + k as f32 * 0.01).collect();
    let mut rev = vec![0u8; revolution_len(360)];
    encode_revolution(&ranges, 40, &mut rev).unwrap();
    s.extend_from_slice(&rev);
    let mut d = RplidarDecoder::new();
    let mut pts = Vec::new();
    d.feed(&s, |p| pts.push(p));
    assert_eq!(d.info(), Some(info));
    assert_eq!(d.health(), Some(health));
    assert_eq!(pts.len(), 360);
    assert_eq!(d.start_flags(), 1);
    for (k, p) in pts.iter().enumerate() {
        assert_eq!(p.angle_cw_deg, k as f32);
        assert!((p.range_m - ranges[k]).abs() <= 0.125e-3 + 1e-6);
        assert_eq!(p.quality, 40);
    }
    let st = d.stats();
    assert_eq!(st.skipped_bytes, 3);
    assert_eq!(
        st.bytes as usize,
        5 * (st.frames_ok as usize - 2 + st.bad_frames as usize)
            + d.response_bytes() as usize
            + st.skipped_bytes as usize
            + d.buffered()
    );
}
