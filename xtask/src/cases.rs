//! `cargo xtask refcases` and `cargo xtask modelcases`: the case tables the host generates for
//! the firmware's check programs (`firmware/src/reference_cases.rs`, `model_cases.rs`).

use crate::error::{Error, Result};
use crate::process::repo_root;
use std::fs;

/// Regenerates (or with `check`, only compares) the beam-mixture reference cases.
pub fn refcases(check: bool) -> Result {
    generated_file(
        host_tests::firmware_cases::GENERATED_PATH,
        &host_tests::firmware_cases::render(),
        check,
        "refcases",
    )
}

/// Regenerates (or with `check`, only compares) the models program's cases.
pub fn modelcases(check: bool) -> Result {
    generated_file(
        host_tests::firmware_models::GENERATED_PATH,
        &host_tests::firmware_models::render(),
        check,
        "modelcases",
    )
}

/// Writes (or with `check`, only compares) a file the host generates for the firmware.
fn generated_file(relative: &str, want: &str, check: bool, task: &'static str) -> Result {
    let path = repo_root().join(relative);
    let have = fs::read_to_string(&path).unwrap_or_default();
    if have == want {
        eprintln!("xtask: {} is up to date", path.display());
        return Ok(());
    }
    if check {
        return Err(Error::Stale { path, task });
    }
    fs::write(&path, want).map_err(|e| Error::io(&path, e))?;
    eprintln!("xtask: wrote {}", path.display());
    Ok(())
}
