//! The boards the robot application (`src/bin/robot.rs`) is built for, one module each: the
//! chip's clock setup, the three serial lines' pins, clocks and dividers, and the interrupt
//! lines. Everything else — the rings, the application loop, the seed store, the report — is
//! shared in `src/bin/robot.rs`, and the chips' drivers are shared in [`crate::serial`] and
//! [`crate::clock_f4`] (STM32F405) and [`crate::stm32l4`] (STM32L475).
//!
//! Every board module has the same items: `NAME`, `Irq` and `LIDAR_IRQ` / `LINK_IRQ`, `init`
//! (clocks, pins and lines), `on_rx`, `resume` and `pump`. `robot.rs` takes the STM32F405's
//! (`netduinoplus2`) by default and the STM32L475's with the feature `board-b-l475e-iot01a`.

pub mod b_l475e_iot01a;
pub mod netduinoplus2;

use beamfield_fixtures::clocks::Clocks;

/// What a board's `init` set up: the clocks the dividers were computed from, and how they were
/// obtained.
#[derive(Clone, Copy, Debug)]
pub struct Started {
    /// The clocks the USART dividers and the SysTick reload are computed from.
    pub clocks: Clocks,
    /// Where they come from (the oscillator, or why the registers could not say).
    pub note: &'static str,
    /// Flash wait states read back.
    pub wait_states: u32,
    /// USART_BRR of the three lines (LiDAR in, link in, link out), as written.
    pub brr: [u16; 3],
}

/// Baud rates of the three lines: LiDAR in, link in, link out.
pub type Bauds = [u32; 3];
