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

/// Says on stderr that a firmware build (a `cargo build` in `firmware/`) starts, and, when the
/// firmware has no build directory yet for its target and profile, that this first build
/// compiles the firmware's dependencies too and takes minutes. Printed before the nested cargo
/// runs, so a cold run is never silent (the nested cargo's own progress follows on stderr).
pub fn announce_firmware_build(cmd: &Command) {
    let args: Vec<String> = cmd
        .get_args()
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    let profile = if args.iter().any(|a| a == "--release") {
        "release"
    } else {
        "debug"
    };
    let target = args
        .iter()
        .skip_while(|a| *a != "--target")
        .nth(1)
        .map_or(FIRMWARE_TARGET, String::as_str);
    let firmware = repo_root().join("firmware");
    let target_dir = std::env::var_os("CARGO_TARGET_DIR")
        .map_or_else(|| firmware.join("target"), |d| firmware.join(d));
    let cold = !target_dir.join(target).join(profile).join("deps").is_dir();
    eprintln!(
        "xtask: building the firmware ({target}, {profile}){}",
        if cold {
            "; first build in this tree: its dependencies are compiled first, several minutes …"
        } else {
            " …"
        }
    );
}

/// Runs a firmware build and returns the executables it produced, by program name.
fn executables(cmd: &mut Command) -> Result<BTreeMap<String, PathBuf>> {
    announce_firmware_build(cmd);
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

/// A package's record in `cargo metadata` (its features, its `[package.metadata]`, …).
fn package_of(manifest: &Path, package: &str) -> Result<serde_json::Value> {
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
    meta["packages"]
        .as_array()
        .and_then(|ps| ps.iter().find(|p| p["name"] == package))
        .cloned()
        .ok_or_else(|| Error::Output(format!("package {package} not in {}", manifest.display())))
}

/// The features a package declares (without `default`).
fn features_of(manifest: &Path, package: &str) -> Result<Vec<String>> {
    let pkg = package_of(manifest, package)?;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Library features that add no public item (they swap an implementation behind the same
    /// API): docs.rs has nothing to show for them.
    const NO_ITEMS: [&str; 1] = ["micromath"];

    fn strings(v: &serde_json::Value) -> Vec<String> {
        v.as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|s| s.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default()
    }

    #[test]
    fn docs_rs_documents_every_feature_with_items() {
        let manifest = repo_root().join("Cargo.toml");
        let pkg = package_of(&manifest, "beamfield").unwrap();
        let defaults = strings(&pkg["features"]["default"]);
        let docs_rs = strings(&pkg["metadata"]["docs"]["rs"]["features"]);
        assert!(
            !docs_rs.is_empty(),
            "no [package.metadata.docs.rs] features in {}",
            manifest.display()
        );
        for f in features_of(&manifest, "beamfield").unwrap() {
            let shown = defaults.contains(&f) || docs_rs.contains(&f);
            assert!(
                shown || NO_ITEMS.contains(&f.as_str()),
                "feature `{f}` is neither a default nor in [package.metadata.docs.rs] features: \
                 docs.rs would leave its items out"
            );
        }
        for f in &docs_rs {
            assert!(
                pkg["features"].get(f).is_some(),
                "docs.rs asks for `{f}`, which the crate does not declare"
            );
        }
    }
}
