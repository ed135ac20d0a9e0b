//! The tools the tasks need besides cargo: rustup targets, the LLVM tools of the Rust sysroot
//! (found once), gcc for the counting plugin.

use crate::error::{Error, Result};
use crate::process::{answers, capture, run};
use std::io::ErrorKind;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// The firmware's target: Cortex-M4F (QEMU `mps2-an386`, `netduinoplus2`).
pub const FIRMWARE_TARGET: &str = "thumbv7em-none-eabihf";

/// Installs the rustup target `target` if it is missing.
pub fn ensure_target(target: &str) -> Result {
    let installed = capture(Command::new("rustup").args(["target", "list", "--installed"]))
        .map_err(|e| {
            Error::Missing(format!(
                "{e}\n  (without rustup, install the Rust standard library for {target})"
            ))
        })?;
    if installed.lines().any(|l| l.trim() == target) {
        return Ok(());
    }
    run(Command::new("rustup").args(["target", "add", target]))
}

/// The directory of the Rust sysroot's LLVM tools (`rustup component add llvm-tools`), asked
/// of rustc once.
fn sysroot_bin() -> Result<&'static Path> {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    if let Some(d) = DIR.get() {
        return Ok(d);
    }
    let sysroot = capture(Command::new("rustc").args(["--print", "sysroot"]))?;
    let host = capture(Command::new("rustc").args(["--print", "host-tuple"]))
        .unwrap_or_else(|_| "x86_64-unknown-linux-gnu".to_string());
    let dir = Path::new(sysroot.trim()).join(format!("lib/rustlib/{}/bin", host.trim()));
    Ok(DIR.get_or_init(|| dir))
}

/// An LLVM tool (`llvm-nm`, `llvm-size`, `llvm-objdump`): from PATH if one answers there, else
/// the Rust sysroot's, installing the `llvm-tools` component when it is missing.
pub fn llvm_tool(name: &str) -> Result<PathBuf> {
    if answers(Path::new(name)) {
        return Ok(PathBuf::from(name));
    }
    let p = sysroot_bin()?.join(name);
    if !p.is_file() {
        run(Command::new("rustup").args(["component", "add", "llvm-tools"]))?;
    }
    if answers(&p) {
        Ok(p)
    } else {
        Err(Error::Missing(format!(
            "{name} not found (rustup component add llvm-tools)"
        )))
    }
}

/// gcc, to build the counting plugin; `hint` ends the message when it is missing (e.g.
/// ", or run with --no-count").
pub fn gcc(hint: &str, what: &str) -> Result<Command> {
    match Command::new("gcc").arg("--version").output() {
        Ok(_) => Ok(Command::new("gcc")),
        Err(e) if e.kind() == ErrorKind::NotFound => Err(Error::Missing(format!(
            "counting instructions needs gcc to build the QEMU plugin {what} \
             (Debian: apt-get install -y gcc){hint}"
        ))),
        Err(source) => Err(Error::Spawn {
            command: "gcc --version".into(),
            source,
        }),
    }
}
