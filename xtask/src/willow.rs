//! `cargo xtask willow`: a map that does not fit the STM32F405 raw, linked tiled. Builds
//! `firmware/src/bin/willow.rs` with the STM32F405 layout (`memory-stm32f405.x`: an image
//! that does not fit 1 MiB of flash is a link error) with the firmware features `tiled,fixed`,
//! runs it on QEMU's `netduinoplus2` (the demo's runner), and compares every score it prints with the host's run of the same plan
//! (`fixtures/src/willow_plan.rs`) on the same blob, bit for bit.

use crate::demo::build_and_run;
use crate::error::{Error, Result};
use crate::process::{repo_root, Finished};
use crate::qemu::{failure, Board};
use beamfield_fixtures::willow_plan;

/// STM32F405 flash, bytes.
const FLASH_BYTES: u64 = 1 << 20;

/// Builds and runs the program, then checks its scores against the host's.
pub fn willow() -> Result {
    crate::qemu::ensure_qemu()?;
    let board = Board::Netduinoplus2;
    let blob_path = repo_root().join("firmware/assets/willow-tiled.bin");
    let blob = std::fs::read(&blob_path).map_err(|e| Error::io(&blob_path, e))?;
    let view =
        beamfield::FieldView::parse(&blob).map_err(|e| Error::Host(format!("willow blob: {e}")))?;
    let raw_len = 48 + u64::from(view.width()) * u64::from(view.height());
    println!(
        "Willow Garage field: raw would be {raw_len} bytes ({} the STM32F405's {FLASH_BYTES} bytes of flash); tiled {} bytes",
        if raw_len > FLASH_BYTES { "more than" } else { "within" },
        blob.len()
    );
    let Finished {
        code,
        stdout: out,
        stderr: err,
    } = build_and_run(board, "willow", &["tiled", "fixed"])?;
    print!("{out}");
    eprint!("{err}");
    if code != 0 {
        return Err(failure(
            code,
            "the willow program",
            board.machine(),
            "see its output",
        ));
    }
    let mut host = [willow_plan::Scores::default(); willow_plan::POSES];
    willow_plan::run(&blob, &mut host).map_err(|e| Error::Host(format!("host run: {e:?}")))?;
    let device = device_scores(&out)?;
    if device.len() != willow_plan::POSES {
        return Err(Error::Mismatch(format!(
            "the device printed {} scores, expected {}",
            device.len(),
            willow_plan::POSES
        )));
    }
    for (i, bits) in device {
        let h = host
            .get(i)
            .ok_or_else(|| Error::Output(format!("score index {i} out of range")))?;
        if *h != bits {
            return Err(Error::Mismatch(format!(
                "pose {i}: device {bits:?}, host {h:?}"
            )));
        }
    }
    println!(
        "host reference: all {} poses' scores (prepared, per-pose and fixed-point paths) equal the device's bit for bit",
        willow_plan::POSES
    );
    Ok(())
}

/// The device's `score I: P Q X` lines (hex bit patterns of the three paths), by pose.
fn device_scores(out: &str) -> Result<Vec<(usize, willow_plan::Scores)>> {
    let mut device = Vec::new();
    for line in out.lines() {
        let Some(rest) = line.strip_prefix("score ") else {
            continue;
        };
        let bad = || Error::Output(format!("cannot read the score line {line:?}"));
        let (i, hex) = rest.split_once(": ").ok_or_else(bad)?;
        let i: usize = i.parse().map_err(|_| bad())?;
        let words: Vec<&str> = hex.split_whitespace().collect();
        let [p, q, x] = words[..] else {
            return Err(bad());
        };
        let bits = willow_plan::Scores {
            prepared: u32::from_str_radix(p, 16).map_err(|_| bad())?,
            per_pose: u32::from_str_radix(q, 16).map_err(|_| bad())?,
            fixed: u64::from_str_radix(x, 16).map_err(|_| bad())? as i64,
        };
        device.push((i, bits));
    }
    Ok(device)
}
