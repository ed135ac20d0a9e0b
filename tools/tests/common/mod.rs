//! Shared by the command-line tests (`mod common;`): the binary under test, and a run that must
//! succeed and print JSON. Not every test file uses both.
#![allow(dead_code)]

use std::process::Command;

/// The `beamfield` binary cargo built for these tests.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_beamfield"))
}

/// Runs `cmd`, which must exit with status 0 (the assertion shows its stderr otherwise), and
/// parses its standard output as JSON.
pub fn run_json(cmd: &mut Command) -> serde_json::Value {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}
