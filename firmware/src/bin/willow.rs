//! A map that does not fit the STM32F405 raw: the Willow Garage distance field (1165 × 945
//! cells of 5 cm; 1,100,973 bytes raw, more than the chip's 1 MiB of flash) linked tiled
//! (distance encoding 2, 523,920 bytes), parsed at boot, a scan cast through it and scored at
//! 125 poses ([`willow_plan`]) through the prepared, the per-pose and the fixed-point paths.
//! Prints every score's bits; `cargo xtask willow` links it with
//! the STM32F405 layout (`memory-stm32f405.x`), runs it on QEMU's `netduinoplus2` and compares
//! every score with the host's, bit for bit.
//!
//! Exit status 1 when the blob or the setup is rejected.
#![no_std]
#![no_main]

use beamfield_firmware::{exit, println};
use cortex_m_rt::entry;
use panic_semihosting as _;

use beamfield_fixtures::willow_plan::{run, Scores, POSES};

/// The Willow Garage field, tiled (`beamfield field build … --encoding tiled`).
static BLOB: &[u8] = include_bytes!("../../assets/willow-tiled.bin");

#[entry]
fn main() -> ! {
    let mut scores = [Scores::default(); POSES];
    match run(BLOB, &mut scores) {
        Ok((encoding, kept)) => {
            println!(
                "willow: blob {} bytes, encoding {}, {} beams kept, {} poses",
                BLOB.len(),
                encoding,
                kept,
                POSES
            );
            let mut best = 0usize;
            for (i, s) in scores.iter().enumerate() {
                println!(
                    "score {}: {:08x} {:08x} {:016x}",
                    i, s.prepared, s.per_pose, s.fixed
                );
                if f32::from_bits(s.prepared) > f32::from_bits(scores[best].prepared) {
                    best = i;
                }
            }
            println!("willow: best pose {}", best);
            exit(true)
        }
        Err(e) => {
            println!("willow: {:?}", e);
            exit(false)
        }
    }
}
