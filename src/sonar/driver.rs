//! An embedded-hal 1.0 I²C driver for a ring of SRF08-class ultrasonic rangers (feature `hal`).
//!
//! One 7-bit bus address per transducer. For each group of the [`Schedule`], in order:
//! 1. start ranging on every transducer of the group: write `[0x00, 0x51]` (command register 0,
//!    command 0x51 = "range, result in centimetres");
//! 2. wait the schedule's interval (to the nearest microsecond) with the [`DelayNs`] (give it at least the ranger's ranging
//!    time: 65 ms for an SRF08 at its default range setting);
//! 3. for every transducer of the group, read the first echo: write `[0x02]` then read two bytes
//!    (registers 2 and 3, high byte first), in one `write_read`.
//!
//! A result of 0 cm means "no echo" and is stored as `+∞` (a max-range reading, see
//! [`crate::scan`]); any other value as metres. Transducers in no group read NaN (invalid,
//! skipped and counted by every model). Each beam is tagged with its co-fired count
//! ([`Schedule::cofired_count`]), precomputed in [`SonarRing::new`].
//!
//! The driver owns the bus and the delay: [`SonarRing::new`] takes them by value,
//! [`SonarRing::release`] gives them back. Bus errors come back as [`Error::I2c`].

use crate::scan::Scan;
use crate::sonar::schedule::Schedule;
use embedded_hal::delay::DelayNs;
use embedded_hal::i2c::I2c;
use heapless::Vec;

/// SRF08 command register.
pub const REG_COMMAND: u8 = 0x00;
/// SRF08 command: start ranging, result in centimetres.
pub const CMD_RANGE_CM: u8 = 0x51;
/// SRF08 register of the first echo's high byte (low byte follows at 3).
pub const REG_FIRST_ECHO: u8 = 0x02;

/// Errors of a ring read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error<E> {
    /// The bus failed; the scan holds what was read before.
    I2c(E),
}

impl<E: core::fmt::Debug> core::fmt::Display for Error<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::I2c(e) => write!(f, "i2c bus error: {e:?}"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for Error<E> {}

/// Why a driver could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ConfigError {
    /// Not one address per transducer of the schedule's ring.
    AddressCount {
        /// Addresses given.
        given: usize,
        /// Transducers in the ring.
        ring: usize,
    },
    /// An address outside the 7-bit range `0x08..=0x77` (the others are reserved).
    BadAddress(u8),
    /// Two transducers share an address.
    DuplicateAddress(u8),
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::AddressCount { given, ring } => {
                write!(f, "{given} addresses given, ring has {ring} transducers")
            }
            Self::BadAddress(a) => write!(f, "address {a:#04x} is not a usable 7-bit address"),
            Self::DuplicateAddress(a) => write!(f, "address {a:#04x} is used twice"),
        }
    }
}

impl core::error::Error for ConfigError {}

/// One cycle of the ring: the ranges (metres, `+∞` = no echo, NaN = not fired) and each beam's
/// co-fired count.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct RingScan<const M: usize> {
    /// Ranges in transducer order, metres.
    pub scan: Scan<M>,
    /// Co-fired count of each transducer (the `k` of the grouped EM).
    pub cofired: Vec<u16, M>,
}

/// A ring of SRF08-class rangers on one I²C bus, fired by a schedule.
pub struct SonarRing<I2C, D, const M: usize, const G: usize> {
    i2c: I2C,
    delay: D,
    addresses: Vec<u8, M>,
    cofired: Vec<u16, M>,
    schedule: Schedule<M, G>,
    interval_us: u32,
}

impl<I2C: I2c, D: DelayNs, const M: usize, const G: usize> SonarRing<I2C, D, M, G> {
    /// Takes the bus and the delay. `addresses[i]` is transducer `i`'s 7-bit address.
    ///
    /// # Errors
    /// A [`ConfigError`], with the bus and the delay given back.
    #[allow(clippy::type_complexity)]
    pub fn new(
        i2c: I2C,
        delay: D,
        addresses: &[u8],
        schedule: Schedule<M, G>,
    ) -> Result<Self, (ConfigError, I2C, D)> {
        match Self::check(addresses, &schedule) {
            Err(e) => Err((e, i2c, delay)),
            Ok((addresses, cofired)) => {
                // Microseconds, rounded up, saturating at u32::MAX (≈ 71 minutes).
                // Nearest microsecond (rounding up would turn the f32 representation error of
                // 0.07 s into 70 001 µs); `as` saturates at u32::MAX (≈ 71 minutes). The
                // interval is finite and ≥ 0 (validated by the schedule).
                let interval_us = (f64::from(schedule.interval_s()) * 1e6 + 0.5) as u32;
                Ok(Self {
                    i2c,
                    delay,
                    addresses,
                    cofired,
                    schedule,
                    interval_us,
                })
            }
        }
    }

    #[allow(clippy::type_complexity)]
    fn check(
        addresses: &[u8],
        schedule: &Schedule<M, G>,
    ) -> Result<(Vec<u8, M>, Vec<u16, M>), ConfigError> {
        let ring = schedule.ring_len();
        let count = ConfigError::AddressCount {
            given: addresses.len(),
            ring,
        };
        if addresses.len() != ring {
            return Err(count);
        }
        for (i, &a) in addresses.iter().enumerate() {
            if !(0x08..=0x77).contains(&a) {
                return Err(ConfigError::BadAddress(a));
            }
            if addresses.iter().take(i).any(|&b| b == a) {
                return Err(ConfigError::DuplicateAddress(a));
            }
        }
        let addrs = Vec::from_slice(addresses).map_err(|_| count)?;
        let mut cofired = Vec::new();
        for i in 0..ring {
            cofired.push(schedule.cofired_count(i)).map_err(|_| count)?;
        }
        Ok((addrs, cofired))
    }

    /// The schedule the ring fires by.
    pub fn schedule(&self) -> &Schedule<M, G> {
        &self.schedule
    }

    /// Runs one full schedule cycle and fills `out` (cleared first).
    ///
    /// # Errors
    /// [`Error::I2c`] on the first bus error; `out` then holds the transducers read so far and
    /// NaN for the others.
    pub fn read_cycle(&mut self, out: &mut RingScan<M>) -> Result<(), Error<I2C::Error>> {
        out.scan.clear();
        out.cofired.clear();
        for (_, &k) in self.addresses.iter().zip(&self.cofired) {
            // Cannot fail: at most M transducers.
            let _ = out.scan.push(f32::NAN);
            let _ = out.cofired.push(k);
        }
        for g in 0..self.schedule.group_count() {
            let group = self.schedule.group(g);
            for &i in group {
                if let Some(&addr) = self.addresses.get(usize::from(i)) {
                    self.i2c
                        .write(addr, &[REG_COMMAND, CMD_RANGE_CM])
                        .map_err(Error::I2c)?;
                }
            }
            self.delay.delay_us(self.interval_us);
            for &i in group {
                let i = usize::from(i);
                if let Some(&addr) = self.addresses.get(i) {
                    let mut buf = [0u8; 2];
                    self.i2c
                        .write_read(addr, &[REG_FIRST_ECHO], &mut buf)
                        .map_err(Error::I2c)?;
                    if let Some(r) = out.scan.ranges_m_mut().get_mut(i) {
                        *r = range_from_cm(u16::from_be_bytes(buf));
                    }
                }
            }
        }
        Ok(())
    }

    /// Gives the bus and the delay back.
    pub fn release(self) -> (I2C, D) {
        (self.i2c, self.delay)
    }
}

/// Converts an SRF08 result (centimetres, 0 = no echo) to metres (`+∞` for no echo).
pub fn range_from_cm(cm: u16) -> f32 {
    if cm == 0 {
        f32::INFINITY
    } else {
        f32::from(cm) * 0.01
    }
}
