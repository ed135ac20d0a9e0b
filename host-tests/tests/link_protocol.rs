//! The device link (`beamfield::link`) as a host sees it: property tests of round trips and of
//! damaged streams, and a check against an implementation written from
//! `docs/link-protocol.md` alone (`host-tests/python/link_interop.py`: the PyPI `cobs` package,
//! `binascii.crc32`, `struct`) that decodes the frames this crate encodes and encodes frames this
//! crate decodes. That check is skipped, with the reason printed, when `python3` or the `cobs`
//! package is missing (`pip install cobs==1.2.2`).

use beamfield::link::{
    decode, encode, Decoder, Encoder, ErrorCode, ErrorReport, Estimate, EstimateFlags, Frame,
    Heartbeat, LinkError, Message, Quality, QualityState, SetInitialPose, SetParameters,
    WheelOdometry, WheelTicks, MAX_POSITION_M, MAX_THETA_RAD, MAX_WIRE_LEN,
};
use beamfield::Pose;
use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::TestRunner;
use std::path::{Path, PathBuf};
use std::process::Command;

fn pose() -> impl Strategy<Value = Pose> {
    let p = -MAX_POSITION_M..=MAX_POSITION_M;
    (p.clone(), p, -MAX_THETA_RAD..=MAX_THETA_RAD).prop_map(|(x, y, t)| Pose::new(x, y, t))
}

/// Symmetric, non-negative diagonal (not necessarily positive definite: the link does not ask).
fn covariance() -> impl Strategy<Value = [[f32; 3]; 3]> {
    (
        prop::array::uniform3(0.0f32..1e3),
        prop::array::uniform3(-1e3f32..1e3),
    )
        .prop_map(|([a, b, c], [d, e, f])| [[a, d, e], [d, b, f], [e, f, c]])
}

fn opt<T: std::fmt::Debug + Clone + 'static>(
    s: impl Strategy<Value = T> + 'static,
) -> impl Strategy<Value = Option<T>> {
    prop::option::of(s)
}

fn message() -> impl Strategy<Value = Message> {
    let flags = (0u16..64).prop_map(|b| EstimateFlags::from_bits(b).unwrap());
    let state = prop::sample::select(vec![
        QualityState::Unknown,
        QualityState::Tracking,
        QualityState::Uncertain,
        QualityState::Lost,
    ]);
    let code = (1u8..=7).prop_map(|c| ErrorCode::from_u8(c).unwrap());
    prop_oneof![
        (any::<u64>(), pose()).prop_map(|(timestamp_us, pose)| Message::WheelOdometry(
            WheelOdometry { timestamp_us, pose }
        )),
        (any::<u64>(), any::<i32>(), any::<i32>()).prop_map(|(t, l, r)| Message::WheelTicks(
            WheelTicks {
                timestamp_us: t,
                left_ticks: l,
                right_ticks: r
            }
        )),
        (any::<u64>(), pose(), covariance()).prop_map(|(timestamp_us, pose, covariance)| {
            Message::SetInitialPose(SetInitialPose {
                timestamp_us,
                pose,
                covariance,
            })
        }),
        Just(Message::StartGlobalLocalization),
        Just(Message::RequestNoMotionUpdate),
        (
            opt(1u16..),
            opt(1e-3f32..1e3),
            prop::array::uniform4(opt(0.0f32..10.0))
        )
            .prop_map(|(particles, kappa, odom_alpha)| {
                Message::SetParameters(SetParameters {
                    particles,
                    kappa,
                    odom_alpha,
                })
            }),
        (
            any::<u64>(),
            pose(),
            covariance(),
            0.0f32..=65_535.0,
            flags,
            state,
            0.0f32..=1.0,
            pose()
        )
            .prop_map(
                |(timestamp_us, pose, covariance, ess, flags, state, score, odometry)| {
                    Message::Estimate(Estimate {
                        timestamp_us,
                        pose,
                        covariance,
                        ess,
                        flags,
                        quality: Quality { state, score },
                        odometry,
                    })
                }
            ),
        (any::<u64>(), prop::array::uniform12(any::<u32>())).prop_map(|(t, c)| {
            Message::Heartbeat(Heartbeat {
                timestamp_us: t,
                bytes: c[0],
                frames: c[1],
                checksum_failures: c[2],
                scans: c[3],
                updates: c[4],
                odometry: c[5],
                drops: c[6],
                link_errors: c[7],
                lidar_skipped: c[8],
                encode_failures: c[9],
                refused: c[10],
                uptime_ms: c[11],
            })
        }),
        (code, any::<u8>(), any::<u16>(), any::<u8>()).prop_map(|(code, msg_type, seq, detail)| {
            Message::Error(ErrorReport {
                code,
                msg_type,
                seq,
                detail,
            })
        }),
    ]
}

fn wire(seq: u16, m: &Message) -> Vec<u8> {
    let mut out = [0u8; MAX_WIRE_LEN];
    let n = encode(seq, m, &mut out).unwrap();
    out[..n].to_vec()
}

fn stream(bytes: &[u8]) -> (Vec<Result<Frame, LinkError>>, Decoder) {
    let mut d = Decoder::new();
    let mut out = Vec::new();
    d.feed(bytes, |r| out.push(r));
    (out, d)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn every_message_round_trips(m in message(), seq in any::<u16>()) {
        let bytes = wire(seq, &m);
        prop_assert_eq!(bytes.len(), m.message_type().payload_len() + 10);
        let frame = decode(&bytes[..bytes.len() - 1]).unwrap();
        prop_assert_eq!(frame, Frame { seq, message: m });
        prop_assert_eq!(wire(frame.seq, &frame.message), bytes);
    }

    #[test]
    fn any_bytes_are_frames_or_typed_errors(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
        let (out, d) = stream(&bytes);
        let s = d.stats();
        prop_assert_eq!(s.bytes as usize, bytes.len());
        prop_assert_eq!((s.frames + s.errors()) as usize, out.len());
        // Whatever decodes holds valid values: it encodes again without complaint.
        for f in out.into_iter().flatten() {
            wire(f.seq, &f.message);
        }
    }

    #[test]
    fn damage_costs_at_most_the_damaged_frame(
        m in message(),
        garbage in prop::collection::vec(any::<u8>(), 0..200),
        cut in any::<prop::sample::Index>(),
        flip in any::<(prop::sample::Index, u8)>(),
    ) {
        let a = wire(1, &m);
        let b = wire(2, &Message::StartGlobalLocalization);
        let want = Ok(Frame { seq: 2, message: Message::StartGlobalLocalization });
        // Garbage glued in front, a truncated frame, a frame with one bit flipped: each is
        // refused with a typed error (or, for garbage, swallowed), and the next frame decodes.
        let mut glued = garbage.clone();
        glued.extend_from_slice(&a);
        glued.extend_from_slice(&b);
        let (out, _) = stream(&glued);
        prop_assert_eq!(out.last().unwrap(), &want);

        let mut truncated = a[..cut.index(a.len() - 1)].to_vec();
        truncated.push(0);
        truncated.extend_from_slice(&b);
        let (out, _) = stream(&truncated);
        prop_assert!(out[..out.len() - 1].iter().all(|r| r.is_err()));
        prop_assert_eq!(out.last().unwrap(), &want);

        let mut flipped = a.clone();
        let i = flip.0.index(a.len() - 1);
        flipped[i] ^= 1 << (flip.1 % 8);
        flipped.extend_from_slice(&b);
        let (out, _) = stream(&flipped);
        prop_assert!(out[..out.len() - 1].iter().all(|r| r.is_err()));
        prop_assert!(out.len() >= 2);
        prop_assert_eq!(out.last().unwrap(), &want);
    }
}

/// The line `link_interop.py` prints for a frame: type, sequence number, then every payload
/// field in layout order (integers in decimal, f32 as `f:` and its bits in hex).
fn line(seq: u16, m: &Message) -> String {
    let f = |v: f32| format!("f:{:08x}", v.to_bits());
    let pose = |p: &Pose| vec![f(p.x_m), f(p.y_m), f(p.theta_rad)];
    let cov = |c: &[[f32; 3]; 3]| c.iter().flatten().map(|&v| f(v)).collect::<Vec<_>>();
    let fields: Vec<String> = match m {
        Message::WheelOdometry(w) => [vec![w.timestamp_us.to_string()], pose(&w.pose)].concat(),
        Message::WheelTicks(w) => vec![
            w.timestamp_us.to_string(),
            w.left_ticks.to_string(),
            w.right_ticks.to_string(),
        ],
        Message::SetInitialPose(s) => [
            vec![s.timestamp_us.to_string()],
            pose(&s.pose),
            cov(&s.covariance),
        ]
        .concat(),
        Message::StartGlobalLocalization | Message::RequestNoMotionUpdate => vec![],
        Message::SetParameters(p) => {
            let mut present = u8::from(p.particles.is_some()) | u8::from(p.kappa.is_some()) << 1;
            for (i, a) in p.odom_alpha.iter().enumerate() {
                present |= u8::from(a.is_some()) << (2 + i);
            }
            let mut v = vec![
                present.to_string(),
                p.particles.unwrap_or(0).to_string(),
                f(p.kappa.unwrap_or(0.0)),
            ];
            v.extend(p.odom_alpha.iter().map(|a| f(a.unwrap_or(0.0))));
            v
        }
        Message::Estimate(e) => [
            vec![e.timestamp_us.to_string()],
            pose(&e.pose),
            cov(&e.covariance),
            vec![
                f(e.ess),
                e.flags.bits().to_string(),
                (e.quality.state as u8).to_string(),
                f(e.quality.score),
            ],
            pose(&e.odometry),
        ]
        .concat(),
        Message::Heartbeat(h) => [
            h.timestamp_us,
            h.bytes.into(),
            h.frames.into(),
            h.checksum_failures.into(),
            h.scans.into(),
            h.updates.into(),
            h.odometry.into(),
            h.drops.into(),
            h.link_errors.into(),
            h.lidar_skipped.into(),
            h.encode_failures.into(),
            h.refused.into(),
            h.uptime_ms.into(),
        ]
        .iter()
        .map(u64::to_string)
        .collect(),
        Message::Error(e) => vec![
            (e.code as u8).to_string(),
            e.msg_type.to_string(),
            e.seq.to_string(),
            e.detail.to_string(),
        ],
        _ => unreachable!("a message type this test does not know"),
    };
    let mut out = format!("0x{:02x} {seq}", m.message_type() as u8);
    for field in fields {
        out.push(' ');
        out.push_str(&field);
    }
    out
}

fn kind(e: &LinkError) -> &'static str {
    match e {
        LinkError::Oversized => "oversized",
        LinkError::BadCobs => "bad_cobs",
        LinkError::TooShort => "too_short",
        LinkError::BadCrc => "bad_crc",
        LinkError::WrongVersion { .. } => "wrong_version",
        LinkError::UnknownType { .. } => "unknown_type",
        LinkError::WrongLength { .. } => "wrong_length",
        LinkError::ValueOutOfRange { .. } => "out_of_range",
        _ => "other",
    }
}

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("python/link_interop.py")
}

/// Why the Python check cannot run here, if it cannot.
fn python_missing() -> Option<String> {
    match Command::new("python3")
        .args(["-c", "import cobs.cobs"])
        .output()
    {
        Err(e) => Some(format!("python3 not found ({e})")),
        Ok(o) if !o.status.success() => Some(format!(
            "python3 has no `cobs` package (pip install cobs==1.2.2): {}",
            String::from_utf8_lossy(&o.stderr)
                .lines()
                .last()
                .unwrap_or("")
        )),
        Ok(_) => None,
    }
}

fn python(args: &[&Path]) -> String {
    let out = Command::new("python3")
        .arg(script())
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "link_interop.py {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// A few hundred messages of every type, the same on every run.
fn interop_messages() -> Vec<Message> {
    let mut runner = TestRunner::deterministic();
    let strategy = message();
    (0..400)
        .map(|_| strategy.new_tree(&mut runner).unwrap().current())
        .collect()
}

#[test]
fn an_implementation_from_the_document_reads_and_writes_the_same_frames() {
    if let Some(why) = python_missing() {
        println!("SKIPPED python interop: {why}");
        return;
    }
    let dir = std::env::temp_dir().join(format!("beamfield-link-interop-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let messages = interop_messages();

    // Rust encodes (with damaged frames in between), Python decodes.
    let mut enc = Encoder::starting_at(65_000); // wraps within the run
    let mut bytes = Vec::new();
    let mut want = Vec::new();
    let mut buf = [0u8; MAX_WIRE_LEN];
    for (i, m) in messages.iter().enumerate() {
        let seq = enc.next_seq();
        let n = enc.encode(m, &mut buf).unwrap();
        let mut frame = buf[..n].to_vec();
        if i % 50 == 7 {
            // A CRC byte damaged (never to 0x00): Rust and Python must both refuse it as such.
            let at = n - 2;
            frame[at] = if frame[at] == 0x01 {
                0x02
            } else {
                frame[at] ^ 0x01
            };
            let (got, _) = stream(&frame);
            want.push(format!("error {}", kind(got[0].as_ref().unwrap_err())));
        } else {
            want.push(line(seq, m));
        }
        bytes.extend_from_slice(&frame);
    }
    let rust_frames = dir.join("rust_frames.bin");
    std::fs::write(&rust_frames, &bytes).unwrap();
    let got = python(&[Path::new("decode"), &rust_frames]);
    let got: Vec<&str> = got.lines().collect();
    assert_eq!(got.len(), want.len());
    for (i, (g, w)) in got.iter().zip(&want).enumerate() {
        assert_eq!(g, w, "frame {i}");
    }
    let python_read = want.iter().filter(|w| !w.starts_with("error")).count();

    // Python encodes from the same values, then frames to refuse; Rust decodes.
    let lines: String = messages
        .iter()
        .enumerate()
        .map(|(i, m)| line(i as u16, m) + "\n")
        .collect();
    let lines_path = dir.join("lines.txt");
    let python_frames = dir.join("python_frames.bin");
    std::fs::write(&lines_path, lines).unwrap();
    let bad = python(&[Path::new("encode"), &lines_path, &python_frames]);
    let bytes = std::fs::read(&python_frames).unwrap();
    let (out, decoder) = stream(&bytes);
    let bad: Vec<Vec<&str>> = bad.lines().map(|l| l.split(' ').collect()).collect();
    // The garbage run, every message, every refused frame.
    assert_eq!(out.len(), 1 + messages.len() + bad.len());
    assert!(out[0].is_err(), "{:?}", out[0]);
    for (i, (r, m)) in out[1..].iter().zip(&messages).enumerate() {
        assert_eq!(
            r,
            &Ok(Frame {
                seq: i as u16,
                message: *m
            }),
            "frame {i}"
        );
    }
    for (r, b) in out[1 + messages.len()..].iter().zip(&bad) {
        let e = r.as_ref().unwrap_err();
        assert_eq!(kind(e), b[1], "{b:?}: {e:?}");
        let msg_type = u8::from_str_radix(b[2].trim_start_matches("0x"), 16).unwrap();
        let seq: u16 = b[3].parse().unwrap();
        let offset: u8 = b[4].parse().unwrap();
        match *e {
            LinkError::ValueOutOfRange {
                msg_type: t,
                seq: s,
                offset: o,
            } => assert_eq!((t, s, o), (msg_type, seq, offset), "{b:?}"),
            LinkError::WrongLength {
                msg_type: t,
                seq: s,
                ..
            }
            | LinkError::UnknownType {
                msg_type: t,
                seq: s,
            }
            | LinkError::WrongVersion {
                msg_type: t,
                seq: s,
                ..
            } => assert_eq!((t, s), (msg_type, seq), "{b:?}"),
            _ => {}
        }
    }
    // Python's frames are byte for byte this crate's.
    let mut rust = vec![0u8];
    for (i, m) in messages.iter().enumerate() {
        rust.extend(wire(i as u16, m));
    }
    let garbage_end = bytes.iter().position(|&b| b == 0).unwrap();
    assert_eq!(&bytes[garbage_end..garbage_end + rust.len()], &rust[..]);
    assert_eq!(decoder.stats().frames as usize, messages.len());
    // And both decoders make the same of those bytes, garbage and bad frames included.
    let python_read_back = python(&[Path::new("decode"), &python_frames]);
    let rust_read_back: Vec<String> = out
        .iter()
        .map(|r| match r {
            Ok(f) => line(f.seq, &f.message),
            Err(e) => format!("error {}", kind(e)),
        })
        .collect();
    assert_eq!(python_read_back.lines().collect::<Vec<_>>(), rust_read_back);
    println!(
        "python interop: python read {python_read} frames rust wrote and refused {} damaged; \
         rust read {} frames python wrote and refused {} bad ones",
        want.len() - python_read,
        messages.len(),
        bad.len()
    );
    std::fs::remove_dir_all(&dir).ok();
}
