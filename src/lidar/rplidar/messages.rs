//! The requests a controller sends and the single responses it reads back: response
//! descriptors, GET_INFO and GET_HEALTH.

use super::{RplidarError, DESCRIPTOR_LEN, HEALTH_LEN, INFO_LEN, NODE_LEN, SYNC, SYNC2};
use crate::lidar::{room, EncodeError};

/// The requests a controller sends. Each is two bytes, `0xA5` and the command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Command {
    /// `0x25`: stop scanning (no response).
    Stop,
    /// `0x40`: reset the core (no response; the sensor prints its boot banner).
    Reset,
    /// `0x20`: start a standard scan (answered by [`SCAN_DESCRIPTOR`](super::SCAN_DESCRIPTOR) and nodes).
    Scan,
    /// `0x21`: start scanning whether or not the motor speed is stable.
    ForceScan,
    /// `0x50`: device information (answered by a descriptor and [`DeviceInfo`]).
    GetInfo,
    /// `0x52`: health (answered by a descriptor and [`Health`]).
    GetHealth,
}

impl Command {
    /// The command byte.
    pub const fn code(self) -> u8 {
        match self {
            Self::Stop => 0x25,
            Self::Reset => 0x40,
            Self::Scan => 0x20,
            Self::ForceScan => 0x21,
            Self::GetInfo => 0x50,
            Self::GetHealth => 0x52,
        }
    }

    /// Writes the request (`0xA5`, code) into `out`; returns 2.
    ///
    /// # Errors
    /// [`EncodeError::BufferTooSmall`].
    pub fn emit(self, out: &mut [u8]) -> Result<usize, EncodeError> {
        room(out, 2)?.copy_from_slice(&[SYNC, self.code()]);
        Ok(2)
    }

    /// Parses a request (what a sensor, or a simulator of one, receives).
    ///
    /// # Errors
    /// [`RplidarError::Truncated`], [`RplidarError::BadSync`], [`RplidarError::UnknownCommand`].
    pub fn parse(bytes: &[u8]) -> Result<Self, RplidarError> {
        match bytes {
            [SYNC, c, ..] => Ok(match *c {
                0x25 => Self::Stop,
                0x40 => Self::Reset,
                0x20 => Self::Scan,
                0x21 => Self::ForceScan,
                0x50 => Self::GetInfo,
                0x52 => Self::GetHealth,
                other => return Err(RplidarError::UnknownCommand(other)),
            }),
            [_, _, ..] => Err(RplidarError::BadSync),
            _ => Err(RplidarError::Truncated(bytes.len())),
        }
    }
}

/// A response descriptor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Descriptor {
    /// Length of one response (30 bits).
    pub len: u32,
    /// Send mode: 0 single response, 1 multiple responses (2 bits).
    pub mode: u8,
    /// Data type.
    pub data_type: u8,
}

impl Descriptor {
    /// The scan descriptor's fields.
    pub const SCAN: Self = Self {
        len: NODE_LEN as u32,
        mode: 1,
        data_type: 0x81,
    };
    /// The GET_INFO descriptor's fields.
    pub const INFO: Self = Self {
        len: INFO_LEN as u32,
        mode: 0,
        data_type: 0x04,
    };
    /// The GET_HEALTH descriptor's fields.
    pub const HEALTH: Self = Self {
        len: HEALTH_LEN as u32,
        mode: 0,
        data_type: 0x06,
    };

    /// Parses 7 descriptor bytes.
    ///
    /// # Errors
    /// [`RplidarError::Truncated`], [`RplidarError::BadSync`].
    pub fn parse(bytes: &[u8]) -> Result<Self, RplidarError> {
        match bytes {
            [SYNC, SYNC2, a, b, c, d, t, ..] => {
                let word = u32::from_le_bytes([*a, *b, *c, *d]);
                Ok(Self {
                    len: word & 0x3FFF_FFFF,
                    mode: (word >> 30) as u8,
                    data_type: *t,
                })
            }
            [_, _, _, _, _, _, _, ..] => Err(RplidarError::BadSync),
            _ => Err(RplidarError::Truncated(bytes.len())),
        }
    }

    /// Writes the 7 descriptor bytes; returns [`DESCRIPTOR_LEN`].
    ///
    /// # Errors
    /// [`EncodeError::BufferTooSmall`].
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        let o = room(out, DESCRIPTOR_LEN)?;
        let word = (self.len & 0x3FFF_FFFF) | (u32::from(self.mode & 3) << 30);
        let [a, b, c, d] = word.to_le_bytes();
        o.copy_from_slice(&[SYNC, SYNC2, a, b, c, d, self.data_type]);
        Ok(DESCRIPTOR_LEN)
    }
}

/// The GET_INFO response.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DeviceInfo {
    /// Model id.
    pub model: u8,
    /// Firmware version, minor part.
    pub firmware_minor: u8,
    /// Firmware version, major part.
    pub firmware_major: u8,
    /// Hardware version.
    pub hardware: u8,
    /// 128-bit serial number, as sent.
    pub serial: [u8; 16],
}

impl DeviceInfo {
    /// Parses the 20-byte payload.
    ///
    /// # Errors
    /// [`RplidarError::Truncated`].
    pub fn parse(bytes: &[u8]) -> Result<Self, RplidarError> {
        match bytes.get(..INFO_LEN) {
            Some([model, fw_minor, fw_major, hw, serial @ ..]) => {
                let mut s = [0u8; 16];
                s.copy_from_slice(serial);
                Ok(Self {
                    model: *model,
                    firmware_minor: *fw_minor,
                    firmware_major: *fw_major,
                    hardware: *hw,
                    serial: s,
                })
            }
            _ => Err(RplidarError::Truncated(bytes.len())),
        }
    }

    /// Writes the descriptor and the payload (27 bytes); returns the count.
    ///
    /// # Errors
    /// [`EncodeError::BufferTooSmall`].
    pub fn emit_response(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        let needed = DESCRIPTOR_LEN + INFO_LEN;
        let o = room(out, needed)?;
        let (d, p) = o.split_at_mut(DESCRIPTOR_LEN);
        Descriptor::INFO.emit(d)?;
        let (head, serial) = p.split_at_mut(4);
        head.copy_from_slice(&[
            self.model,
            self.firmware_minor,
            self.firmware_major,
            self.hardware,
        ]);
        serial.copy_from_slice(&self.serial);
        Ok(needed)
    }
}

/// The GET_HEALTH response.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Health {
    /// 0 good, 1 warning, 2 error (the sensor's protection stop; send [`Command::Reset`]).
    pub status: u8,
    /// The sensor's error code, meaningful when `status` is not 0.
    pub error_code: u16,
}

impl Health {
    /// Parses the 3-byte payload.
    ///
    /// # Errors
    /// [`RplidarError::Truncated`].
    pub fn parse(bytes: &[u8]) -> Result<Self, RplidarError> {
        match bytes {
            [status, lo, hi, ..] => Ok(Self {
                status: *status,
                error_code: u16::from_le_bytes([*lo, *hi]),
            }),
            _ => Err(RplidarError::Truncated(bytes.len())),
        }
    }

    /// Writes the descriptor and the payload (10 bytes); returns the count.
    ///
    /// # Errors
    /// [`EncodeError::BufferTooSmall`].
    pub fn emit_response(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        let needed = DESCRIPTOR_LEN + HEALTH_LEN;
        let o = room(out, needed)?;
        let (d, p) = o.split_at_mut(DESCRIPTOR_LEN);
        Descriptor::HEALTH.emit(d)?;
        let [lo, hi] = self.error_code.to_le_bytes();
        p.copy_from_slice(&[self.status, lo, hi]);
        Ok(needed)
    }
}
