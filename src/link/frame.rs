//! One frame to bytes and back: header, payload, CRC-32, COBS.

use super::layout::header;
use super::wire::{self, Check};
use super::{
    ErrorReport, Estimate, Frame, Heartbeat, LinkError, Message, MessageType, SetInitialPose,
    SetParameters, WheelOdometry, WheelTicks, DELIMITER, MAX_ENCODED_LEN, MAX_FRAME_LEN, VERSION,
};
use crc::{Crc, CRC_32_ISO_HDLC};

/// CRC-32/ISO-HDLC: polynomial 0x04C11DB7 reflected, init and final XOR 0xFFFFFFFF (zlib's
/// `crc32`, Python's `binascii.crc32`; check value 0xCBF43926 over `b"123456789"`).
const CRC: Crc<u32> = Crc::<u32>::new(&CRC_32_ISO_HDLC);

/// The link's CRC-32 (CRC-32/ISO-HDLC, zlib's `crc32`) of `bytes`.
pub fn crc32(bytes: &[u8]) -> u32 {
    CRC.checksum(bytes)
}

/// The payload offset as the error's `u8` (payloads are at most 79 bytes).
fn offset_u8(offset: usize) -> u8 {
    u8::try_from(offset).unwrap_or(u8::MAX)
}

/// Checks `message`'s values and writes its payload into `p` (exactly its length).
fn write_payload(message: &Message, p: &mut [u8]) -> Check {
    match message {
        Message::WheelOdometry(m) => m.check().map(|()| m.write(p)),
        Message::WheelTicks(m) => {
            m.write(p);
            Ok(())
        }
        Message::SetInitialPose(m) => m.check().map(|()| m.write(p)),
        Message::StartGlobalLocalization | Message::RequestNoMotionUpdate => Ok(()),
        Message::SetParameters(m) => m.check().map(|()| m.write(p)),
        Message::Estimate(m) => m.check().map(|()| m.write(p)),
        Message::Heartbeat(m) => {
            m.write(p);
            Ok(())
        }
        Message::Error(m) => {
            m.write(p);
            Ok(())
        }
    }
}

/// Reads and checks a payload of the right length for `t`.
fn read_payload(t: MessageType, p: &[u8]) -> Result<Message, usize> {
    Ok(match t {
        MessageType::WheelOdometry => {
            let m = WheelOdometry::read(p);
            m.check()?;
            Message::WheelOdometry(m)
        }
        MessageType::WheelTicks => Message::WheelTicks(WheelTicks::read(p)),
        MessageType::SetInitialPose => {
            let m = SetInitialPose::read(p);
            m.check()?;
            Message::SetInitialPose(m)
        }
        MessageType::StartGlobalLocalization => Message::StartGlobalLocalization,
        MessageType::RequestNoMotionUpdate => Message::RequestNoMotionUpdate,
        MessageType::SetParameters => {
            let m = SetParameters::read(p)?;
            m.check()?;
            Message::SetParameters(m)
        }
        MessageType::Estimate => {
            let m = Estimate::read(p)?;
            m.check()?;
            Message::Estimate(m)
        }
        MessageType::Heartbeat => Message::Heartbeat(Heartbeat::read(p)),
        MessageType::Error => Message::Error(ErrorReport::read(p)?),
    })
}

/// Writes `message` with sequence number `seq` into `out` as it goes on the wire: COBS bytes and
/// the `0x00` delimiter. Returns the number of bytes written (at most
/// [`MAX_WIRE_LEN`](super::MAX_WIRE_LEN)).
///
/// # Errors
/// [`LinkError::ValueOutOfRange`] for a value the receiver would refuse (nothing is written),
/// [`LinkError::BufferTooSmall`] when `out` cannot take the frame.
pub fn encode(seq: u16, message: &Message, out: &mut [u8]) -> Result<usize, LinkError> {
    let t = message.message_type();
    let payload_len = t.payload_len();
    let len = header::LEN + payload_len + header::CRC_LEN;
    let mut raw = [0u8; MAX_FRAME_LEN];
    let body_end = header::LEN + payload_len;
    wire::put_u8(&mut raw, header::VERSION, VERSION);
    wire::put_u8(&mut raw, header::TYPE, t as u8);
    wire::put_u16(&mut raw, header::SEQ, seq);
    let payload = raw.get_mut(header::LEN..body_end).unwrap_or_default();
    write_payload(message, payload).map_err(|offset| LinkError::ValueOutOfRange {
        msg_type: t as u8,
        seq,
        offset: offset_u8(offset),
    })?;
    let crc = crc32(raw.get(..body_end).unwrap_or_default());
    wire::put_u32(&mut raw, body_end..len, crc);
    let encoded_len = cobs::max_encoding_length(len);
    if out.len() <= encoded_len {
        return Err(LinkError::BufferTooSmall);
    }
    let n = cobs::try_encode(raw.get(..len).unwrap_or_default(), out)
        .map_err(|_| LinkError::BufferTooSmall)?;
    *out.get_mut(n).ok_or(LinkError::BufferTooSmall)? = DELIMITER;
    Ok(n + 1)
}

/// Decodes one frame from the bytes between two delimiters (COBS-encoded, without the `0x00`).
///
/// # Errors
/// The first check that fails, in the order of [`LinkError`]'s variants.
pub fn decode(encoded: &[u8]) -> Result<Frame, LinkError> {
    if encoded.len() > MAX_ENCODED_LEN {
        return Err(LinkError::Oversized);
    }
    if encoded.contains(&DELIMITER) {
        return Err(LinkError::BadCobs);
    }
    let mut raw = [0u8; MAX_FRAME_LEN];
    let len = match cobs::decode(encoded, &mut raw) {
        Ok(report) => report.frame_size(),
        Err(cobs::DecodeError::TargetBufTooSmall) => return Err(LinkError::Oversized),
        Err(_) => {
            return Err(if encoded.is_empty() {
                LinkError::TooShort
            } else {
                LinkError::BadCobs
            })
        }
    };
    let frame = raw.get(..len).ok_or(LinkError::Oversized)?;
    let Some(body_len) = len
        .checked_sub(header::CRC_LEN)
        .filter(|&b| b >= header::LEN)
    else {
        return Err(LinkError::TooShort);
    };
    let (body, crc) = frame.split_at(body_len);
    if crc32(body) != wire::u32_at(crc, 0..header::CRC_LEN) {
        return Err(LinkError::BadCrc);
    }
    let version = wire::u8_at(body, header::VERSION);
    let type_byte = wire::u8_at(body, header::TYPE);
    let seq = wire::u16_at(body, header::SEQ);
    if version != VERSION {
        return Err(LinkError::WrongVersion {
            version,
            msg_type: type_byte,
            seq,
        });
    }
    let t = MessageType::from_u8(type_byte).ok_or(LinkError::UnknownType {
        msg_type: type_byte,
        seq,
    })?;
    let payload = body.get(header::LEN..).unwrap_or_default();
    if payload.len() != t.payload_len() {
        return Err(LinkError::WrongLength {
            msg_type: type_byte,
            seq,
            len: offset_u8(payload.len()),
        });
    }
    let message = read_payload(t, payload).map_err(|offset| LinkError::ValueOutOfRange {
        msg_type: type_byte,
        seq,
        offset: offset_u8(offset),
    })?;
    Ok(Frame { seq, message })
}

/// [`encode`] with the sequence numbers counted: the first frame is 0, each encoded frame
/// takes the next (wrapping at 65,535).
#[derive(Clone, Debug, Default)]
pub struct Encoder {
    next_seq: u16,
}

impl Encoder {
    /// An encoder whose first frame has sequence number 0.
    pub const fn new() -> Self {
        Self { next_seq: 0 }
    }

    /// An encoder whose first frame has sequence number `first`.
    pub const fn starting_at(first: u16) -> Self {
        Self { next_seq: first }
    }

    /// The sequence number the next frame will carry.
    pub const fn next_seq(&self) -> u16 {
        self.next_seq
    }

    /// [`encode`]s `message` with the next sequence number, which is used up only when the frame
    /// was written.
    ///
    /// # Errors
    /// As [`encode`].
    pub fn encode(&mut self, message: &Message, out: &mut [u8]) -> Result<usize, LinkError> {
        let n = encode(self.next_seq, message, out)?;
        self.next_seq = self.next_seq.wrapping_add(1);
        Ok(n)
    }
}
