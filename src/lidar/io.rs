//! Readers that pull bytes from a UART into a decoder (feature `hal`).
//!
//! [`LidarReader`] owns the port and a decoder (any [`StreamDecoder`]); as with the crate's other
//! drivers, [`LidarReader::new`] takes both by value and [`LidarReader::release`] gives them back.
//! Two kinds of ports:
//! - a blocking [`embedded_io::Read`] port (most HALs' UARTs): [`LidarReader::read_io`] makes one
//!   `read` call into a caller's buffer and feeds what came;
//! - a non-blocking [`embedded_hal_nb::serial::Read<u8>`] port: [`LidarReader::poll_nb`] takes
//!   the bytes that are ready, up to a limit, and returns when the port would block.
//!
//! For an interrupt or DMA ring buffer there is nothing to adapt: call the decoder's `feed` with
//! the received slice.

use super::{DecoderStats, LidarPoint, StreamDecoder};

/// A port error while reading.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error<E> {
    /// The port reported an error; bytes read before it were fed.
    Port(E),
}

impl<E: core::fmt::Debug> core::fmt::Display for Error<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Port(e) => write!(f, "serial port error: {e:?}"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for Error<E> {}

/// A UART and the decoder it feeds.
#[derive(Debug)]
pub struct LidarReader<R, D> {
    port: R,
    decoder: D,
}

impl<R, D: StreamDecoder> LidarReader<R, D> {
    /// Takes the port and the decoder.
    pub fn new(port: R, decoder: D) -> Self {
        Self { port, decoder }
    }

    /// Gives the port and the decoder back.
    pub fn release(self) -> (R, D) {
        (self.port, self.decoder)
    }

    /// The decoder (its counters, its last frame).
    pub fn decoder(&self) -> &D {
        &self.decoder
    }

    /// The decoder's counters.
    pub fn stats(&self) -> DecoderStats {
        self.decoder.stats()
    }
}

impl<R: embedded_io::Read, D: StreamDecoder> LidarReader<R, D> {
    /// One blocking `read` into `buf`, then feeds the bytes read; returns their count (0 at the
    /// end of the stream or for an empty `buf`).
    ///
    /// # Errors
    /// [`Error::Port`] when the read fails (nothing was fed).
    pub fn read_io(
        &mut self,
        buf: &mut [u8],
        mut on_point: impl FnMut(LidarPoint),
    ) -> Result<usize, Error<R::Error>> {
        if buf.is_empty() {
            return Ok(0);
        }
        let n = self.port.read(buf).map_err(Error::Port)?;
        for &b in buf.get(..n).unwrap_or(&[]) {
            self.decoder.push_byte(b, &mut on_point);
        }
        Ok(n)
    }
}

impl<R: embedded_hal_nb::serial::Read<u8>, D: StreamDecoder> LidarReader<R, D> {
    /// Takes up to `max_bytes` bytes that the port has ready and feeds each; returns how many were
    /// fed when the port would block or the limit is reached.
    ///
    /// # Errors
    /// [`Error::Port`] on a port error (the bytes before it were fed).
    pub fn poll_nb(
        &mut self,
        max_bytes: usize,
        mut on_point: impl FnMut(LidarPoint),
    ) -> Result<usize, Error<R::Error>> {
        let mut n = 0;
        while n < max_bytes {
            match self.port.read() {
                Ok(b) => {
                    self.decoder.push_byte(b, &mut on_point);
                    n += 1;
                }
                Err(embedded_hal_nb::nb::Error::WouldBlock) => break,
                Err(embedded_hal_nb::nb::Error::Other(e)) => return Err(Error::Port(e)),
            }
        }
        Ok(n)
    }
}
