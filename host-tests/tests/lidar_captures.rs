//! Frames printed in public documents, decoded to the values those documents give.
//!
//! Sources (bytes and values are facts quoted from them; see docs/lidar.md):
//! - LD06/LD19: the example frame of LDROBOT's *LD19 Development Manual* (v2.3, "communication
//!   protocol" chapter), whose decoded fields (speed 2,152 °/s, start 324.27°, end 334.70°,
//!   timestamp 6,714 ms, 12 (distance, intensity) pairs and the per-point angles) are also listed
//!   in the tests of the public `Paradoxdruid/pyLIDAR` repository (`tests/test_read_data.py`);
//! - LD06 family: a frame captured from a running youyeetoo FHL-LD20 and printed in the
//!   "UART Communication" tutorial of UC San Diego's ECE 196 course (Yang, Wu, Mottaghi, 2024),
//!   next to the manual's frame.

use beamfield::lidar::ld06::{self, Ld06Decoder, Ld06Frame, Ld06Sample};
use beamfield::lidar::LidarPoint;

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).unwrap())
        .collect()
}

const LD19_MANUAL: &str = "54 2C 68 08 AB 7E E0 00 E4 DC 00 E2 D9 00 E5 D5 00 E3 D3 00 E4 D0 00 \
     E9 CD 00 E4 CA 00 E2 C7 00 E9 C5 00 E5 C2 00 E5 C0 00 E5 BE 82 3A 1A 50";

const LD20_CAPTURE: &str = "54 2C 74 08 B0 86 00 00 D4 00 00 D4 00 00 D4 00 00 D4 00 00 D4 00 00 \
     D5 00 00 D5 00 00 49 00 00 5F 00 00 B0 00 00 D2 00 00 D4 02 89 1E 09 1F";

#[test]
fn ld19_manual_example_frame() {
    let bytes = hex(LD19_MANUAL);
    assert_eq!(bytes.len(), ld06::FRAME_LEN);
    assert_eq!(ld06::crc8(&bytes[..46]), 0x50, "the manual's CRC byte");
    let f = Ld06Frame::parse(&bytes).unwrap();
    assert_eq!(f.speed_deg_per_s, 2152);
    assert_eq!(f.start_angle_cdeg, 32_427);
    assert_eq!(f.end_angle_cdeg, 33_470);
    assert_eq!(f.timestamp_ms, 6714);
    let documented: [(u16, u8); 12] = [
        (224, 228),
        (220, 226),
        (217, 229),
        (213, 227),
        (211, 228),
        (208, 233),
        (205, 228),
        (202, 226),
        (199, 233),
        (197, 229),
        (194, 229),
        (192, 229),
    ];
    for (s, &(d, i)) in f.samples.iter().zip(&documented) {
        assert_eq!(
            *s,
            Ld06Sample {
                distance_mm: d,
                intensity: i
            }
        );
    }
    // The stream decoder gives the same points, angles interpolated as documented:
    // start + i·(end − start)/11, in hundredths of a degree.
    let mut d = Ld06Decoder::new();
    let mut pts: Vec<LidarPoint> = Vec::new();
    d.feed(&bytes, |p| pts.push(p));
    assert_eq!(pts.len(), 12);
    for (i, (p, &(dist, inten))) in pts.iter().zip(&documented).enumerate() {
        let want_deg = (32_427.0 + i as f64 * (33_470.0 - 32_427.0) / 11.0) / 100.0;
        assert!(
            (f64::from(p.angle_cw_deg) - want_deg).abs() < 1e-4,
            "point {i}: {} vs {want_deg}",
            p.angle_cw_deg
        );
        assert!((f64::from(p.range_m) - f64::from(dist) / 1000.0).abs() < 1e-7);
        assert_eq!(p.quality, u16::from(inten));
        assert!(p.valid);
        assert_eq!(p.timestamp_ms, Some(6714));
    }
    // Emitting the parsed frame gives the manual's bytes back.
    let mut out = [0u8; ld06::FRAME_LEN];
    f.emit(&mut out).unwrap();
    assert_eq!(out.to_vec(), bytes);
}

#[test]
fn ld20_capture_from_a_running_sensor() {
    let bytes = hex(LD20_CAPTURE);
    let f = Ld06Frame::parse(&bytes).unwrap();
    // speed 0x0874, start 0x86B0, end 0x8902, timestamp 0x091E, as printed.
    assert_eq!(f.speed_deg_per_s, 2164);
    assert_eq!(f.start_angle_cdeg, 34_480);
    assert_eq!(f.end_angle_cdeg, 35_074);
    assert_eq!(f.timestamp_ms, 2334);
    let intensities = [
        0xD4, 0xD4, 0xD4, 0xD4, 0xD4, 0xD5, 0xD5, 0x49, 0x5F, 0xB0, 0xD2, 0xD4,
    ];
    // Both frames back to back, behind a partial one, as a receiver that starts mid-stream sees.
    let mut stream = hex(LD19_MANUAL)[20..].to_vec();
    stream.extend(hex(LD20_CAPTURE));
    stream.extend(hex(LD19_MANUAL));
    let mut d = Ld06Decoder::new();
    let mut pts = Vec::new();
    d.feed(&stream, |p| pts.push(p));
    assert_eq!(d.stats().frames_ok, 2);
    assert_eq!(d.stats().skipped_bytes, 27);
    // The capture's points carry no distance: flagged invalid, with the sensor's intensities.
    for (p, &i) in pts[..12].iter().zip(&intensities) {
        assert!(!p.valid);
        assert_eq!(p.range_m, 0.0);
        assert_eq!(p.quality, i);
    }
    assert!((pts[0].angle_cw_deg - 344.80).abs() < 1e-4);
    assert!((pts[11].angle_cw_deg - 350.74).abs() < 1e-4);
    assert!(pts[12..].iter().all(|p| p.valid));
}
