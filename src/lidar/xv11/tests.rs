//! Unit tests: the checksum against the community notes' formula, the packet layout by hand,
//! and the decoder's resync and counters.

use super::*;

/// The checksum as written in the community notes, in u64 (no wrapping to reason about).
fn checksum_ref(p: &[u8]) -> u16 {
    let mut c: u64 = 0;
    for t in 0..10 {
        c = (c << 1) + u64::from(p[2 * t]) + (u64::from(p[2 * t + 1]) << 8);
    }
    (((c & 0x7FFF) + (c >> 15)) & 0x7FFF) as u16
}

#[test]
fn checksum_matches_reference_and_round_trip() {
    let pkt = Xv11Packet {
        packet: 37,
        speed_rpm_q6: 300 * 64,
        readings: [
            Xv11Reading {
                distance_mm: 1234,
                invalid: false,
                strength_warning: false,
                strength: 500,
            },
            Xv11Reading {
                distance_mm: 0x35,
                invalid: true,
                strength_warning: false,
                strength: 0,
            },
            Xv11Reading {
                distance_mm: 16_383,
                invalid: false,
                strength_warning: true,
                strength: 65_535,
            },
            Xv11Reading::default(),
        ],
    };
    let mut b = [0u8; 22];
    pkt.emit(&mut b).unwrap();
    assert_eq!(&b[..4], &[0xFA, 0xA0 + 37, 0x00, 0x4B]);
    assert_eq!(&b[4..8], &[0xD2, 0x04, 0xF4, 0x01]);
    assert_eq!(b[9], 0x80);
    assert_eq!(b[13], 0x7F);
    assert_eq!(u16::from_le_bytes([b[20], b[21]]), checksum_ref(&b));
    assert_eq!(Xv11Packet::parse(&b), Ok(pkt));
    let p = pkt.point(1);
    assert!(!p.valid);
    assert_eq!(pkt.point(2).angle_cw_deg, 150.0);
    assert!(!pkt.point(3).valid);
}

#[test]
fn decoder_resyncs_and_counts() {
    let readings: [Xv11Reading; 360] =
        core::array::from_fn(|a| Xv11Reading::from_range_m(0.2 + a as f32 * 0.01, 100));
    let mut rev = vec![0u8; REVOLUTION_LEN];
    encode_revolution(&readings, 300 * 64, &mut rev).unwrap();
    let mut s = vec![0xFA, 0x00, 0x13];
    s.extend_from_slice(&rev[..100]);
    s.extend_from_slice(&rev[105..]); // packet 4 loses 5 bytes
    let mut d = Xv11Decoder::new();
    let mut pts = Vec::new();
    d.feed(&s, |p| pts.push(p));
    let st = d.stats();
    assert_eq!(st.frames_ok, 89);
    assert_eq!(st.bad_checksum, 1);
    assert_eq!(pts.len(), 356);
    assert!(pts.iter().all(|p| (p.angle_cw_deg as usize) / 4 != 4));
    assert_eq!(
        st.bytes as usize,
        22 * st.frames_ok as usize + st.skipped_bytes as usize + d.buffered()
    );
    assert_eq!(d.last_speed_rpm_q6(), Some(19_200));
}
