//! Wire-format fields at fixed byte ranges, smoltcp style: each format keeps one table of where
//! its fields lie (`mod field { pub const SPEED: Field = 2..4; … }`), and its parse and emit code
//! read and write through that table only, with the helpers here.
//!
//! Contract: every helper is total. A range that does not fit the bytes reads as 0 and writes
//! nothing, so no input can make a parser panic; in the formats of this crate the tables are
//! checked against the formats' lengths at compile time, so that case never arises and, once
//! inlined over a fixed-size buffer, the checks fold away.

use core::ops::{Range, RangeFrom};

/// The bytes of one field: `start..end` of its frame, packet or header.
pub(crate) type Field = Range<usize>;
/// A field that runs to the end of its frame (a payload).
pub(crate) type Rest = RangeFrom<usize>;

/// The little-endian `u16` at `field` of `bytes` (0 when it does not fit).
#[inline(always)]
pub(crate) fn get_u16(bytes: &[u8], field: Field) -> u16 {
    match bytes.get(field) {
        Some(&[lo, hi]) => u16::from_le_bytes([lo, hi]),
        _ => 0,
    }
}

/// The little-endian `u32` at `field` of `bytes` (0 when it does not fit).
#[inline(always)]
pub(crate) fn get_u32(bytes: &[u8], field: Field) -> u32 {
    match bytes.get(field) {
        Some(&[a, b, c, d]) => u32::from_le_bytes([a, b, c, d]),
        _ => 0,
    }
}

/// The little-endian IEEE 754 binary32 at `field` of `bytes` (0.0 when it does not fit).
#[inline(always)]
pub(crate) fn get_f32(bytes: &[u8], field: Field) -> f32 {
    f32::from_bits(get_u32(bytes, field))
}

/// Writes `value` at `field` of `bytes` (nothing when the field does not fit or is not
/// `value.len()` bytes long).
#[inline(always)]
pub(crate) fn put(bytes: &mut [u8], field: Field, value: &[u8]) {
    if let Some(dst) = bytes.get_mut(field) {
        if dst.len() == value.len() {
            dst.copy_from_slice(value);
        }
    }
}

/// Writes `value` little-endian at `field` of `bytes` (see [`put`]).
#[inline(always)]
pub(crate) fn put_u16(bytes: &mut [u8], field: Field, value: u16) {
    put(bytes, field, &value.to_le_bytes());
}

/// Writes `value` little-endian at `field` of `bytes` (see [`put`]).
#[inline(always)]
pub(crate) fn put_u32(bytes: &mut [u8], field: Field, value: u32) {
    put(bytes, field, &value.to_le_bytes());
}

/// The length of `field`, for the compile-time checks of a table.
pub(crate) const fn len(field: &Field) -> usize {
    field.end - field.start
}

/// Writes `value` little-endian at `field` of `bytes` (see [`put`]).
#[inline(always)]
pub(crate) fn put_f32(bytes: &mut [u8], field: Field, value: f32) {
    put(bytes, field, &value.to_le_bytes());
}
