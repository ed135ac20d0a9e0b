//! STM32L475 on the B-L475E-IOT01A kit (QEMU `b-l475e-iot01a`: `-serial` 1, 2, 3 are USART1,
//! USART2, USART3). USART1 RX on PB7 (APB2; on the kit also the ST-LINK's virtual COM port),
//! USART2 RX on PA3 (APB1), USART3 TX on PD8 (APB1), all alternate function 7, the USARTs
//! clocked from their APB (RCC_CCIPR's reset value). 80 MHz from the PLL on the HSI16.

use super::{Bauds, Started};
use crate::serial::Backpressure;
use crate::stm32l4::{self, modify, pin_af, Usart};
use beamfield_fixtures::clocks;
use cortex_m::interrupt::InterruptNumber;
use heapless::spsc::{Consumer, Producer};

/// The board, for the ready line.
pub const NAME: &str = "STM32L475 (B-L475E-IOT01A)";

/// The receive interrupts the application takes (RM0351 Table 58).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Irq {
    /// USART1 global interrupt.
    Usart1 = 37,
    /// USART2 global interrupt.
    Usart2 = 38,
}

// SAFETY: the numbers are the chip's NVIC positions of these interrupts.
#[allow(unsafe_code)]
unsafe impl InterruptNumber for Irq {
    fn number(self) -> u16 {
        self as u16
    }
}

/// The LiDAR's receive interrupt.
pub const LIDAR_IRQ: Irq = Irq::Usart1;
/// The link's receive interrupt.
pub const LINK_IRQ: Irq = Irq::Usart2;

fn usart(irq: Irq) -> Usart {
    match irq {
        Irq::Usart1 => Usart::USART1,
        Irq::Usart2 => Usart::USART2,
    }
}

/// Clocks (80 MHz from the PLL), the GPIO and USART clocks, pins and the three lines.
///
/// # Errors
/// What could not be set up, as a line to print.
pub fn init(baud: Bauds) -> Result<Started, &'static str> {
    let report =
        stm32l4::set_up_clocks(80_000_000).map_err(|_| "the clock tree could not be set up")?;
    let note = match (report.pll_locked, report.hsi_ready, report.flash_modelled) {
        (true, true, true) => "PLL from the HSI16",
        (true, true, false) => "PLL from the HSI16; flash interface not modelled (QEMU)",
        (true, false, _) => "PLL from the MSI (the HSI16 did not start)",
        (false, ..) => "the PLL did not lock or the wait states did not take: not switched",
    };
    let c = report.clocks;
    // GPIOA, GPIOB, GPIOD; USART1 on APB2, USART2 and USART3 on APB1.
    modify(stm32l4::RCC_AHB2ENR, 0, 0b1011);
    modify(stm32l4::RCC_APB2ENR, 0, 1 << 14);
    modify(stm32l4::RCC_APB1ENR1, 0, (1 << 17) | (1 << 18));
    pin_af(1, 7, 7, true);
    pin_af(0, 3, 7, true);
    pin_af(3, 8, 7, false);
    let lines = [Usart::USART1, Usart::USART2, Usart::USART3];
    let pclk = [c.pclk2_hz, c.pclk1_hz, c.pclk1_hz];
    let mut brr = [0u16; 3];
    for (i, line) in lines.into_iter().enumerate() {
        let b = clocks::usart_brr(pclk[i], baud[i])
            .ok_or("a baud rate cannot be set from its clock")?;
        line.setup(b, i < 2, i == 2);
        brr[i] = b;
    }
    Ok(Started {
        clocks: c,
        note,
        wait_states: report.wait_states,
        brr,
    })
}

/// The receive interrupt of `irq`'s line.
#[inline(always)]
pub fn on_rx(irq: Irq, ring: &mut Producer<'_, u8>, state: &Backpressure) {
    usart(irq).on_rx_interrupt(irq, ring, state);
}

/// Unmasks a paused receiver once its ring has room.
pub fn resume(irq: Irq, ring_has_room: bool, state: &Backpressure) {
    usart(irq).resume(irq, ring_has_room, state);
}

/// Sends what the transmitter takes from `ring` on USART3.
pub fn pump(ring: &mut Consumer<'_, u8>) -> u32 {
    Usart::USART3.pump(ring)
}
