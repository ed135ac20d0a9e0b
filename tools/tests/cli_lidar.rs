//! `beamfield lidar encode` and `beamfield lidar decode`, run as a user would, on the Intel log.

use std::path::PathBuf;
use std::process::Output;

mod common;

fn beamfield(args: &[&str]) -> Output {
    common::bin().args(args).output().unwrap()
}

fn intel() -> String {
    host_tests::data_dir()
        .join("laser_intel_lab/intel-corrected.log")
        .display()
        .to_string()
}

fn tmp(name: &str) -> String {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_lidar");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name).display().to_string()
}

/// The first `n` scans of the log, read independently of the tools' CARMEN reader: FLASER lines,
/// `FLASER n r0 … r(n−1) …`.
fn logged_scans(n: usize) -> Vec<Vec<f64>> {
    std::fs::read_to_string(intel())
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("FLASER "))
        .take(n)
        .map(|l| {
            let t: Vec<&str> = l.split_whitespace().collect();
            let beams: usize = t[1].parse().unwrap();
            t[2..2 + beams].iter().map(|v| v.parse().unwrap()).collect()
        })
        .collect()
}

#[test]
fn encode_then_decode_gives_the_logged_ranges_back() {
    let want = logged_scans(25);
    // (format, resolution m, largest distance carried m)
    for (format, res, max) in [
        ("ld06", 1e-3, 65.535),
        ("rplidar", 0.25e-3, 16.38375),
        ("xv11", 1e-3, 16.383),
    ] {
        let stream = tmp(&format!("{format}.bin"));
        let enc = common::run_json(common::bin().args([
            "--json",
            "lidar",
            "encode",
            "--log",
            &intel(),
            "--format",
            format,
            "--scans",
            "25",
            "--garbage",
            "40",
            "-o",
            &stream,
        ]));
        assert_eq!(enc["revolutions"], 25);
        assert_eq!(enc["garbage"], 40);
        let bytes = std::fs::metadata(&stream).unwrap().len();
        assert_eq!(enc["bytes"], bytes);
        let png = tmp(&format!("{format}.png"));
        let dec = common::run_json(common::bin().args([
            "--json", "lidar", "decode", "--format", format, "--layout", "carmen", "--ranges",
            &stream, "-o", &png,
        ]));
        assert_eq!(dec["decoder"]["skipped_bytes"], 40, "{format}");
        assert_eq!(dec["decoder"]["bad_checksum"], 0, "{format}");
        let scans = dec["scans"].as_array().unwrap();
        assert_eq!(scans.len(), 25, "{format}");
        for (k, (s, w)) in scans.iter().zip(&want).enumerate() {
            let got = s["ranges_m"].as_array().unwrap();
            assert_eq!(got.len(), w.len());
            for (i, (g, &w)) in got.iter().zip(w).enumerate() {
                if w >= res / 2.0 && w < max + res / 2.0 {
                    let g = g.as_f64().unwrap_or(f64::NAN);
                    assert!(
                        (g - w).abs() <= res / 2.0 + 1e-6 * w,
                        "{format} scan {k} beam {i}: {g} vs {w}"
                    );
                } else {
                    assert!(g.is_null(), "{format} scan {k} beam {i}: {g} for {w}");
                }
            }
        }
        let png = std::fs::read(&png).unwrap();
        assert_eq!(&png[1..4], b"PNG");
    }
}

/// YDLIDAR through the binary: the decoder applies the triangulation angle correction, so a beam
/// no rotor angle's corrected point lands on comes back empty (docs/lidar.md); every range that
/// comes back is the logged one to the quarter millimetre.
#[test]
fn ydlidar_encode_then_decode_gives_logged_ranges_or_nothing() {
    let want = logged_scans(25);
    let stream = tmp("ydlidar.bin");
    let enc = common::run_json(common::bin().args([
        "--json",
        "lidar",
        "encode",
        "--log",
        &intel(),
        "--format",
        "ydlidar",
        "--scans",
        "25",
        "--garbage",
        "40",
        "-o",
        &stream,
    ]));
    assert_eq!(enc["revolutions"], 25);
    let dec = common::run_json(common::bin().args([
        "--json", "lidar", "decode", "--format", "ydlidar", "--layout", "carmen", "--ranges",
        &stream,
    ]));
    assert_eq!(dec["decoder"]["skipped_bytes"], 40);
    assert_eq!(dec["decoder"]["bad_checksum"], 0);
    // A zero packet and nine packets of up to 40 samples per revolution.
    assert_eq!(dec["decoder"]["frames_ok"], 250);
    let scans = dec["scans"].as_array().unwrap();
    assert_eq!(scans.len(), 25);
    let (res, max) = (0.25e-3, 16.38375);
    let (mut back, mut empty) = (0usize, 0usize);
    for (k, (s, w)) in scans.iter().zip(&want).enumerate() {
        let got = s["ranges_m"].as_array().unwrap();
        assert_eq!(got.len(), w.len());
        for (i, (g, &w)) in got.iter().zip(w).enumerate() {
            let carried = w >= res / 2.0 && w < max + res / 2.0;
            match g.as_f64() {
                Some(g) => {
                    assert!(carried, "scan {k} beam {i}: {g} for {w}");
                    assert!(
                        (g - w).abs() <= res / 2.0 + 1e-6 * w,
                        "scan {k} beam {i}: {g} vs {w}"
                    );
                    back += 1;
                }
                None if carried => empty += 1,
                None => {}
            }
        }
    }
    assert!(empty * 20 < back, "{empty} empty, {back} back");
}

#[test]
fn corrupted_stream_is_counted_not_trusted() {
    let stream = tmp("bad.bin");
    let enc = common::run_json(common::bin().args([
        "--json",
        "lidar",
        "encode",
        "--log",
        &intel(),
        "--format",
        "ld06",
        "--scans",
        "40",
        "--corrupt",
        "0.002",
        "--seed",
        "9",
        "-o",
        &stream,
    ]));
    let flipped = enc["corrupted_bytes"].as_u64().unwrap();
    assert!(flipped > 0);
    let dec = common::run_json(common::bin().args([
        "--json", "lidar", "decode", "--format", "ld06", "--layout", "carmen", &stream,
    ]));
    let d = &dec["decoder"];
    let bad = d["bad_checksum"].as_u64().unwrap();
    // Every flipped byte breaks its frame's CRC (several flips may share one frame).
    assert!(
        bad > 0 && bad <= flipped,
        "{bad} bad frames for {flipped} flips"
    );
    // A flip costs at most its own frame (a flipped header byte makes the frame unrecognisable:
    // its bytes are skipped rather than counted as a bad checksum), never the next one.
    let ok = d["frames_ok"].as_u64().unwrap();
    assert!(
        ok + flipped >= 40 * 30,
        "{ok} frames ok after {flipped} flips"
    );
    assert!(ok + bad <= 40 * 30);
}

#[test]
fn errors_are_typed_and_help_explains() {
    let out = beamfield(&[
        "lidar",
        "encode",
        "--log",
        &intel(),
        "--format",
        "ld06",
        "--rpm",
        "0",
        "-o",
        &tmp("x.bin"),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--rpm must be in (0, 3000]"), "{err}");
    // A speed the LD06 decoder rejects as implausible (1,200 °/s, under 1,800) is refused at
    // encoding time, with the range that works.
    let out = beamfield(&[
        "lidar",
        "encode",
        "--log",
        &intel(),
        "--format",
        "ld06",
        "--rpm",
        "200",
        "-o",
        &tmp("slow.bin"),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--rpm must be in [300, 780] for ld06"),
        "{err}"
    );
    let out = beamfield(&[
        "lidar",
        "decode",
        "--format",
        "xv11",
        "/nonexistent/stream.bin",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/stream.bin"));
    let out = beamfield(&["lidar", "decode", "--format", "pl", "x.bin"]);
    assert!(!out.status.success());
    let out = beamfield(&["lidar", "encode", "--help"]);
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(
        help.contains("clockwise") && help.contains("--corrupt"),
        "{help}"
    );
}

/// A stream decoded with another protocol's `--format` is refused (not "0 frames ok" and
/// success), naming the protocol whose decoder finds its frames; `ld19` is the LD06 protocol.
#[test]
fn wrong_format_is_refused_and_the_right_one_named() {
    let formats = ["ld06", "rplidar", "xv11", "ydlidar"];
    for format in formats {
        let stream = tmp(&format!("sniff-{format}.bin"));
        common::run_json(common::bin().args([
            "--json",
            "lidar",
            "encode",
            "--log",
            &intel(),
            "--format",
            format,
            "--scans",
            "3",
            "--garbage",
            "300",
            "--seed",
            "5",
            "-o",
            &stream,
        ]));
        let right = common::run_json(
            common::bin().args(["--json", "lidar", "decode", "--format", format, &stream]),
        );
        assert!(
            right["decoder"]["frames_ok"].as_u64().unwrap() > 0,
            "{format}"
        );
        for other in formats.iter().filter(|f| **f != format) {
            let out = beamfield(&["lidar", "decode", "--format", other, &stream]);
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(!out.status.success(), "{format} decoded as {other}: {err}");
            assert!(
                err.contains(&format!("the stream does not look like {other}; it looks like {format} (try --format {format})")),
                "{format} decoded as {other}: {err}"
            );
        }
    }
    // The LD19 speaks the LD06 protocol: the same report under either name.
    let stream = tmp("sniff-ld06.bin");
    let ld06 = common::run_json(
        common::bin().args(["--json", "lidar", "decode", "--format", "ld06", &stream]),
    );
    let ld19 = common::run_json(
        common::bin().args(["--json", "lidar", "decode", "--format", "ld19", &stream]),
    );
    assert_eq!(ld06, ld19);
}

/// An empty capture and one of random bytes (no protocol's frames) are refused, saying so.
#[test]
fn streams_without_frames_are_refused() {
    let empty = tmp("empty.bin");
    std::fs::write(&empty, b"").unwrap();
    let out = beamfield(&["lidar", "decode", "--format", "ld06", &empty]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("empty.bin is empty: no ld06 frame to decode"),
        "{err}"
    );
    // 20,000 pseudo-random bytes (xorshift64).
    let noise = tmp("noise.bin");
    let mut x = 0x9e37_79b9_7f4a_7c15_u64;
    let bytes: Vec<u8> = (0..20_000)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 56) as u8
        })
        .collect();
    std::fs::write(&noise, bytes).unwrap();
    let out = beamfield(&["lidar", "decode", "--format", "xv11", &noise]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no xv11 frame in 20000 bytes: the stream does not look like xv11; no other decoder (ld06, rplidar, ydlidar) finds a frame in its first 16384 bytes either"),
        "{err}"
    );
}

/// Two real LD06-family frames (not written by this project's encoder): the example frame of
/// LDROBOT's *LD19 Development Manual* (v2.3) and a frame captured from a youyeetoo FHL-LD20
/// printed in UC San Diego's ECE 196 "UART Communication" tutorial (the same frames as
/// host-tests/tests/lidar_captures.rs). `--format ld19` decodes both; `--format xv11` is refused
/// and names ld06.
#[test]
fn real_ld19_frames_decode_as_ld19_and_are_named_under_another_format() {
    const LD19_MANUAL: &str =
        "54 2C 68 08 AB 7E E0 00 E4 DC 00 E2 D9 00 E5 D5 00 E3 D3 00 E4 D0 00 \
         E9 CD 00 E4 CA 00 E2 C7 00 E9 C5 00 E5 C2 00 E5 C0 00 E5 BE 82 3A 1A 50";
    const LD20_CAPTURE: &str =
        "54 2C 74 08 B0 86 00 00 D4 00 00 D4 00 00 D4 00 00 D4 00 00 D4 00 00 \
         D5 00 00 D5 00 00 49 00 00 5F 00 00 B0 00 00 D2 00 00 D4 02 89 1E 09 1F";
    let bytes: Vec<u8> = format!("{LD19_MANUAL} {LD20_CAPTURE}")
        .split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).unwrap())
        .collect();
    let stream = tmp("ld19-real.bin");
    std::fs::write(&stream, &bytes).unwrap();
    let dec = common::run_json(
        common::bin().args(["--json", "lidar", "decode", "--format", "ld19", &stream]),
    );
    assert_eq!(dec["format"], "ld06");
    assert_eq!(dec["decoder"]["frames_ok"], 2);
    let out = beamfield(&["lidar", "decode", "--format", "xv11", &stream]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(
            "no xv11 frame in 94 bytes: the stream does not look like xv11; it looks like ld06"
        ),
        "{err}"
    );
}
