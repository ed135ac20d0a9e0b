//! The STM32F405's clock tree (RM0090 §7): HSE (or HSI when the crystal does not start) → main
//! PLL → 168 MHz SYSCLK and 48 MHz for USB; flash wait states, prefetch and caches; AHB /1,
//! APB1 /4 (42 MHz), APB2 /2 (84 MHz). [`set_up`] then reads back what the RCC reports
//! (RCC_CFGR.SWS and prescalers, RCC_PLLCFGR) and decodes the frequencies from it
//! ([`beamfield_fixtures::clocks::f4::decode`]): every divider the firmware programs is computed
//! from those, never from the frequencies it asked for.
//!
//! Every wait on a ready flag is bounded ([`READY_POLLS`]); a step that does not complete leaves
//! the chip on the clock it had, and the report says which step it was.
//!
//! **QEMU.** The `netduinoplus2` machine's RCC (QEMU 10, `stm32_rcc`) only stores what is
//! written and implements the peripheral enable and reset bits: no oscillator or PLL ever
//! reports ready, SWS stays 00 (HSI), and the core runs at the machine's fixed 168 MHz whatever
//! the registers say. Its FLASH interface is not modelled at all (reads as 0). A real chip leaves
//! reset with RCC_CR.HSIRDY set (it runs from the HSI), so RCC_CR reading HSIRDY clear on entry
//! means the RCC is not modelled: [`ClockReport::rcc_modelled`] is then false and the caller
//! must take its clocks from elsewhere (the board's code says from where).

use beamfield_fixtures::clocks::{self, f4, ClockError, Clocks};
use stm32f4::stm32f405::{FLASH, RCC};

/// Polls of a ready flag before giving up. Each poll is a volatile read and a branch, at least
/// 4 cycles of the 16 MHz HSI, so the bound is at least 125 ms (RM0090's HSE start-up time is
/// 2 ms typical; ST's HAL waits 100 ms).
pub const READY_POLLS: u32 = 500_000;

/// What the clock setup did and what the RCC reports afterwards.
#[derive(Clone, Copy, Debug)]
pub struct ClockReport {
    /// The frequencies decoded from the registers read back.
    pub clocks: Clocks,
    /// HSE became ready (else the PLL runs from the HSI).
    pub hse_ready: bool,
    /// The PLL locked and SYSCLK was switched to it.
    pub pll_locked: bool,
    /// Flash wait states read back from FLASH_ACR.LATENCY.
    pub wait_states: u32,
    /// RCC_CR reported the HSI running on entry, as every real chip does.
    pub rcc_modelled: bool,
}

const CR_HSIRDY: u32 = 1 << 1;
const CR_HSEON: u32 = 1 << 16;
const CR_HSERDY: u32 = 1 << 17;
const CR_PLLON: u32 = 1 << 24;
const CR_PLLRDY: u32 = 1 << 25;
const ACR_PRFTEN: u32 = 1 << 8;
const ACR_ICEN: u32 = 1 << 9;
const ACR_DCEN: u32 = 1 << 10;

fn wait(mut ready: impl FnMut() -> bool) -> bool {
    (0..READY_POLLS).any(|_| ready())
}

/// Sets up SYSCLK at `sysclk_hz` from the PLL, with `usb_hz` on its Q output and AHB /1, APB1
/// /4, APB2 /2, from an HSE of `hse_hz` or, if it is not ready within [`READY_POLLS`], the HSI.
///
/// # Errors
/// [`ClockError::NoPllFactors`] when no PLL factors give these frequencies from the input (then
/// only the HSE was switched on); [`ClockError::BadRegister`] / [`ClockError::TooFast`] when the registers
/// read back decode to no valid clock tree.
pub fn set_up(
    rcc: &RCC,
    flash: &FLASH,
    hse_hz: u32,
    sysclk_hz: u32,
    usb_hz: u32,
) -> Result<ClockReport, ClockError> {
    let cr = || rcc.cr().read().bits();
    let rcc_modelled = cr() & CR_HSIRDY != 0;
    // SAFETY (every `bits` write below): the values are whole register images built from
    // RM0090's field layout; reserved bits are kept as read.
    #[allow(unsafe_code)]
    rcc.cr()
        .modify(|r, w| unsafe { w.bits(r.bits() | CR_HSEON) });
    let hse_ready = wait(|| cr() & CR_HSERDY != 0);
    #[allow(unsafe_code)]
    if !hse_ready {
        rcc.cr()
            .modify(|r, w| unsafe { w.bits(r.bits() & !CR_HSEON) });
    }
    let input = if hse_ready { hse_hz } else { f4::HSI_HZ };
    let pll = f4::Pll::for_outputs(input, sysclk_hz, usb_hz)?;
    // The PLL can be configured only while it is off, and it cannot be switched off while it
    // is SYSCLK (as a bootloader may have left it): SYSCLK goes to the HSI first.
    #[allow(unsafe_code)]
    rcc.cfgr().modify(|r, w| unsafe { w.bits(r.bits() & !0x3) });
    wait(|| (rcc.cfgr().read().bits() >> 2) & 0x3 == 0b00);
    #[allow(unsafe_code)]
    rcc.cr()
        .modify(|r, w| unsafe { w.bits(r.bits() & !CR_PLLON) });
    wait(|| cr() & CR_PLLRDY == 0);
    #[allow(unsafe_code)]
    rcc.pllcfgr().modify(|r, w| unsafe {
        // Bits 31:28, 23 and 15:14 are reserved.
        w.bits((r.bits() & 0xF080_C000) | pll.pllcfgr(hse_ready))
    });
    #[allow(unsafe_code)]
    rcc.cr()
        .modify(|r, w| unsafe { w.bits(r.bits() | CR_PLLON) });
    let locked = wait(|| cr() & CR_PLLRDY != 0);

    // Wait states before the clock goes up (RM0090 §3.5.1), checked by reading them back.
    let ws = f4::wait_states(sysclk_hz);
    #[allow(unsafe_code)]
    flash.acr().modify(|r, w| unsafe {
        w.bits((r.bits() & !0x7) | ws | ACR_PRFTEN | ACR_ICEN | ACR_DCEN)
    });
    let ws_ok = wait(|| flash.acr().read().bits() & 0x7 == ws);

    let pll_locked = locked && ws_ok;
    if pll_locked {
        let (Some(hpre), Some(ppre1), Some(ppre2)) = (
            clocks::hpre_bits(1),
            clocks::ppre_bits(4),
            clocks::ppre_bits(2),
        ) else {
            return Err(ClockError::BadRegister);
        };
        // Prescalers first (APB1 must not see 168 MHz), then the switch: SW = 10 (PLL).
        #[allow(unsafe_code)]
        rcc.cfgr().modify(|r, w| unsafe {
            w.bits((r.bits() & !0xFCF0) | (hpre << 4) | (ppre1 << 10) | (ppre2 << 13))
        });
        #[allow(unsafe_code)]
        rcc.cfgr()
            .modify(|r, w| unsafe { w.bits((r.bits() & !0x3) | 0b10) });
        wait(|| (rcc.cfgr().read().bits() >> 2) & 0x3 == 0b10);
    }
    let clocks = f4::decode(
        rcc.cfgr().read().bits(),
        rcc.pllcfgr().read().bits(),
        hse_hz,
    )?;
    Ok(ClockReport {
        clocks,
        hse_ready,
        pll_locked: pll_locked && clocks.source == clocks::SysclkSource::Pll,
        wait_states: flash.acr().read().bits() & 0x7,
        rcc_modelled,
    })
}
