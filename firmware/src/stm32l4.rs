//! The STM32L475's registers that the robot application needs (RM0351), written directly (no
//! register crate: a dozen registers of four peripherals): the clock tree (HSI16, or the MSI
//! when the HSI16 does not start, → main PLL → 80 MHz), flash wait states, GPIO alternate
//! functions, and the USART (the STM32L4's version: ISR, ICR, RDR and TDR in place of the
//! STM32F4's SR and DR) with the same interrupt-driven receive and polled transmit as
//! [`crate::serial`].
//!
//! **QEMU.** QEMU 10's `b-l475e-iot01a` models this chip's RCC (ready flags set as soon as an
//! oscillator or the PLL is switched on, SWS following SW, the core and SysTick clocked at the
//! HCLK the registers select, each USART's kernel clock gated by its enable bit) and its USARTs,
//! GPIOs and EXTI (through which the USARTs' interrupts reach the NVIC). It does not model the
//! FLASH interface (it reads as 0): a real chip's FLASH_ACR leaves reset as 0x0000_0600 (both
//! caches on), so [`ClockReport::flash_modelled`] is false when it reads 0 on entry, and the
//! wait states are then not checked (the emulated flash has none).

use crate::serial::Backpressure;
use beamfield_fixtures::clocks::{l4, ClockError, Clocks, SysclkSource};
use core::ptr::{read_volatile, write_volatile};
use core::sync::atomic::Ordering;
use cortex_m::interrupt::InterruptNumber;
use cortex_m::peripheral::NVIC;
use heapless::spsc::{Consumer, Producer};

const RCC: usize = 0x4002_1000;
const RCC_CR: usize = RCC;
const RCC_CFGR: usize = RCC + 0x08;
const RCC_PLLCFGR: usize = RCC + 0x0C;
/// RCC_AHB2ENR: GPIOx clock enables (bit x).
pub const RCC_AHB2ENR: usize = RCC + 0x4C;
/// RCC_APB1ENR1: USART2EN bit 17, USART3EN bit 18.
pub const RCC_APB1ENR1: usize = RCC + 0x58;
/// RCC_APB2ENR: USART1EN bit 14.
pub const RCC_APB2ENR: usize = RCC + 0x60;
const FLASH_ACR: usize = 0x4002_2000;

/// Polls of a ready flag before giving up: at least 4 cycles each at the 4 MHz MSI, so at least
/// 0.5 s (RM0351 gives the HSI16 3.8 µs and the PLL 40 µs to start).
pub const READY_POLLS: u32 = 500_000;

/// A 32-bit register at `addr`.
#[inline(always)]
pub fn read(addr: usize) -> u32 {
    // SAFETY: only called with the addresses of this module's registers, which exist on the
    // chip for the whole run; a volatile word read has no other effect than the hardware's.
    #[allow(unsafe_code)]
    unsafe {
        read_volatile(addr as *const u32)
    }
}

/// Writes a 32-bit register at `addr`.
#[inline(always)]
pub fn write(addr: usize, value: u32) {
    // SAFETY: as in `read`.
    #[allow(unsafe_code)]
    unsafe {
        write_volatile(addr as *mut u32, value)
    }
}

/// Read-modify-write: `clear` bits off, then `set` bits on.
#[inline(always)]
pub fn modify(addr: usize, clear: u32, set: u32) {
    write(addr, (read(addr) & !clear) | set);
}

fn wait(mut ready: impl FnMut() -> bool) -> bool {
    (0..READY_POLLS).any(|_| ready())
}

/// What the clock setup did and what the RCC reports afterwards.
#[derive(Clone, Copy, Debug)]
pub struct ClockReport {
    /// The frequencies decoded from the registers read back.
    pub clocks: Clocks,
    /// The HSI16 became ready (else the PLL runs from the MSI).
    pub hsi_ready: bool,
    /// The PLL locked and SYSCLK was switched to it.
    pub pll_locked: bool,
    /// Flash wait states read back.
    pub wait_states: u32,
    /// FLASH_ACR read non-zero on entry, as on every real chip.
    pub flash_modelled: bool,
}

/// SYSCLK at `sysclk_hz` from the PLL, fed by the HSI16 or, if it does not start, the MSI;
/// AHB, APB1 and APB2 at /1 (80 MHz is within all three's limit in voltage range 1, the reset
/// range).
///
/// # Errors
/// [`ClockError::NoPllFactors`] (only the HSI16 was switched on); [`ClockError::BadRegister`] /
/// [`ClockError::TooFast`] when the registers read back decode to no valid clock tree.
pub fn set_up_clocks(sysclk_hz: u32) -> Result<ClockReport, ClockError> {
    const HSION: u32 = 1 << 8;
    const HSIRDY: u32 = 1 << 10;
    const PLLON: u32 = 1 << 24;
    const PLLRDY: u32 = 1 << 25;
    let flash_modelled = read(FLASH_ACR) != 0;
    modify(RCC_CR, 0, HSION);
    let hsi_ready = wait(|| read(RCC_CR) & HSIRDY != 0);
    let (input, src) = if hsi_ready {
        (l4::HSI16_HZ, l4::src::HSI16)
    } else {
        let msi = l4::decode(read(RCC_CR), 0, 0, 0)?.sysclk_hz;
        (msi, l4::src::MSI)
    };
    let pll = l4::Pll::for_sysclk(input, sysclk_hz)?;
    // The PLL cannot be switched off while it is SYSCLK (as a bootloader may have left it):
    // SYSCLK goes to the MSI first (SW = 00).
    modify(RCC_CFGR, 0x3, 0);
    wait(|| (read(RCC_CFGR) >> 2) & 0x3 == 0b00);
    modify(RCC_CR, PLLON, 0);
    wait(|| read(RCC_CR) & PLLRDY == 0);
    // Every field of PLLCFGR is written: P and Q off, R on.
    write(RCC_PLLCFGR, pll.pllcfgr(src));
    modify(RCC_CR, 0, PLLON);
    let locked = wait(|| read(RCC_CR) & PLLRDY != 0);
    // Wait states (RM0351 §3.3.3) with prefetch and both caches, checked by reading them back.
    let ws = l4::wait_states(sysclk_hz);
    modify(FLASH_ACR, 0x7, ws | (1 << 8) | (1 << 9) | (1 << 10));
    let ws_ok = !flash_modelled || wait(|| read(FLASH_ACR) & 0x7 == ws);
    if locked && ws_ok {
        // HPRE, PPRE1, PPRE2 at /1; then SW = 11 (PLL), and SWS follows.
        modify(RCC_CFGR, 0x3FF0, 0);
        modify(RCC_CFGR, 0x3, 0b11);
        wait(|| (read(RCC_CFGR) >> 2) & 0x3 == 0b11);
    }
    let clocks = l4::decode(read(RCC_CR), read(RCC_CFGR), read(RCC_PLLCFGR), 0)?;
    Ok(ClockReport {
        clocks,
        hsi_ready,
        pll_locked: locked && ws_ok && clocks.source == SysclkSource::Pll,
        wait_states: read(FLASH_ACR) & 0x7,
        flash_modelled,
    })
}

/// Sets pin `pin` of GPIO port `port` (0 = A) to alternate function `af`, with the pull-up
/// when `pull_up` (an unwired receive line then idles high). The port's clock must be on.
pub fn pin_af(port: usize, pin: usize, af: u32, pull_up: bool) {
    let base = 0x4800_0000 + 0x400 * port;
    let (afr, shift) = if pin < 8 {
        (base + 0x20, pin * 4)
    } else {
        (base + 0x24, (pin - 8) * 4)
    };
    modify(afr, 0xF << shift, af << shift);
    if pull_up {
        modify(base + 0x0C, 0b11 << (pin * 2), 0b01 << (pin * 2));
    }
    modify(base, 0b11 << (pin * 2), 0b10 << (pin * 2));
}

/// A USART of the STM32L4 (RM0351 §40), by its base address.
#[derive(Clone, Copy, Debug)]
pub struct Usart(pub usize);

const CR1_UE: u32 = 1 << 0;
const CR1_RE: u32 = 1 << 2;
const CR1_TE: u32 = 1 << 3;
const CR1_RXNEIE: u32 = 1 << 5;
const ISR_PE_FE_NF: u32 = 0b111;
const ISR_ORE: u32 = 1 << 3;
const ISR_RXNE: u32 = 1 << 5;
const ISR_TXE: u32 = 1 << 7;

impl Usart {
    /// USART1.
    pub const USART1: Usart = Usart(0x4001_3800);
    /// USART2.
    pub const USART2: Usart = Usart(0x4000_4400);
    /// USART3.
    pub const USART3: Usart = Usart(0x4000_4800);

    /// 8N1, 16× oversampling, BRR `brr` (computed from the line's clock as read back), with
    /// the receiver (and its interrupt) or the transmitter enabled. BRR is written while UE is
    /// off, as RM0351 requires.
    pub fn setup(self, brr: u16, rx: bool, tx: bool) {
        write(self.0, 0);
        write(self.0 + 0x04, 0);
        write(self.0 + 0x08, 0);
        write(self.0 + 0x0C, u32::from(brr));
        let rx = if rx { CR1_RE | CR1_RXNEIE } else { 0 };
        let tx = if tx { CR1_TE } else { 0 };
        write(self.0, CR1_UE | rx | tx);
    }

    /// The receive interrupt's work, as [`crate::serial::on_rx_interrupt`]: one byte from RDR
    /// into `ring`, or with the ring full the receive interrupt disabled (RXNEIE, and `irq` in
    /// the NVIC) and the byte left in RDR. Line errors and overruns are counted and cleared
    /// (ICR).
    #[inline(always)]
    pub fn on_rx_interrupt<I: InterruptNumber>(
        self,
        irq: I,
        ring: &mut Producer<'_, u8>,
        state: &Backpressure,
    ) {
        let isr = read(self.0 + 0x1C);
        if isr & ISR_ORE != 0 {
            state.overruns.fetch_add(1, Ordering::Relaxed);
            write(self.0 + 0x20, ISR_ORE);
        }
        if isr & ISR_PE_FE_NF != 0 {
            let _ = read(self.0 + 0x24);
            write(self.0 + 0x20, ISR_PE_FE_NF);
            state.line_errors.fetch_add(1, Ordering::Relaxed);
            return;
        }
        if isr & ISR_RXNE == 0 {
            return;
        }
        if !ring.ready() {
            modify(self.0, CR1_RXNEIE, 0);
            NVIC::mask(irq);
            state.paused.store(true, Ordering::Release);
            state.full.fetch_add(1, Ordering::Relaxed);
            return;
        }
        let byte = read(self.0 + 0x24) as u8;
        // `ready` was true and only this handler produces: the enqueue cannot fail.
        let _ = ring.enqueue(byte);
        state.received.fetch_add(1, Ordering::Relaxed);
    }

    /// Unmasks a paused receiver once its ring has room again.
    pub fn resume<I: InterruptNumber>(self, irq: I, ring_has_room: bool, state: &Backpressure) {
        if ring_has_room && state.paused.swap(false, Ordering::AcqRel) {
            modify(self.0, 0, CR1_RXNEIE);
            NVIC::unpend(irq);
            // SAFETY: the handler of `irq` only touches its ring's producer end and the
            // counters; it was masked only to pause it.
            #[allow(unsafe_code)]
            unsafe {
                NVIC::unmask(irq)
            };
        }
    }

    /// Writes bytes from `ring` while the transmitter takes them (TXE); returns how many.
    pub fn pump(self, ring: &mut Consumer<'_, u8>) -> u32 {
        let mut n = 0;
        while ring.ready() && read(self.0 + 0x1C) & ISR_TXE != 0 {
            let Some(b) = ring.dequeue() else { break };
            write(self.0 + 0x28, u32::from(b));
            n += 1;
        }
        n
    }
}
