//! Hostile CARMEN logs: a log without newlines is read in bounded memory, each overlong line a
//! counted bad line (never an abort), non-UTF-8 lines are bad lines too, and no control byte from
//! the log reaches the terminal.

mod common;

use beamfield_tools::carmen::{CarmenLog, LineErrorKind, ReadOptions, MAX_LINE_BYTES};
use common::bin;
use std::io::{BufReader, Read};

fn skip_bad() -> ReadOptions {
    ReadOptions {
        skip_bad_lines: true,
        ..ReadOptions::default()
    }
}

#[test]
fn a_log_without_newlines_is_bad_lines_not_an_abort() {
    // 64 MiB of NUL bytes, no newline: the old reader kept the whole "line" (and aborted on
    // /dev/zero after a 4 GiB allocation).
    let len: u64 = 64 << 20;
    let log = CarmenLog::read(BufReader::new(std::io::repeat(0).take(len)), skip_bad()).unwrap();
    // Each overlong line keeps MAX_LINE_BYTES + 1 bytes and skips the rest of the input (there is
    // no newline), so the whole input is one bad line.
    assert_eq!(log.bad_lines.len(), 1);
    assert_eq!(log.bad_lines[0].kind, LineErrorKind::TooLong);
    assert!(log.scans.is_empty() && log.skipped.is_empty());
    // Strict reading reports it as an error with its line number.
    let e = CarmenLog::read(
        BufReader::new(std::io::repeat(0).take(len)),
        ReadOptions::default(),
    )
    .unwrap_err();
    assert!(e.to_string().starts_with("line 1: longer than"), "{e}");
}

#[test]
fn overlong_lines_between_good_ones_are_counted_and_skipped() {
    let long = "X".repeat(MAX_LINE_BYTES + 10);
    let exact = "Y".repeat(MAX_LINE_BYTES);
    let text = format!("ODOM 1 2 3\n{long}\n{exact}\nODOM 4 5 6\n\u{0}\u{0}\n");
    let mut bytes = text.into_bytes();
    bytes.extend_from_slice(b"\xff\xfe bad\nODOM 7\n");
    let log = CarmenLog::read(&bytes[..], skip_bad()).unwrap();
    let kinds: Vec<(usize, LineErrorKind)> = log
        .bad_lines
        .iter()
        .map(|e| (e.line, e.kind.clone()))
        .collect();
    assert_eq!(
        kinds,
        vec![(2, LineErrorKind::TooLong), (6, LineErrorKind::NotUtf8)]
    );
    assert_eq!(log.skipped.get("ODOM"), Some(&3));
    // A line of exactly MAX_LINE_BYTES is read (as an unknown message type, shortened).
    assert_eq!(log.skipped.values().sum::<usize>(), 5);
}

#[test]
fn control_bytes_are_never_echoed() {
    let dir = std::env::temp_dir().join(format!("beamfield-loglimits-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("hostile.log");
    let mut bytes = b"\x1b[31mEVIL 1 2\nPARAM name\x07 v\x1b\n".to_vec();
    bytes.extend(std::iter::repeat_n(0u8, 1 << 20));
    bytes.extend_from_slice(b"\n\0\0\0\0 x\n");
    std::fs::write(&path, &bytes).unwrap();
    for json in [false, true] {
        let mut cmd = bin();
        if json {
            cmd.arg("--json");
        }
        let out = cmd.args(["log", "info"]).arg(&path).output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        for (name, stream) in [("stdout", &out.stdout), ("stderr", &out.stderr)] {
            let bad: Vec<u8> = stream
                .iter()
                .copied()
                .filter(|&b| (b < 0x20 && b != b'\n' && b != b'\t') || b == 0x7f)
                .collect();
            assert!(
                bad.is_empty(),
                "json {json}: control bytes on {name}: {bad:?}"
            );
        }
        let text = String::from_utf8_lossy(&out.stdout);
        // The message types are still counted, escaped.
        assert!(text.contains("EVIL"), "{text}");
        assert!(
            stream_len_ok(&out.stdout),
            "stdout {} bytes",
            out.stdout.len()
        );
    }
}

/// The 1 MiB NUL line is not echoed in any form (escaped it would be 2 MiB).
fn stream_len_ok(s: &[u8]) -> bool {
    s.len() < 16 * 1024
}
