//! `cargo xtask demo` and `cargo xtask demo-assets`: the pose-scoring demo under QEMU on one of
//! two boards, and the regeneration of its checked-in assets.

use super::{capture, ensure_qemu, ensure_target, repo_root, run, run_to_files, show, Result};
use super::{cargo, FIRMWARE_TARGET, QEMU_TIMEOUT_S};
use std::path::PathBuf;
use std::process::Command;

/// A board the demo runs on: QEMU machine, memory layout, SysTick clock.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum Board {
    /// ARM MPS2+ AN386: Cortex-M4F, 4 MiB code, 4 MiB SRAM, 25 MHz (the repository's memory.x).
    #[value(name = "mps2-an386")]
    Mps2An386,
    /// STM32F405 (Netduino Plus 2): 1 MiB flash, 128 KiB of its SRAM used (memory-stm32f405.x).
    #[value(name = "netduinoplus2")]
    Netduinoplus2,
}

impl Board {
    pub fn machine(self) -> &'static str {
        match self {
            Board::Mps2An386 => "mps2-an386",
            Board::Netduinoplus2 => "netduinoplus2",
        }
    }
    pub(crate) fn memory_x(self) -> PathBuf {
        repo_root().join(match self {
            Board::Mps2An386 => "memory.x",
            Board::Netduinoplus2 => "memory-stm32f405.x",
        })
    }
    /// SysTick's clock in QEMU's model of the board, Hz.
    fn core_hz(self) -> u64 {
        match self {
            Board::Mps2An386 => 25_000_000,
            Board::Netduinoplus2 => 168_000_000,
        }
    }
}

/// Builds firmware program `bin` (release) for `board` and runs it under QEMU; returns its exit
/// code, stdout and stderr. The SysTick clock of the board reaches the build as
/// `BEAMFIELD_CORE_HZ`.
pub fn build_and_run(board: Board, bin: &str) -> Result<(i32, String, String)> {
    build_and_run_with(board, bin, &[])
}

/// [`build_and_run`] with firmware cargo `features` turned on.
pub fn build_and_run_with(
    board: Board,
    bin: &str,
    features: &[&str],
) -> Result<(i32, String, String)> {
    ensure_qemu()?;
    let elf = build_with(board, bin, features)?;
    run_to_files(
        Command::new("timeout")
            .args([
                QEMU_TIMEOUT_S,
                "qemu-system-arm",
                "-machine",
                board.machine(),
            ])
            .args([
                "-nographic",
                "-semihosting-config",
                "enable=on,target=native",
            ])
            .args(["-icount", "shift=0", "-kernel"])
            .arg(&elf),
        bin,
    )
}

/// Builds firmware program `bin` (release) for `board`; returns the ELF's path.
pub fn build(board: Board, bin: &str) -> Result<PathBuf> {
    build_with(board, bin, &[])
}

/// [`build`] with firmware cargo `features` turned on.
pub fn build_with(board: Board, bin: &str, features: &[&str]) -> Result<PathBuf> {
    ensure_target(FIRMWARE_TARGET)?;
    let mut cmd = cargo();
    cmd.current_dir(repo_root().join("firmware"))
        .env("BEAMFIELD_MEMORY_X", board.memory_x())
        .env("BEAMFIELD_CORE_HZ", board.core_hz().to_string())
        .args([
            "build",
            "--release",
            "--target",
            FIRMWARE_TARGET,
            "--bin",
            bin,
            "--message-format=json-render-diagnostics",
        ]);
    if !features.is_empty() {
        cmd.args(["--features", &features.join(",")]);
    }
    eprintln!("+ (cd firmware && {})", show(&cmd));
    let out = capture(&mut cmd)?;
    let elf = out
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|m| m["reason"] == "compiler-artifact" && m["target"]["name"] == bin)
        .find_map(|m| m["executable"].as_str().map(PathBuf::from))
        .ok_or_else(|| format!("cargo built no `{bin}` executable"))?;
    Ok(elf)
}

/// How the demo links the Intel field.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum DemoEncoding {
    /// `firmware/assets/intel.bin`: one byte per cell (distance encoding 1).
    Raw,
    /// `firmware/assets/intel-tiled.bin`: the same codes in deduplicated 4 × 4 tiles (encoding
    /// 2; the firmware built with its feature `tiled`).
    Tiled,
}

/// Builds `firmware/src/bin/demo.rs` (release) for `board` and runs it under QEMU, printing its
/// report; fails unless it exits 0 and the host, scoring the raw field, recomputes its numbers
/// to the printed digits. With the tiled field on the device this shows the encoding changes
/// no best pose, weight or ESS of the demo (that every score is bit-identical is checked on the
/// host, host-tests/tests/field_tiled.rs).
pub fn demo(board: Board, encoding: DemoEncoding) -> Result {
    let machine = board.machine();
    let features: &[&str] = match encoding {
        DemoEncoding::Raw => &[],
        DemoEncoding::Tiled => &["tiled"],
    };
    let (code, out, err) = build_and_run_with(board, "demo", features)?;
    print!("{out}");
    eprint!("{err}");
    match code {
        0 => {
            let read = |name: &str| {
                let path = repo_root().join("firmware/assets").join(name);
                std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))
            };
            let raw = read("intel.bin")?;
            if encoding == DemoEncoding::Tiled {
                let tiled = read("intel-tiled.bin")?;
                println!(
                    "the device read the tiled field ({} bytes); the host below reads the raw one ({} bytes)",
                    tiled.len(),
                    raw.len()
                );
            }
            println!("{}", crate::demo_ref::check(&out, &raw)?);
            let f64_checks = crate::demo_f64::check(&out, &raw)?;
            for c in &f64_checks {
                println!(
                    "f64 reference: scan {}: weight {:.4} in [{:.4}, {:.4}], ESS {:.2} in [{:.2}, {:.2}] (widest pose bracket ±{:.4} nats)",
                    c.log_index, c.weight.0, c.weight.1, c.weight.2, c.ess.0, c.ess.1, c.ess.2, c.worst_e
                );
            }
            println!(
                "f64 reference: the device's best pose, weight and ESS of all {} scans lie within the bounds of an independent f64 scoring of every hypothesis",
                f64_checks.len()
            );
            Ok(())
        }
        c => Err(qemu_failure(
            c,
            "the demo",
            machine,
            "a scan could not be scored",
        )),
    }
}

/// The error for a firmware program (`what`, e.g. "the demo") that exited `code` (not 0) under
/// QEMU on `machine`: 124 is `timeout` killing it after [`QEMU_TIMEOUT_S`] seconds, 134 a CPU
/// lockup (QEMU aborts), any other code the program's own failure, explained by `cause`.
pub fn qemu_failure(code: i32, what: &str, machine: &str, cause: &str) -> String {
    match code {
        124 => format!("{what} did not finish within {QEMU_TIMEOUT_S} s"),
        134 => format!("QEMU stopped with a CPU lockup on `{machine}`"),
        c => format!("{what} exited {c} under QEMU ({machine}): {cause}"),
    }
}

/// Regenerates `firmware/assets/` from the Intel lab log beside the repository.
pub fn demo_assets() -> Result {
    let root = repo_root();
    run(cargo().current_dir(&root).args([
        "run",
        "--release",
        "-p",
        "beamfield-tools",
        "--example",
        "demo_assets",
        "--",
        "data/laser_intel_lab/intel-corrected.log",
        "firmware/assets",
    ]))
}
