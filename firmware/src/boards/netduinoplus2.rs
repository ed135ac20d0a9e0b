//! STM32F405 with an 8 MHz crystal (QEMU `netduinoplus2`: the Nth `-serial` is USART N).
//! USART1 (PA10, APB2) LiDAR in, USART2 (PA3, APB1) link in, USART3 (PB10, APB1) link out.
//!
//! QEMU's `netduinoplus2` does not model the clock tree (see [`crate::clock_f4`]): when the RCC
//! does not report the HSI running at start, the dividers are computed from [`EMULATED`], the
//! clocks QEMU gives this machine (a fixed 168 MHz core; its USARTs ignore BRR).

use super::{Bauds, Started};
use crate::clock_f4;
use crate::serial::{self, Backpressure};
use beamfield_fixtures::clocks::{self, Clocks, SysclkSource};
use heapless::spsc::{Consumer, Producer};
use stm32f4::stm32f405::{usart1::RegisterBlock, Interrupt, Peripherals, USART1, USART2, USART3};

/// The board, for the ready line.
pub const NAME: &str = "STM32F405 (netduinoplus2)";
/// The chip's interrupt numbers.
pub type Irq = Interrupt;
/// The LiDAR's receive interrupt (IRQ 37).
pub const LIDAR_IRQ: Irq = Interrupt::USART1;
/// The link's receive interrupt (IRQ 38).
pub const LINK_IRQ: Irq = Interrupt::USART2;
/// The crystal, Hz.
const HSE_HZ: u32 = 8_000_000;
/// The clocks QEMU's `netduinoplus2` runs at whatever its RCC registers hold.
pub const EMULATED: Clocks = Clocks {
    source: SysclkSource::Pll,
    sysclk_hz: 168_000_000,
    hclk_hz: 168_000_000,
    pclk1_hz: 42_000_000,
    pclk2_hz: 84_000_000,
    pll48_hz: 48_000_000,
};

fn regs(which: Irq) -> &'static RegisterBlock {
    // SAFETY: the register blocks are memory-mapped hardware at fixed addresses for the whole
    // run. The main loop and the handlers touch disjoint bits, except CR1.RXNEIE, which the
    // handler clears only while it is set and the main loop sets only after the handler
    // cleared it (`serial::resume`), so no read-modify-write of CR1 races another.
    #[allow(unsafe_code)]
    unsafe {
        match which {
            Interrupt::USART2 => &*USART2::ptr(),
            Interrupt::USART3 => &*USART3::ptr(),
            _ => &*USART1::ptr(),
        }
    }
}

/// Clocks (168 MHz from the PLL), pins and the three lines.
///
/// # Errors
/// What could not be set up, as a line to print.
pub fn init(baud: Bauds) -> Result<Started, &'static str> {
    let dp = Peripherals::take().ok_or("peripherals taken twice")?;
    let report = clock_f4::set_up(&dp.RCC, &dp.FLASH, HSE_HZ, 168_000_000, 48_000_000)
        .map_err(|_| "the clock tree could not be set up")?;
    let (clocks, note) = match (report.rcc_modelled, report.pll_locked, report.hse_ready) {
        (false, ..) => (
            EMULATED,
            "RCC not modelled (QEMU): the machine's fixed clocks",
        ),
        (true, true, true) => (report.clocks, "PLL from the 8 MHz HSE"),
        (true, true, false) => (report.clocks, "PLL from the HSI (the HSE did not start)"),
        (true, false, _) => (report.clocks, "the PLL did not lock: still on the HSI"),
    };
    serial::enable_clocks_and_pins(&dp.RCC, &dp.GPIOA, &dp.GPIOB);
    let pclk = [clocks.pclk2_hz, clocks.pclk1_hz, clocks.pclk1_hz];
    let mut brr = [0u16; 3];
    for (i, which) in [Interrupt::USART1, Interrupt::USART2, Interrupt::USART3]
        .into_iter()
        .enumerate()
    {
        let b = clocks::usart_brr(pclk[i], baud[i])
            .ok_or("a baud rate cannot be set from its clock")?;
        serial::setup(regs(which), b, i < 2, i == 2);
        brr[i] = b;
    }
    Ok(Started {
        clocks,
        note,
        wait_states: report.wait_states,
        brr,
    })
}

/// The receive interrupt of `irq`'s line.
#[inline(always)]
pub fn on_rx(irq: Irq, ring: &mut Producer<'_, u8>, state: &Backpressure) {
    serial::on_rx_interrupt(regs(irq), irq, ring, state);
}

/// Unmasks a paused receiver once its ring has room.
pub fn resume(irq: Irq, ring_has_room: bool, state: &Backpressure) {
    serial::resume(regs(irq), irq, ring_has_room, state);
}

/// Sends what the transmitter takes from `ring` on USART3.
pub fn pump(ring: &mut Consumer<'_, u8>) -> u32 {
    serial::pump(regs(Interrupt::USART3), ring)
}
