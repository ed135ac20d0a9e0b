//! The requests a controller sends and the single responses it reads back: response
//! descriptors, GET_INFO and GET_HEALTH.

use super::field::{descriptor, health, info, request};
use super::{
    RplidarError, DESCRIPTOR_LEN, HEALTH_LEN, INFO_LEN, NODE_LEN, REQUEST_LEN, SYNC, SYNC2,
};
use crate::lidar::{room, EncodeError};
use crate::wire;

/// `bytes[at] = value`, when `at` is in `bytes`.
fn set(bytes: &mut [u8], at: usize, value: u8) {
    if let Some(b) = bytes.get_mut(at) {
        *b = value;
    }
}

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
        let o = room(out, REQUEST_LEN)?;
        set(o, request::SYNC, SYNC);
        set(o, request::COMMAND, self.code());
        Ok(REQUEST_LEN)
    }

    /// Parses a request (what a sensor, or a simulator of one, receives).
    ///
    /// # Errors
    /// [`RplidarError::Truncated`], [`RplidarError::BadSync`], [`RplidarError::UnknownCommand`].
    pub fn parse(bytes: &[u8]) -> Result<Self, RplidarError> {
        let (Some(&sync), Some(&c)) = (bytes.get(request::SYNC), bytes.get(request::COMMAND))
        else {
            return Err(RplidarError::Truncated(bytes.len()));
        };
        if sync != SYNC {
            return Err(RplidarError::BadSync);
        }
        Ok(match c {
            0x25 => Self::Stop,
            0x40 => Self::Reset,
            0x20 => Self::Scan,
            0x21 => Self::ForceScan,
            0x50 => Self::GetInfo,
            0x52 => Self::GetHealth,
            other => return Err(RplidarError::UnknownCommand(other)),
        })
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
        let b = bytes
            .get(..DESCRIPTOR_LEN)
            .ok_or(RplidarError::Truncated(bytes.len()))?;
        // Byte by byte, as the decoder's own test of the prefix (which then folds this one away).
        if !matches!(b.get(descriptor::SYNC), Some(&[SYNC, SYNC2])) {
            return Err(RplidarError::BadSync);
        }
        let word = wire::get_u32(b, descriptor::LEN_MODE);
        Ok(Self {
            len: word & 0x3FFF_FFFF,
            mode: (word >> 30) as u8,
            data_type: b.get(descriptor::DATA_TYPE).copied().unwrap_or(0),
        })
    }

    /// Writes the 7 descriptor bytes; returns [`DESCRIPTOR_LEN`].
    ///
    /// # Errors
    /// [`EncodeError::BufferTooSmall`].
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        let o = room(out, DESCRIPTOR_LEN)?;
        let word = (self.len & 0x3FFF_FFFF) | (u32::from(self.mode & 3) << 30);
        wire::put(o, descriptor::SYNC, &[SYNC, SYNC2]);
        wire::put_u32(o, descriptor::LEN_MODE, word);
        set(o, descriptor::DATA_TYPE, self.data_type);
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
        let b: &[u8; INFO_LEN] = bytes
            .get(..INFO_LEN)
            .and_then(|s| s.try_into().ok())
            .ok_or(RplidarError::Truncated(bytes.len()))?;
        let mut serial = [0u8; 16];
        if let Some(s) = b.get(info::SERIAL) {
            serial.copy_from_slice(s);
        }
        Ok(Self {
            model: b[info::MODEL],
            firmware_minor: b[info::FIRMWARE_MINOR],
            firmware_major: b[info::FIRMWARE_MAJOR],
            hardware: b[info::HARDWARE],
            serial,
        })
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
        set(p, info::MODEL, self.model);
        set(p, info::FIRMWARE_MINOR, self.firmware_minor);
        set(p, info::FIRMWARE_MAJOR, self.firmware_major);
        set(p, info::HARDWARE, self.hardware);
        if let Some(serial) = p.get_mut(info::SERIAL) {
            serial.copy_from_slice(&self.serial);
        }
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
        let b = bytes
            .get(..HEALTH_LEN)
            .ok_or(RplidarError::Truncated(bytes.len()))?;
        Ok(Self {
            status: b.get(health::STATUS).copied().unwrap_or(0),
            error_code: wire::get_u16(b, health::ERROR_CODE),
        })
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
        set(p, health::STATUS, self.status);
        wire::put_u16(p, health::ERROR_CODE, self.error_code);
        Ok(needed)
    }
}
