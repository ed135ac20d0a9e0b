//! `cargo xtask nopanic`: the link-time proof that the scoring core has no panic path, and
//! `--show-failure`, which shows that proof failing on a deliberate panic.

use crate::cross::announce_firmware_build;
use crate::error::{Error, Result};
use crate::process::{cargo, repo_root, show, spawn_error};
use crate::toolchain::{ensure_target, FIRMWARE_TARGET};
use std::process::Stdio;

/// The symbol `size_core`'s panic handler calls under the `nopanic` feature.
const NOPANIC_SYMBOL: &str = "beamfield_scoring_path_can_panic";

/// Builds `size_core` with `nopanic` (its panic handler calls an undefined function). Without
/// `show_failure` the link must succeed; with it, `deliberate-panic` is added and the link must
/// fail on exactly that undefined symbol.
pub fn nopanic(show_failure: bool) -> Result {
    ensure_target(FIRMWARE_TARGET)?;
    let features = if show_failure {
        "nopanic,deliberate-panic"
    } else {
        "nopanic"
    };
    let mut cmd = cargo();
    cmd.current_dir(repo_root().join("firmware")).args([
        "build",
        "--release",
        "--target",
        FIRMWARE_TARGET,
        "--bin",
        "size_core",
        "--features",
        features,
    ]);
    announce_firmware_build(&cmd);
    eprintln!("+ (cd firmware && {})", show(&cmd));
    let out = cmd
        .stdin(Stdio::null())
        .output()
        .map_err(|e| spawn_error(&cmd, e))?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    let undefined = stderr
        .lines()
        .any(|l| l.contains("undefined symbol") && l.contains(NOPANIC_SYMBOL));
    match (show_failure, out.status.success()) {
        (false, true) => {
            eprint!("{stderr}");
            println!(
                "nopanic: PASS: size_core (the scoring core: blob parsing, tempered likelihood \
                 field, weight normalization, beam model with ray casting) links with a panic \
                 handler that calls the undefined `{NOPANIC_SYMBOL}`: no panic path is left \
                 (release, LTO, 1 codegen unit, overflow checks off)"
            );
            Ok(())
        }
        (false, false) => {
            eprint!("{stderr}");
            Err(if undefined {
                Error::Requirement(format!(
                    "a panic path is left in the scoring core: the link needs `{NOPANIC_SYMBOL}`"
                ))
            } else {
                Error::Host("the no-panic build failed for another reason (see above)".into())
            })
        }
        (true, true) => Err(Error::Requirement(
            "size_core with `deliberate-panic` linked: the no-panic proof cannot fail, so it proves nothing"
                .to_string(),
        )),
        (true, false) => {
            for l in stderr.lines().filter(|l| l.contains("undefined symbol")) {
                eprintln!("{l}");
            }
            if undefined {
                println!(
                    "nopanic --show-failure: PASS: with a deliberate out-of-bounds index the \
                     link fails on the undefined `{NOPANIC_SYMBOL}`, as it must"
                );
                Ok(())
            } else {
                eprint!("{stderr}");
                Err(Error::Requirement(format!(
                    "the deliberate-panic build failed, but not on the undefined `{NOPANIC_SYMBOL}`"
                )))
            }
        }
    }
}
