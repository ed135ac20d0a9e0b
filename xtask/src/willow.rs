//! `cargo xtask willow`: a map that does not fit the STM32F405 raw, linked tiled. Builds
//! `firmware/src/bin/willow.rs` with the STM32F405 layout (`memory-stm32f405.x`: an image
//! that does not fit 1 MiB of flash is a link error) with the firmware features `tiled,fixed`,
//! runs it on QEMU's `netduinoplus2` (the demo's runner), and compares every score it prints with the host's run of the same plan
//! (`firmware/src/willow_plan.rs`) on the same blob, bit for bit.

#[path = "../../firmware/src/willow_plan.rs"]
#[allow(dead_code)]
mod willow_plan;

use super::demo::{build_and_run_with, Board};
use super::{repo_root, Result};

/// STM32F405 flash, bytes.
const FLASH_BYTES: u64 = 1 << 20;

/// Builds and runs the program, then checks its scores against the host's.
pub fn willow() -> Result {
    let board = Board::Netduinoplus2;
    let blob_path = repo_root().join("firmware/assets/willow-tiled.bin");
    let blob = std::fs::read(&blob_path).map_err(|e| format!("{}: {e}", blob_path.display()))?;
    let view = beamfield::FieldView::parse(&blob).map_err(|e| format!("willow blob: {e}"))?;
    let raw_len = 48 + u64::from(view.width()) * u64::from(view.height());
    println!(
        "Willow Garage field: raw would be {raw_len} bytes ({} the STM32F405's {FLASH_BYTES} bytes of flash); tiled {} bytes",
        if raw_len > FLASH_BYTES { "more than" } else { "within" },
        blob.len()
    );
    let (code, out, err) = build_and_run_with(board, "willow", &["tiled", "fixed"])?;
    print!("{out}");
    eprint!("{err}");
    if code != 0 {
        return Err(format!("the willow program exited {code} under QEMU"));
    }
    let mut host = [willow_plan::Scores::default(); willow_plan::POSES];
    willow_plan::run(&blob, &mut host).map_err(|e| format!("host run: {e:?}"))?;
    let mut device = Vec::new();
    for line in out.lines() {
        if let Some(rest) = line.strip_prefix("score ") {
            let (i, hex) = rest
                .split_once(": ")
                .ok_or_else(|| format!("bad line {line:?}"))?;
            let i: usize = i.parse().map_err(|e| format!("{line:?}: {e}"))?;
            let words: Vec<&str> = hex.split_whitespace().collect();
            let [p, q, x] = words[..] else {
                return Err(format!("bad line {line:?}"));
            };
            let bad = |e: std::num::ParseIntError| format!("{line:?}: {e}");
            let bits = willow_plan::Scores {
                prepared: u32::from_str_radix(p, 16).map_err(bad)?,
                per_pose: u32::from_str_radix(q, 16).map_err(bad)?,
                fixed: u64::from_str_radix(x, 16).map_err(bad)? as i64,
            };
            device.push((i, bits));
        }
    }
    if device.len() != willow_plan::POSES {
        return Err(format!(
            "the device printed {} scores, expected {}",
            device.len(),
            willow_plan::POSES
        ));
    }
    for (i, bits) in device {
        let h = host
            .get(i)
            .ok_or_else(|| format!("score index {i} out of range"))?;
        if *h != bits {
            return Err(format!("pose {i}: device {bits:?}, host {h:?}"));
        }
    }
    println!(
        "host reference: all {} poses' scores (prepared, per-pose and fixed-point paths) equal the device's bit for bit",
        willow_plan::POSES
    );
    Ok(())
}
