//! In-module tests of the link: a round trip of every message, the exact sizes, every check of
//! the decoder and the encoder, truncations, bit flips and garbage.

use super::layout::{self, header};
use super::*;
use crate::pose::Pose;

const COV: [[f32; 3]; 3] = [
    [0.25, 0.01, -0.002],
    [0.01, 0.16, 0.003],
    [-0.002, 0.003, 0.07],
];

/// One message of every type, with values away from zero in every field.
fn samples() -> [Message; 9] {
    [
        Message::WheelOdometry(WheelOdometry {
            timestamp_us: 1_234_567_890_123,
            pose: Pose::new(12.5, -3.25, 1.5),
        }),
        Message::WheelTicks(WheelTicks {
            timestamp_us: u64::MAX,
            left_ticks: i32::MIN,
            right_ticks: 987_654,
        }),
        Message::SetInitialPose(SetInitialPose {
            timestamp_us: 0,
            pose: Pose::new(-99_999.0, 100_000.0, -core::f32::consts::PI),
            covariance: COV,
        }),
        Message::StartGlobalLocalization,
        Message::RequestNoMotionUpdate,
        Message::SetParameters(SetParameters {
            particles: Some(500),
            kappa: None,
            odom_alpha: [Some(0.2), None, Some(0.0), Some(1e-3)],
        }),
        Message::Estimate(Estimate {
            timestamp_us: 42_000_000,
            pose: Pose::new(3.0, 4.0, core::f32::consts::PI),
            covariance: COV,
            ess: 65_535.0,
            flags: EstimateFlags::INITIALIZED | EstimateFlags::RESAMPLED,
            quality: Quality {
                state: QualityState::Uncertain,
                score: 0.75,
            },
            odometry: Pose::new(-12.5, 0.25, -1.5),
        }),
        Message::Heartbeat(Heartbeat {
            timestamp_us: 5,
            bytes: u32::MAX,
            frames: 1,
            checksum_failures: 2,
            scans: 3,
            updates: 4,
            odometry: 5,
            drops: 6,
            link_errors: 7,
            lidar_skipped: 8,
            encode_failures: 9,
            refused: 10,
            uptime_ms: u32::MAX - 1,
        }),
        Message::Error(ErrorReport {
            code: ErrorCode::ValueOutOfRange,
            msg_type: 0x03,
            seq: 0xBEEF,
            detail: 20,
        }),
    ]
}

fn encoded(seq: u16, m: &Message) -> Vec<u8> {
    let mut out = [0u8; MAX_WIRE_LEN];
    let n = encode(seq, m, &mut out).unwrap();
    out[..n].to_vec()
}

/// A frame built by hand (no value check), as it goes on the wire.
fn raw_frame(version: u8, msg_type: u8, seq: u16, payload: &[u8]) -> Vec<u8> {
    let mut raw = vec![version, msg_type];
    raw.extend_from_slice(&seq.to_le_bytes());
    raw.extend_from_slice(payload);
    let crc = crc32(&raw);
    raw.extend_from_slice(&crc.to_le_bytes());
    let mut out = vec![0u8; raw.len() + 2];
    let n = cobs::try_encode(&raw, &mut out).unwrap();
    out.truncate(n);
    out.push(0);
    out
}

/// The payload of a sample message, as the encoder writes it.
fn payload_of(m: &Message) -> Vec<u8> {
    let wire = encoded(0, m);
    let mut raw = [0u8; MAX_FRAME_LEN];
    let n = cobs::decode(&wire[..wire.len() - 1], &mut raw)
        .unwrap()
        .frame_size();
    raw[header::LEN..n - header::CRC_LEN].to_vec()
}

/// Every frame a decoder makes of `bytes`.
fn stream(bytes: &[u8]) -> (Vec<Result<Frame, LinkError>>, LinkStats) {
    let mut d = Decoder::new();
    let mut out = Vec::new();
    d.feed(bytes, |r| out.push(r));
    (out, d.stats())
}

#[test]
fn every_message_round_trips_at_its_size() {
    // Payload sizes of docs/link-protocol.md.
    let sizes = [20, 16, 56, 0, 0, 23, 79, 56, 5];
    for (m, size) in samples().iter().zip(sizes) {
        assert_eq!(m.message_type().payload_len(), size, "{m:?}");
        for seq in [0, 1, 0x00FF, 0xFFFF] {
            let wire = encoded(seq, m);
            // Up to 254 bytes, COBS adds exactly one; then the delimiter.
            assert_eq!(
                wire.len(),
                header::LEN + size + header::CRC_LEN + 2,
                "{m:?}"
            );
            assert_eq!(wire.last(), Some(&0));
            assert!(!wire[..wire.len() - 1].contains(&0));
            let frame = decode(&wire[..wire.len() - 1]).unwrap();
            assert_eq!(frame, Frame { seq, message: *m });
            // Decoding then encoding again gives the same bytes (one encoding per value).
            assert_eq!(encoded(frame.seq, &frame.message), wire);
        }
    }
    assert_eq!(MAX_FRAME_LEN, 87);
    assert_eq!(MAX_WIRE_LEN, 89);
}

#[test]
fn the_worked_example_of_the_protocol_document() {
    // docs/link-protocol.md, "A worked example".
    let m = Message::WheelTicks(WheelTicks {
        timestamp_us: 1_000_000,
        left_ticks: 1200,
        right_ticks: -35,
    });
    let hex: String = encoded(7, &m).iter().map(|b| format!("{b:02x}")).collect();
    assert_eq!(
        hex,
        // COBS code 04 and 02 02 07; code 04 and 40 42 0f; four zeros (codes 01); code 03
        // and b0 04; code 01; code 09 and dd ff ff ff and the CRC 0xbc2fdc96; the delimiter.
        "04020207".to_string()
            + "0440420f"
            + "01010101"
            + "03b004"
            + "01"
            + "09ddffffff96dc2fbc"
            + "00",
        "{hex}"
    );
}

#[test]
fn a_stream_of_frames_decodes_in_order_and_counts_gaps() {
    let mut enc = Encoder::new();
    let mut bytes = vec![0u8]; // a leading delimiter is allowed
    let mut buf = [0u8; MAX_WIRE_LEN];
    for m in samples() {
        let n = enc.encode(&m, &mut buf).unwrap();
        bytes.extend_from_slice(&buf[..n]);
        bytes.push(0); // empty frames are ignored
    }
    bytes.extend(encoded(100, &Message::RequestNoMotionUpdate));
    let (out, stats) = stream(&bytes);
    assert_eq!(out.len(), 10);
    for (i, (r, m)) in out.iter().zip(samples()).enumerate() {
        assert_eq!(
            r,
            &Ok(Frame {
                seq: i as u16,
                message: m
            })
        );
    }
    assert_eq!(stats.frames, 10);
    assert_eq!(stats.errors(), 0);
    assert_eq!(stats.sequence_gaps, 1);
    assert_eq!(stats.bytes as usize, bytes.len());
}

#[test]
fn every_truncation_is_a_typed_error_and_the_next_frame_decodes() {
    for m in samples() {
        let wire = encoded(3, &m);
        let next = encoded(4, &Message::StartGlobalLocalization);
        for cut in 1..wire.len() - 1 {
            let mut bytes = wire[..cut].to_vec();
            bytes.push(0);
            bytes.extend_from_slice(&next);
            let (out, stats) = stream(&bytes);
            assert_eq!(out.len(), 2, "{m:?} cut at {cut}");
            assert!(
                matches!(
                    out[0],
                    Err(LinkError::BadCobs | LinkError::TooShort | LinkError::BadCrc)
                ),
                "{m:?} cut at {cut}: {:?}",
                out[0]
            );
            assert_eq!(
                out[1],
                Ok(Frame {
                    seq: 4,
                    message: Message::StartGlobalLocalization
                })
            );
            assert_eq!(stats.errors(), 1);
        }
    }
}

#[test]
fn every_bit_flip_is_refused_and_the_next_frame_decodes() {
    for m in samples() {
        let wire = encoded(9, &m);
        let next = encoded(10, &Message::RequestNoMotionUpdate);
        for byte in 0..wire.len() - 1 {
            for bit in 0..8 {
                let mut bytes = wire.clone();
                bytes[byte] ^= 1 << bit;
                bytes.extend_from_slice(&next);
                let (out, _) = stream(&bytes);
                let (last, rest) = out.split_last().unwrap();
                assert_eq!(
                    last,
                    &Ok(Frame {
                        seq: 10,
                        message: Message::RequestNoMotionUpdate
                    }),
                    "{m:?} byte {byte} bit {bit}"
                );
                // A flip to 0x00 cuts the frame in two; neither half decodes.
                assert!(!rest.is_empty() && rest.iter().all(|r| r.is_err()));
            }
        }
    }
}

#[test]
fn garbage_before_a_frame_costs_at_most_that_frame() {
    let frame = encoded(1, &Message::StartGlobalLocalization);
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    for len in 0..300 {
        let garbage: Vec<u8> = (0..len)
            .map(|_| {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                (seed >> 24) as u8
            })
            .collect();
        // Glued to the frame: at most that frame is lost, the next one decodes.
        let mut bytes = garbage.clone();
        bytes.extend_from_slice(&frame);
        bytes.extend_from_slice(&frame);
        let (out, _) = stream(&bytes);
        assert_eq!(out.last().unwrap(), &decode(&frame[..frame.len() - 1]));
        // With a delimiter in between, nothing is lost.
        let mut bytes = garbage;
        bytes.push(0);
        bytes.extend_from_slice(&frame);
        let (out, _) = stream(&bytes);
        assert!(out.last().unwrap().is_ok());
    }
}

#[test]
fn a_run_longer_than_any_frame_is_refused_once() {
    let mut bytes = vec![0x55u8; 1000];
    bytes.push(0);
    bytes.extend(encoded(0, &Message::RequestNoMotionUpdate));
    let (out, stats) = stream(&bytes);
    assert_eq!(out.len(), 2);
    assert_eq!(out[0], Err(LinkError::Oversized));
    assert!(out[1].is_ok());
    assert_eq!(stats.oversized, 1);
    assert_eq!(
        decode(&[0x55; MAX_ENCODED_LEN + 1]),
        Err(LinkError::Oversized)
    );
}

#[test]
fn header_errors_keep_the_type_and_sequence_number() {
    let payload = payload_of(&samples()[0]);
    let one = |bytes: Vec<u8>| decode(&bytes[..bytes.len() - 1]);
    assert_eq!(
        one(raw_frame(VERSION + 1, 0x01, 77, &payload)),
        Err(LinkError::WrongVersion {
            version: VERSION + 1,
            msg_type: 1,
            seq: 77
        })
    );
    assert_eq!(
        one(raw_frame(VERSION, 0x07, 78, &payload)),
        Err(LinkError::UnknownType {
            msg_type: 7,
            seq: 78
        })
    );
    assert_eq!(
        one(raw_frame(VERSION, 0x01, 79, &payload[..19])),
        Err(LinkError::WrongLength {
            msg_type: 1,
            seq: 79,
            len: 19
        })
    );
    assert_eq!(
        one(raw_frame(VERSION, 0x04, 80, &[0])),
        Err(LinkError::WrongLength {
            msg_type: 4,
            seq: 80,
            len: 1
        })
    );
    assert_eq!(one(vec![1, 1, 0]), Err(LinkError::TooShort));
    assert_eq!(decode(&[]), Err(LinkError::TooShort));
    assert_eq!(decode(&[5, 1, 0, 1]), Err(LinkError::BadCobs));
    let e = one(raw_frame(VERSION, 0x07, 78, &[])).unwrap_err();
    assert_eq!(
        ErrorReport::for_link_error(&e),
        Some(ErrorReport {
            code: ErrorCode::UnknownType,
            msg_type: 7,
            seq: 78,
            detail: 0
        })
    );
    assert_eq!(ErrorReport::for_link_error(&LinkError::BadCrc), None);
}

/// Payload offsets of every `f32` field that must be finite, per sample index.
fn float_fields() -> Vec<(usize, Vec<usize>)> {
    let cov = |start: usize| (0..9).map(move |i| start + 4 * i);
    vec![
        (0, vec![8, 12, 16]),
        (2, [8, 12, 16].into_iter().chain(cov(20)).collect()),
        (6, [8, 12, 16, 56, 63].into_iter().chain(cov(20)).collect()),
    ]
}

#[test]
fn nan_and_infinity_in_any_field_are_refused_both_ways() {
    let s = samples();
    for (i, offsets) in float_fields() {
        let m = &s[i];
        let t = m.message_type() as u8;
        for at in offsets {
            for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                let mut p = payload_of(m);
                p[at..at + 4].copy_from_slice(&bad.to_le_bytes());
                let wire = raw_frame(VERSION, t, 5, &p);
                let got = decode(&wire[..wire.len() - 1]);
                // An off-diagonal NaN fails the symmetry check at the first of the pair.
                let LinkError::ValueOutOfRange { offset, seq: 5, .. } = got.unwrap_err() else {
                    panic!("{m:?} at {at}")
                };
                assert!(usize::from(offset) <= at, "{m:?} at {at}: {offset}");
            }
        }
    }
    // The encoder refuses them too.
    let mut m = WheelOdometry::default();
    m.pose.y_m = f32::NAN;
    let mut out = [0u8; MAX_WIRE_LEN];
    assert_eq!(
        encode(1, &Message::WheelOdometry(m), &mut out),
        Err(LinkError::ValueOutOfRange {
            msg_type: 1,
            seq: 1,
            offset: 12
        })
    );
}

#[test]
fn out_of_range_values_are_refused_at_their_offset() {
    let s = samples();
    let with = |i: usize, at: usize, bytes: &[u8]| {
        let m = &s[i];
        let mut p = payload_of(m);
        p[at..at + bytes.len()].copy_from_slice(bytes);
        let wire = raw_frame(VERSION, m.message_type() as u8, 0, &p);
        match decode(&wire[..wire.len() - 1]) {
            Err(LinkError::ValueOutOfRange { offset, .. }) => Some(usize::from(offset)),
            _ => None,
        }
    };
    let f = |v: f32| v.to_le_bytes();
    // Positions beyond 100 km, headings beyond π.
    assert_eq!(with(0, 8, &f(100_001.0)), Some(8));
    assert_eq!(with(0, 12, &f(-1e6)), Some(12));
    let past_pi = f32::from_bits(core::f32::consts::PI.to_bits() + 1);
    assert_eq!(with(0, 16, &f(past_pi)), Some(16));
    assert_eq!(with(0, 16, &f(-past_pi)), Some(16));
    // Covariance: a negative variance, an asymmetric pair (reported at its first entry).
    assert_eq!(with(2, 20 + 4 * 4, &f(-0.01)), Some(36));
    assert_eq!(with(2, 20 + 4 * 5, &f(0.0031)), Some(20 + 4 * 5));
    assert_eq!(with(6, 20 + 4 * 7, &f(0.0031)), Some(20 + 4 * 5));
    // ESS, flags, quality state and score.
    assert_eq!(with(6, 56, &f(-1.0)), Some(56));
    assert_eq!(with(6, 56, &f(65_536.0)), Some(56));
    assert_eq!(with(6, 60, &[0x40, 0]), Some(60));
    assert_eq!(with(6, 62, &[4]), Some(62));
    assert_eq!(with(6, 63, &f(1.01)), Some(63));
    // SetParameters: reserved presence bits, absent fields not zero, values.
    assert_eq!(with(5, 0, &[0xFF]), Some(0));
    assert_eq!(with(5, 3, &f(2.0)), Some(3));
    assert_eq!(with(5, 11, &f(-0.0)), Some(11));
    assert_eq!(with(5, 1, &[0, 0]), Some(1));
    assert_eq!(with(5, 7, &f(-0.1)), Some(7));
    // Error: codes 0 and 8.
    assert_eq!(with(8, 0, &[0]), Some(0));
    assert_eq!(with(8, 0, &[8]), Some(0));
    // Valid edges pass.
    assert_eq!(with(0, 16, &f(core::f32::consts::PI)), None);
    assert_eq!(with(6, 56, &f(0.0)), None);
    assert_eq!(with(6, 63, &f(1.0)), None);
    assert_eq!(with(6, 62, &[3]), None);
    let kappa = SetParameters {
        kappa: Some(0.0),
        ..SetParameters::default()
    };
    let mut out = [0u8; MAX_WIRE_LEN];
    assert!(matches!(
        encode(0, &Message::SetParameters(kappa), &mut out),
        Err(LinkError::ValueOutOfRange { offset: 3, .. })
    ));
}

#[test]
fn small_buffers_and_sequence_wrap() {
    let m = samples()[6];
    let need = encoded(0, &m).len();
    let mut out = [0u8; MAX_WIRE_LEN];
    for len in 0..need {
        assert_eq!(
            encode(0, &m, &mut out[..len]),
            Err(LinkError::BufferTooSmall)
        );
    }
    let mut enc = Encoder::starting_at(u16::MAX);
    enc.encode(&m, &mut out).unwrap();
    assert_eq!(enc.next_seq(), 0);
    // A refused message does not use up a sequence number.
    let bad = Message::WheelOdometry(WheelOdometry {
        timestamp_us: 0,
        pose: Pose::new(f32::NAN, 0.0, 0.0),
    });
    assert!(enc.encode(&bad, &mut out).is_err());
    assert_eq!(enc.next_seq(), 0);
}

#[test]
fn estimate_from_the_filter_is_made_symmetric() {
    let mut e = crate::mcl::Estimate {
        pose: Pose::new(1.0, 2.0, 0.5),
        covariance: COV,
        ess: 120.0,
    };
    e.covariance[0][1] = 0.010_000_1;
    let m = Estimate::from_mcl(
        &e,
        7,
        EstimateFlags::INITIALIZED,
        Quality::default(),
        Pose::default(),
    );
    assert_eq!(m.covariance[0][1], m.covariance[1][0]);
    assert!(decode(&encoded(0, &Message::Estimate(m))[..MAX_ENCODED_LEN]).is_ok());
}

#[test]
fn errors_display_in_lower_case() {
    let all = [
        LinkError::Oversized,
        LinkError::BadCobs,
        LinkError::TooShort,
        LinkError::BadCrc,
        LinkError::WrongVersion {
            version: 2,
            msg_type: 1,
            seq: 3,
        },
        LinkError::UnknownType {
            msg_type: 9,
            seq: 3,
        },
        LinkError::WrongLength {
            msg_type: 1,
            seq: 3,
            len: 4,
        },
        LinkError::ValueOutOfRange {
            msg_type: 1,
            seq: 3,
            offset: 8,
        },
        LinkError::BufferTooSmall,
    ];
    for e in all {
        let s = e.to_string();
        assert!(s.chars().next().unwrap().is_lowercase(), "{s}");
        let crate_error: crate::Error = e.into();
        assert!(crate_error.to_string().starts_with("link: "));
    }
    assert_eq!(layout::estimate::LEN, MAX_PAYLOAD_LEN);
}
