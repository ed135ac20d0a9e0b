//! Why a frame was refused (decoding) or could not be written (encoding).

/// Why a frame was refused or could not be written. The checks run in the order of the variants
/// below (`docs/link-protocol.md#receiving`); the first that fails is reported. Variants after
/// [`LinkError::BadCrc`] come from frames whose CRC passed, so their type byte and sequence
/// number can be trusted and are kept (see [`LinkError::seq`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum LinkError {
    /// More bytes between two delimiters than the longest frame can take
    /// ([`MAX_ENCODED_LEN`](super::MAX_ENCODED_LEN)); discarded up to the next `0x00`.
    Oversized,
    /// The bytes between two delimiters are not a valid COBS encoding.
    BadCobs,
    /// The decoded frame is shorter than a header and a CRC (8 bytes).
    TooShort,
    /// The CRC-32 does not match the frame's bytes.
    BadCrc,
    /// The frame carries another protocol version than [`VERSION`](super::VERSION).
    WrongVersion {
        /// The version byte received.
        version: u8,
        /// The type byte (the header's layout is the same in every version).
        msg_type: u8,
        /// The frame's sequence number.
        seq: u16,
    },
    /// The type byte names no message of this protocol version.
    UnknownType {
        /// The type byte received.
        msg_type: u8,
        /// The frame's sequence number.
        seq: u16,
    },
    /// The payload's length is not the one its type has.
    WrongLength {
        /// The type byte.
        msg_type: u8,
        /// The frame's sequence number.
        seq: u16,
        /// The payload length received, bytes.
        len: u8,
    },
    /// A field's value is outside its valid range (NaN, infinite, an asymmetric covariance, a
    /// reserved bit set, …). Also returned by the encoder, which never writes such a frame.
    ValueOutOfRange {
        /// The type byte.
        msg_type: u8,
        /// The frame's sequence number.
        seq: u16,
        /// Byte offset of the first offending field in the payload.
        offset: u8,
    },
    /// The output buffer is too small for the encoded frame (encoding only;
    /// [`MAX_ENCODED_LEN`](super::MAX_ENCODED_LEN) + 1 bytes always suffice).
    BufferTooSmall,
}

impl LinkError {
    /// The offending frame's sequence number, when its CRC passed (so that it can be trusted).
    pub fn seq(&self) -> Option<u16> {
        match *self {
            Self::WrongVersion { seq, .. }
            | Self::UnknownType { seq, .. }
            | Self::WrongLength { seq, .. }
            | Self::ValueOutOfRange { seq, .. } => Some(seq),
            _ => None,
        }
    }
}

impl core::fmt::Display for LinkError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Oversized => f.write_str("frame longer than any message"),
            Self::BadCobs => f.write_str("invalid cobs encoding"),
            Self::TooShort => f.write_str("frame shorter than header and crc"),
            Self::BadCrc => f.write_str("crc mismatch"),
            Self::WrongVersion { version, seq, .. } => {
                write!(f, "protocol version {version} (expected {}) in frame {seq}", super::VERSION)
            }
            Self::UnknownType { msg_type, seq } => {
                write!(f, "unknown message type 0x{msg_type:02x} in frame {seq}")
            }
            Self::WrongLength { msg_type, seq, len } => write!(
                f,
                "payload of {len} bytes is the wrong length for type 0x{msg_type:02x} in frame {seq}"
            ),
            Self::ValueOutOfRange {
                msg_type,
                seq,
                offset,
            } => write!(
                f,
                "value out of range at payload offset {offset} of type 0x{msg_type:02x} in frame {seq}"
            ),
            Self::BufferTooSmall => f.write_str("output buffer too small"),
        }
    }
}

impl core::error::Error for LinkError {}
