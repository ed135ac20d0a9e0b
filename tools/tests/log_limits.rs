//! Hostile CARMEN logs: a log without newlines is read in bounded memory, each overlong line a
//! counted bad line (never an abort), non-UTF-8 lines are bad lines too, and no control byte from
//! the log reaches the terminal.

mod common;

use beamfield_tools::input::carmen::{CarmenLog, LineErrorKind, ReadOptions, MAX_LINE_BYTES};
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

fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("beamfield-loglimits-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `error: PATH is larger than 268435456 bytes, the limit for a CARMEN log`.
fn too_large(path: &str) -> String {
    format!(
        "error: {path} is larger than {} bytes, the limit for a CARMEN log",
        beamfield_tools::input::limits::MAX_LOG_BYTES
    )
}

#[test]
fn a_log_that_never_ends_stops_at_256_mib() {
    let d = scratch("endless");
    let out = d.join("map.yaml").display().to_string();
    // /dev/zero: one NUL line that never ends. Its bytes are skipped without being kept, but
    // they never end either: the log's size limit stops the read.
    for args in [
        vec!["log", "info", "/dev/zero"],
        vec!["map", "from-log", "/dev/zero", "-o", &out],
    ] {
        let o = common::run_bounded(&args, None);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {o:?}");
        assert_eq!(common::one_line_error(&o), too_large("/dev/zero"));
    }
    assert!(!d.join("map.yaml").exists());
    // A FIFO whose writer never stops (good lines, forever) is read with the same cap.
    let fifo = d.join("fifo");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let writer = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            use std::io::Write;
            let mut f = std::fs::File::create(&fifo).unwrap();
            let line = "ODOM 1.0 2.0 0.5 0 0 0 1.0 host 1.0\n".repeat(20_000);
            // Until the reader is gone (EPIPE).
            while f.write_all(line.as_bytes()).is_ok() {}
        })
    };
    let path = fifo.display().to_string();
    let o = common::run_bounded(&["log", "info", &path], None);
    assert_eq!(o.status.code(), Some(1), "{o:?}");
    assert_eq!(common::one_line_error(&o), too_large(&path));
    writer.join().unwrap();
}

#[test]
fn a_regular_log_over_256_mib_is_refused() {
    let d = scratch("big");
    let path = d.join("big.log");
    std::fs::File::create(&path)
        .unwrap()
        .set_len(beamfield_tools::input::limits::MAX_LOG_BYTES + 1)
        .unwrap();
    let p = path.display().to_string();
    let o = common::run_bounded(&["log", "info", &p], None);
    assert_eq!(o.status.code(), Some(1), "{o:?}");
    assert_eq!(common::one_line_error(&o), too_large(&p));
}

#[test]
fn bad_lines_are_all_counted_the_first_1000_kept_and_quoted_short() {
    use beamfield_tools::input::carmen::MAX_BAD_LINES_KEPT;
    let d = scratch("badlines");
    let path = d.join("bad.log");
    let mut text = String::new();
    for i in 0..1500 {
        text.push_str(&format!("FLASER {i}x\n"));
    }
    // A bad token of 10,000 characters with an escape sequence is quoted as a short prefix.
    text.push_str(&format!("FLASER \x1b[2J{}\n", "9".repeat(10_000)));
    std::fs::write(&path, &text).unwrap();
    let log = CarmenLog::read(text.as_bytes(), skip_bad()).unwrap();
    assert_eq!(log.bad_line_count, 1501);
    assert_eq!(log.bad_lines.len(), MAX_BAD_LINES_KEPT);
    let strict = CarmenLog::read(
        &text.as_bytes()[text.rfind("FLASER \x1b").unwrap()..],
        ReadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        strict.starts_with("line 1: beam count \"\\u{1b}[2J999")
            && strict.chars().count() < 150
            && !strict.contains('\x1b'),
        "{strict}"
    );
    let o = common::run_bounded(&["--json", "log", "info", path.to_str().unwrap()], None);
    assert!(o.status.success(), "{o:?}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["bad_lines_total"], 1501);
    assert_eq!(
        v["bad_lines"].as_array().map(Vec::len),
        Some(MAX_BAD_LINES_KEPT)
    );
    let o = common::run_bounded(&["log", "info", path.to_str().unwrap()], None);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("bad lines: 1501\n"), "{out}");
    assert!(
        out.contains("… and 1481 more (use --json for the first 1000)"),
        "{out}"
    );
}

#[test]
fn a_log_holds_a_bounded_number_of_scans_params_and_message_types() {
    use beamfield_tools::input::carmen::{
        LogError, MAX_LOG_MESSAGE_TYPES, MAX_LOG_PARAMS, MAX_LOG_SCANS,
    };
    let too_many = |text: &str| match CarmenLog::read(text.as_bytes(), skip_bad()) {
        Err(LogError::TooMany(what, limit)) => (what, limit),
        other => panic!("expected TooMany, got {other:?}"),
    };
    let params = |n: usize| {
        (0..n)
            .map(|i| format!("PARAM p{i} 1\n"))
            .collect::<String>()
    };
    assert_eq!(
        CarmenLog::read(params(MAX_LOG_PARAMS).as_bytes(), skip_bad())
            .unwrap()
            .params
            .len(),
        MAX_LOG_PARAMS
    );
    assert_eq!(
        too_many(&params(MAX_LOG_PARAMS + 1)),
        ("PARAM lines", MAX_LOG_PARAMS)
    );
    let types = |n: usize| {
        (0..n)
            .map(|i| format!("T{i} 1\nT0 2\n"))
            .collect::<String>()
    };
    assert_eq!(
        CarmenLog::read(types(MAX_LOG_MESSAGE_TYPES).as_bytes(), skip_bad())
            .unwrap()
            .skipped
            .len(),
        MAX_LOG_MESSAGE_TYPES
    );
    assert_eq!(
        too_many(&types(MAX_LOG_MESSAGE_TYPES + 1)),
        ("distinct message types", MAX_LOG_MESSAGE_TYPES)
    );
    let scans = "FLASER 1 1.0 0 0 0 0 0 0 0 h 0\n".repeat(MAX_LOG_SCANS + 1);
    assert_eq!(too_many(&scans), ("FLASER scans", MAX_LOG_SCANS));
    let e = CarmenLog::read(scans.as_bytes(), skip_bad()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "the log has more than 1048576 FLASER scans, the limit for a log"
    );
    let cut = scans.len() - scans.lines().next().unwrap().len() - 1;
    assert_eq!(
        CarmenLog::read(&scans.as_bytes()[..cut], skip_bad())
            .unwrap()
            .scans
            .len(),
        MAX_LOG_SCANS
    );
}
