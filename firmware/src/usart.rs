//! A receive-only driver for USART1 of the STM32F405 (RM0090 §30), on the chip's registers
//! through the `stm32f4` register crate: the sensor's byte stream comes in here.
//!
//! Wiring on a real board: the sensor's TX line to PA10 (USART1_RX, alternate function 7), the
//! grounds together, 8 data bits, no parity, one stop bit (8N1, what the LD06 and the other 2-D
//! LiDARs send). [`UsartRx::new`] enables the peripheral clocks, sets PA10 to AF7, programs the
//! baud rate from the APB2 clock and enables the receiver.
//!
//! Under QEMU (`netduinoplus2`) the first `-serial` is USART1: the RCC and GPIO blocks are
//! stubs and the baud-rate register is ignored (the writes are kept for real hardware); a byte
//! is offered in DR as soon as the previous one has been read, so a slow reader loses nothing,
//! and bytes sent before the receiver is enabled are dropped: the program says it is ready only
//! after [`UsartRx::new`].
//!
//! [`UsartRx`] also implements `embedded_hal_nb::serial::Read<u8>` (with the line errors of SR
//! reported as overrun, framing, noise or parity errors), so anything written against that trait
//! can read from it.
//!
//! Two ways to wait for a byte: [`UsartRx::read_polling`] spins on RXNE; [`UsartRx::read_wfi`]
//! sleeps with `wfi` until the USART raises its interrupt line. The interrupt is never *taken*
//! (it is only used to wake the core): [`UsartRx::enable_wakeup`] masks interrupts with PRIMASK
//! first, so no handler is needed and the default vector table stays as it is.

use cortex_m::peripheral::NVIC;
use stm32f4::stm32f405::{Interrupt, GPIOA, RCC, USART1};

/// 8N1 receiver settings.
#[derive(Clone, Copy, Debug)]
pub struct Config {
    /// The APB2 clock that feeds USART1, Hz (84 MHz with the usual 168 MHz core clock).
    pub pclk2_hz: u32,
    /// Bits per second on the line (230,400 for the LD06).
    pub baud: u32,
}

/// The LD06's line: 230,400 baud, with the APB2 clock of a 168 MHz STM32F405.
pub const LD06_CONFIG: Config = Config {
    pclk2_hz: 84_000_000,
    baud: 230_400,
};

/// `(mantissa, fraction)` of USART_BRR for 16× oversampling (RM0090 §30.3.4):
/// `USARTDIV = pclk / (16 · baud)` in 12.4 fixed point, rounded to the nearest sixteenth.
/// Returns `None` when the divider does not fit the register (baud zero or too low or high for
/// the clock).
pub const fn brr(config: Config) -> Option<(u16, u8)> {
    if config.baud == 0 {
        return None;
    }
    // 16 · USARTDIV = pclk / baud, rounded.
    let sixteenths = (config.pclk2_hz as u64 + config.baud as u64 / 2) / config.baud as u64;
    let mantissa = sixteenths >> 4;
    if mantissa == 0 || mantissa > 0xFFF {
        return None;
    }
    Some((mantissa as u16, (sixteenths & 0xF) as u8))
}

/// Why the receiver could not be set up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum UsartError {
    /// The baud rate cannot be reached from this clock (see [`brr`]).
    BaudOutOfRange,
}

impl core::fmt::Display for UsartError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            UsartError::BaudOutOfRange => "baud rate out of range for this clock",
        })
    }
}

impl core::error::Error for UsartError {}

/// USART1 as an 8N1 receiver. Owns the peripheral; [`UsartRx::release`] gives it back.
pub struct UsartRx {
    usart: USART1,
    /// Bytes taken from DR so far.
    received: u32,
}

impl UsartRx {
    /// Sets up USART1 to receive on PA10: clocks (RCC), pin (GPIOA alternate function 7),
    /// baud rate, then UE and RE. Transmit stays off.
    ///
    /// # Errors
    /// [`UsartError::BaudOutOfRange`] when the baud rate cannot be set from `config.pclk2_hz`.
    pub fn new(
        usart: USART1,
        rcc: &RCC,
        gpioa: &GPIOA,
        config: Config,
    ) -> Result<Self, UsartError> {
        let Some((mantissa, fraction)) = brr(config) else {
            return Err(UsartError::BaudOutOfRange);
        };
        rcc.ahb1enr().modify(|_, w| w.gpioaen().enabled());
        rcc.apb2enr().modify(|_, w| w.usart1en().enabled());
        // PA10: alternate function 7 (USART1_RX), with the pull-up so an unwired line idles
        // high instead of reading noise as start bits.
        gpioa.afrh().modify(|_, w| w.afrh10().af7());
        gpioa.pupdr().modify(|_, w| w.pupdr10().pull_up());
        gpioa.moder().modify(|_, w| w.moder10().alternate());
        // Disabled while it is configured; 8 data bits, no parity (the reset values, written
        // anyway so a previous owner's settings do not survive).
        usart.cr1().write(|w| w.ue().disabled());
        usart.cr2().write(|w| w.stop().stop1());
        usart.cr3().write(|w| w);
        usart
            .brr()
            .write(|w| w.div_mantissa().set(mantissa).div_fraction().set(fraction));
        usart.cr1().write(|w| w.ue().enabled().re().enabled());
        Ok(Self { usart, received: 0 })
    }

    /// The next byte if one has arrived (RXNE set), else `None`. Reading DR clears RXNE and
    /// the overrun flag.
    #[inline]
    pub fn try_read(&mut self) -> Option<u8> {
        if self.usart.sr().read().rxne().bit_is_set() {
            self.received = self.received.wrapping_add(1);
            // 8 data bits: the ninth bit of DR is zero.
            Some(self.usart.dr().read().dr().bits() as u8)
        } else {
            None
        }
    }

    /// Waits for the next byte by polling RXNE.
    pub fn read_polling(&mut self) -> u8 {
        loop {
            if let Some(b) = self.try_read() {
                return b;
            }
        }
    }

    /// Lets [`UsartRx::read_wfi`] sleep between bytes: masks interrupts (PRIMASK, so no
    /// handler ever runs), enables the RXNE interrupt and unmasks USART1 in the NVIC, so a
    /// received byte wakes the core from `wfi`.
    pub fn enable_wakeup(&mut self) {
        cortex_m::interrupt::disable();
        self.usart.cr1().modify(|_, w| w.rxneie().enabled());
        NVIC::unpend(Interrupt::USART1);
        // SAFETY: PRIMASK is set above and never cleared by this program, so the interrupt
        // only wakes the core and no handler can break a critical section.
        #[allow(unsafe_code)]
        unsafe {
            NVIC::unmask(Interrupt::USART1)
        };
    }

    /// Waits for the next byte, sleeping with `wfi` while none is there. Call
    /// [`UsartRx::enable_wakeup`] once first (without it this still works, polling).
    pub fn read_wfi(&mut self) -> u8 {
        loop {
            if let Some(b) = self.try_read() {
                // The line dropped with RXNE; the latched pending bit would end the next wfi
                // at once.
                NVIC::unpend(Interrupt::USART1);
                return b;
            }
            if NVIC::is_enabled(Interrupt::USART1) {
                cortex_m::asm::wfi();
            }
        }
    }

    /// Bytes read from the data register so far (wraps at 2³²).
    pub fn received(&self) -> u32 {
        self.received
    }

    /// Disables the receiver and gives the peripheral back.
    pub fn release(self) -> USART1 {
        NVIC::mask(Interrupt::USART1);
        self.usart.cr1().write(|w| w.ue().disabled());
        self.usart
    }
}

/// A line error the USART flagged in SR (overrun, framing, noise, parity). The byte that came
/// with it is dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LineError(embedded_hal_nb::serial::ErrorKind);

impl embedded_hal_nb::serial::Error for LineError {
    fn kind(&self) -> embedded_hal_nb::serial::ErrorKind {
        self.0
    }
}

impl embedded_hal_nb::serial::ErrorType for UsartRx {
    type Error = LineError;
}

impl embedded_hal_nb::serial::Read<u8> for UsartRx {
    /// The next byte, `WouldBlock` while none has arrived, or the line error SR reports (the
    /// SR-then-DR read that returns it also clears it, RM0090 §30.6.1).
    fn read(&mut self) -> embedded_hal_nb::nb::Result<u8, LineError> {
        use embedded_hal_nb::serial::ErrorKind;
        let sr = self.usart.sr().read();
        let kind = if sr.ore().bit_is_set() {
            Some(ErrorKind::Overrun)
        } else if sr.fe().bit_is_set() {
            Some(ErrorKind::FrameFormat)
        } else if sr.nf().bit_is_set() {
            Some(ErrorKind::Noise)
        } else if sr.pe().bit_is_set() {
            Some(ErrorKind::Parity)
        } else {
            None
        };
        if let Some(kind) = kind {
            let _ = self.usart.dr().read();
            return Err(embedded_hal_nb::nb::Error::Other(LineError(kind)));
        }
        self.try_read()
            .ok_or(embedded_hal_nb::nb::Error::WouldBlock)
    }
}

// The divider, checked at compile time (this package has no host tests). RM0090's baud-rate
// tables (§30.3.4, 16× oversampling, fPCLK = 84 MHz) give USARTDIV 22.8125 for 230,400 baud
// (mantissa 22, fraction 13) and 45.5625 for 115,200 baud (45, 9).
const _: () = {
    assert!(matches!(brr(LD06_CONFIG), Some((22, 13))));
    assert!(matches!(
        brr(Config {
            pclk2_hz: 84_000_000,
            baud: 115_200
        }),
        Some((45, 9))
    ));
    assert!(brr(Config {
        pclk2_hz: 84_000_000,
        baud: 0
    })
    .is_none());
};
