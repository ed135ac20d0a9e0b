//! `cargo xtask demo` and `cargo xtask demo-assets`: the pose-scoring demo under QEMU on one of
//! two boards, and the regeneration of its checked-in assets.

use crate::cross::build_program;
use crate::error::{Error, Result};
use crate::process::{cargo, repo_root, run, Finished};
use crate::qemu::{ensure_qemu, failure, run_elf, Board};

/// Builds firmware program `bin` (release) for `board` with firmware cargo `features` and runs
/// it under QEMU.
pub fn build_and_run(board: Board, bin: &str, features: &[&str]) -> Result<Finished> {
    ensure_qemu()?;
    let elf = build_program(board, bin, features)?;
    run_elf(&elf, board.machine(), &[], bin)
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
    let Finished {
        code,
        stdout: out,
        stderr: err,
    } = build_and_run(board, "demo", features)?;
    print!("{out}");
    eprint!("{err}");
    match code {
        0 => {
            let read = |name: &str| {
                let path = repo_root().join("firmware/assets").join(name);
                std::fs::read(&path).map_err(|e| Error::io(&path, e))
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
        c => Err(failure(
            c,
            "the demo",
            machine,
            "a scan could not be scored",
        )),
    }
}

/// Regenerates the demo's assets from the Intel lab log in `data/`: the blobs in
/// `firmware/assets/`, the scans in `fixtures/assets/`.
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
        "fixtures/assets",
    ]))
}
