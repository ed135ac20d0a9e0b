//! Fuzzes the host tool's CARMEN log reader: any bytes, read leniently (bad lines collected) and
//! strictly, must give a log or a typed error, never a panic; a lenient read's statistics and
//! layout must be computable, and no stored message type or PARAM may hold a control byte
//! (they are printed back by `beamfield log info`).
//!
//! Run: `cargo +nightly fuzz run carmen_log` from the repository root.

#![no_main]

use beamfield_tools::input::carmen::{CarmenLog, LogError, ReadOptions};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = CarmenLog::read(data, ReadOptions::default());
    let lenient = ReadOptions {
        skip_bad_lines: true,
        ..ReadOptions::default()
    };
    let log = match CarmenLog::read(data, lenient) {
        Ok(log) => log,
        // A limit of the whole log (PARAM lines, message types: docs/resource-limits.md).
        Err(LogError::TooMany(..)) => return,
        Err(e) => panic!("a lenient read of bytes in memory: {e}"),
    };
    let _ = log.stats();
    for name in log.skipped.keys() {
        assert!(!name.chars().any(char::is_control), "{name:?}");
    }
    for (k, v) in &log.params {
        assert!(!k.chars().any(char::is_control) && !v.chars().any(char::is_control));
    }
    for e in &log.bad_lines {
        let _ = e.to_string();
    }
});
