//! The robot application's three serial lines on the STM32F405 (RM0090 §30): receivers that
//! fill a lock-free ring from their interrupt handler, and a transmitter the main loop drains
//! a ring into.
//!
//! | line | pins (AF7) | clock | direction |
//! |---|---|---|---|
//! | USART1 | PA10 RX | APB2 (84 MHz at 168 MHz) | the LiDAR's bytes in |
//! | USART2 | PA3 RX | APB1 (42 MHz at 168 MHz) | odometry and commands in |
//! | USART3 | PB10 TX | APB1 (42 MHz at 168 MHz) | estimates, heartbeats, errors out |
//!
//! **Receiving.** [`on_rx_interrupt`] runs in the USART's interrupt: it takes the byte from DR
//! into the ring's producer end (`heapless::spsc`, one producer — the handler — and one
//! consumer — the main loop — so no lock). When the ring is full it leaves the byte in DR and
//! masks the receive interrupt ([`Backpressure`]): the main loop unmasks it once it has made
//! room ([`resume`]). On a real line the next byte then overruns and is lost — the overrun flag
//! is counted, and the ring is sized so that it does not happen (`docs/robot.md`); under QEMU
//! the emulated line waits, so a test run loses nothing and says so.
//!
//! **Transmitting.** [`pump`] writes bytes from the transmit ring while TXE is set and returns
//! at once when it is not: the main loop calls it between its other work, so sending never
//! blocks the filter.

use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use cortex_m::peripheral::NVIC;
use heapless::spsc::{Consumer, Producer};
use stm32f4::stm32f405::{usart1::RegisterBlock, Interrupt, GPIOA, GPIOB, RCC};

/// A receiver's state shared between its interrupt handler and the main loop.
pub struct Backpressure {
    /// The handler masked the receive interrupt because the ring was full.
    pub paused: AtomicBool,
    /// Times the handler found the ring full.
    pub full: AtomicU32,
    /// Overruns (a byte lost in the hardware because the previous one was not read in time).
    pub overruns: AtomicU32,
    /// Line errors (framing, noise, parity): the byte is dropped.
    pub line_errors: AtomicU32,
    /// Bytes put into the ring.
    pub received: AtomicU32,
}

impl Backpressure {
    /// Nothing counted, not paused.
    pub const fn new() -> Self {
        Self {
            paused: AtomicBool::new(false),
            full: AtomicU32::new(0),
            overruns: AtomicU32::new(0),
            line_errors: AtomicU32::new(0),
            received: AtomicU32::new(0),
        }
    }
}

impl Default for Backpressure {
    fn default() -> Self {
        Self::new()
    }
}

/// Enables the clocks and pins of the three lines (on QEMU the RCC and GPIO blocks are stubs;
/// the writes are for real hardware).
pub fn enable_clocks_and_pins(rcc: &RCC, gpioa: &GPIOA, gpiob: &GPIOB) {
    rcc.ahb1enr()
        .modify(|_, w| w.gpioaen().enabled().gpioben().enabled());
    rcc.apb2enr().modify(|_, w| w.usart1en().enabled());
    rcc.apb1enr()
        .modify(|_, w| w.usart2en().enabled().usart3en().enabled());
    // PA10 (USART1_RX) and PA3 (USART2_RX) with pull-ups, so an unwired line idles high.
    gpioa.afrh().modify(|_, w| w.afrh10().af7());
    gpioa.afrl().modify(|_, w| w.afrl3().af7());
    gpioa
        .pupdr()
        .modify(|_, w| w.pupdr10().pull_up().pupdr3().pull_up());
    gpioa
        .moder()
        .modify(|_, w| w.moder10().alternate().moder3().alternate());
    // PB10 (USART3_TX).
    gpiob.afrh().modify(|_, w| w.afrh10().af7());
    gpiob.moder().modify(|_, w| w.moder10().alternate());
}

/// Programs a line for 8N1 with the divider `brr` (USART_BRR, 12.4 fixed point: computed from
/// the line's clock as it was read back, `beamfield_fixtures::clocks::usart_brr`), with the
/// receiver (and its interrupt) or the transmitter enabled.
pub fn setup(regs: &RegisterBlock, brr: u16, rx: bool, tx: bool) {
    regs.cr1().write(|w| w.ue().disabled());
    regs.cr2().write(|w| w.stop().stop1());
    regs.cr3().write(|w| w);
    regs.brr().write(|w| {
        w.div_mantissa()
            .set(brr >> 4)
            .div_fraction()
            .set((brr & 0xF) as u8)
    });
    regs.cr1().write(|w| {
        let w = w.ue().enabled();
        let w = if rx {
            w.re().enabled().rxneie().enabled()
        } else {
            w
        };
        if tx {
            w.te().enabled()
        } else {
            w
        }
    });
}

/// The receive interrupt's work: one byte from DR into `ring`, or, with the ring full, the
/// receive interrupt disabled (RXNEIE) and the byte left in DR; `irq` is then masked in the
/// NVIC too (QEMU's USART model lowers its interrupt line only when DR is read, so RXNEIE alone
/// would leave the handler running in a loop). Line errors and overruns are counted in `state`.
#[inline(always)]
pub fn on_rx_interrupt(
    regs: &RegisterBlock,
    irq: Interrupt,
    ring: &mut Producer<'_, u8>,
    state: &Backpressure,
) {
    let sr = regs.sr().read();
    if sr.ore().bit_is_set() {
        state.overruns.fetch_add(1, Ordering::Relaxed);
    }
    if sr.fe().bit_is_set() || sr.nf().bit_is_set() || sr.pe().bit_is_set() {
        // The SR-then-DR read clears the flags; the byte is dropped.
        let _ = regs.dr().read();
        state.line_errors.fetch_add(1, Ordering::Relaxed);
        return;
    }
    if !sr.rxne().bit_is_set() {
        // An overrun alone (ORE without RXNE) is cleared by the same SR-then-DR read.
        if sr.ore().bit_is_set() {
            let _ = regs.dr().read();
        }
        return;
    }
    if !ring.ready() {
        regs.cr1().modify(|_, w| w.rxneie().disabled());
        NVIC::mask(irq);
        state.paused.store(true, Ordering::Release);
        state.full.fetch_add(1, Ordering::Relaxed);
        return;
    }
    let byte = regs.dr().read().dr().bits() as u8;
    // `ready` was true and only this handler produces: the enqueue cannot fail.
    let _ = ring.enqueue(byte);
    state.received.fetch_add(1, Ordering::Relaxed);
}

/// Unmasks a paused receiver once its ring has room again (called by the main loop after it
/// took bytes out).
pub fn resume(regs: &RegisterBlock, irq: Interrupt, ring_has_room: bool, state: &Backpressure) {
    if ring_has_room && state.paused.swap(false, Ordering::AcqRel) {
        regs.cr1().modify(|_, w| w.rxneie().enabled());
        NVIC::unpend(irq);
        // SAFETY: the handler of `irq` only touches its ring's producer end and the counters;
        // it was masked only to pause it.
        #[allow(unsafe_code)]
        unsafe {
            NVIC::unmask(irq)
        };
    }
}

/// Writes bytes from `ring` while the transmitter takes them (TXE); returns how many.
pub fn pump(regs: &RegisterBlock, ring: &mut Consumer<'_, u8>) -> u32 {
    let mut n = 0;
    while ring.ready() && regs.sr().read().txe().bit_is_set() {
        let Some(b) = ring.dequeue() else { break };
        regs.dr().write(|w| w.dr().set(u16::from(b)));
        n += 1;
    }
    n
}
