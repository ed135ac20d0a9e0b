//! Firmware builds: every program of `firmware/` at once, or one program for a board's memory
//! layout; and `cargo xtask cross`, the library for every bare-metal target with each feature.

use crate::error::{Error, Result};
use crate::process::{capture, cargo, repo_root, run, show};
use crate::qemu::Board;
use crate::toolchain::{ensure_target, FIRMWARE_TARGET};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Targets the library must build for.
const CROSS_TARGETS: [&str; 4] = [
    "thumbv7em-none-eabihf",
    "thumbv7m-none-eabi",
    "thumbv6m-none-eabi",
    "riscv32imc-unknown-none-elf",
];

/// `cargo build` in `firmware/` for the firmware's target, with JSON messages (the ELF paths).
fn firmware_build(features: Option<&str>) -> Result<Command> {
    ensure_target(FIRMWARE_TARGET)?;
    let mut cmd = cargo();
    cmd.current_dir(repo_root().join("firmware")).args([
        "build",
        "--target",
        FIRMWARE_TARGET,
        "--message-format=json-render-diagnostics",
    ]);
    if let Some(f) = features.filter(|f| !f.is_empty()) {
        cmd.args(["--features", f]);
    }
    Ok(cmd)
}

/// Runs a firmware build and returns the executables it produced, by program name.
fn executables(cmd: &mut Command) -> Result<BTreeMap<String, PathBuf>> {
    eprintln!("+ (cd firmware && {})", show(cmd));
    let out = capture(cmd)?;
    let mut elves = BTreeMap::new();
    for line in out.lines() {
        let Ok(msg) = serde_json::from_str::<serde_json::Value>(line) else {
            continue;
        };
        if msg["reason"] != "compiler-artifact" {
            continue;
        }
        if let (Some(name), Some(exe)) =
            (msg["target"]["name"].as_str(), msg["executable"].as_str())
        {
            elves.insert(name.to_string(), PathBuf::from(exe));
        }
    }
    Ok(elves)
}

/// Builds the firmware's programs (the default layout) and returns their ELF paths by name.
pub fn build_firmware(release: bool, features: Option<&str>) -> Result<BTreeMap<String, PathBuf>> {
    let mut cmd = firmware_build(features)?;
    cmd.arg("--bins");
    if release {
        cmd.arg("--release");
    }
    executables(&mut cmd)
}

/// Builds firmware program `bin` (release) for `board` with firmware cargo `features`; returns
/// the ELF's path. The SysTick clock of the board reaches the build as `BEAMFIELD_CORE_HZ`.
pub fn build_program(board: Board, bin: &str, features: &[&str]) -> Result<PathBuf> {
    let joined = features.join(",");
    let mut cmd = firmware_build(Some(&joined))?;
    cmd.env("BEAMFIELD_MEMORY_X", board.memory_x())
        .env("BEAMFIELD_CORE_HZ", board.core_hz().to_string())
        .args(["--release", "--bin", bin]);
    executables(&mut cmd)?
        .remove(bin)
        .ok_or_else(|| Error::Output(format!("cargo built no `{bin}` executable")))
}

/// The features a package declares (without `default`).
fn features_of(manifest: &Path, package: &str) -> Result<Vec<String>> {
    let meta = capture(
        cargo()
            .args([
                "metadata",
                "--no-deps",
                "--format-version",
                "1",
                "--manifest-path",
            ])
            .arg(manifest),
    )?;
    let meta: serde_json::Value =
        serde_json::from_str(&meta).map_err(|e| Error::Output(format!("cargo metadata: {e}")))?;
    let pkg = meta["packages"]
        .as_array()
        .and_then(|ps| ps.iter().find(|p| p["name"] == package))
        .ok_or_else(|| Error::Output(format!("package {package} not in {}", manifest.display())))?;
    Ok(pkg["features"]
        .as_object()
        .map(|f| f.keys().filter(|k| *k != "default").cloned().collect())
        .unwrap_or_default())
}

/// `cargo xtask cross`: the library for every bare-metal target, without and with each feature
/// and with all of them; then the firmware linked with each optional feature (the proof that
/// none needs an allocator).
pub fn cross() -> Result {
    let root = repo_root();
    let features = features_of(&root.join("Cargo.toml"), "beamfield")?;
    eprintln!("xtask: library features: {}", features.join(", "));
    for target in CROSS_TARGETS {
        ensure_target(target)?;
        let lib = || {
            let mut c = cargo();
            c.current_dir(&root)
                .args(["build", "-p", "beamfield", "--target", target]);
            c
        };
        run(&mut lib())?;
        for f in &features {
            run(lib().args(["--features", f]))?;
        }
        run(lib().arg("--all-features"))?;
    }
    // The firmware has no #[global_allocator]: a crate graph that used `alloc` would not link.
    let fw = features_of(&root.join("firmware/Cargo.toml"), "beamfield-firmware")?;
    // `deliberate-panic` exists to make the no-panic link fail (`cargo xtask nopanic
    // --show-failure`): it is not a feature a program is linked with.
    let fw: Vec<String> = fw.into_iter().filter(|f| f != "deliberate-panic").collect();
    for f in std::iter::once(None).chain(fw.iter().map(|f| Some(f.as_str()))) {
        build_firmware(true, f)?;
        eprintln!(
            "xtask: firmware linked without an allocator (features: {})",
            f.unwrap_or("none")
        );
    }
    Ok(())
}
