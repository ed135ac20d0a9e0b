//! Little-endian field access by [`Field`] range, and the range checks shared by messages.
//!
//! Readers are called on payloads whose length was checked against the message's layout, so
//! every range is in bounds; an out-of-bounds range (a layout bug) reads as zeros and writes
//! nothing instead of panicking.

use super::layout::Field;
use super::{MAX_POSITION_M, MAX_THETA_RAD};
use crate::pose::Pose;

/// The `N` bytes of `field` in `buf`, zeros when out of bounds.
fn bytes<const N: usize>(buf: &[u8], field: Field) -> [u8; N] {
    buf.get(field)
        .and_then(|s| <[u8; N]>::try_from(s).ok())
        .unwrap_or([0; N])
}

/// Writes `value` into `field` of `buf` (nothing when the lengths differ).
fn put<const N: usize>(buf: &mut [u8], field: Field, value: [u8; N]) {
    if let Some(dst) = buf
        .get_mut(field)
        .and_then(|s| <&mut [u8; N]>::try_from(s).ok())
    {
        *dst = value;
    }
}

pub(super) fn u8_at(buf: &[u8], field: Field) -> u8 {
    u8::from_le_bytes(bytes(buf, field))
}
pub(super) fn u16_at(buf: &[u8], field: Field) -> u16 {
    u16::from_le_bytes(bytes(buf, field))
}
pub(super) fn u32_at(buf: &[u8], field: Field) -> u32 {
    u32::from_le_bytes(bytes(buf, field))
}
pub(super) fn i32_at(buf: &[u8], field: Field) -> i32 {
    i32::from_le_bytes(bytes(buf, field))
}
pub(super) fn u64_at(buf: &[u8], field: Field) -> u64 {
    u64::from_le_bytes(bytes(buf, field))
}
pub(super) fn f32_at(buf: &[u8], field: Field) -> f32 {
    f32::from_le_bytes(bytes(buf, field))
}

pub(super) fn put_u8(buf: &mut [u8], field: Field, v: u8) {
    put(buf, field, v.to_le_bytes());
}
pub(super) fn put_u16(buf: &mut [u8], field: Field, v: u16) {
    put(buf, field, v.to_le_bytes());
}
pub(super) fn put_u32(buf: &mut [u8], field: Field, v: u32) {
    put(buf, field, v.to_le_bytes());
}
pub(super) fn put_i32(buf: &mut [u8], field: Field, v: i32) {
    put(buf, field, v.to_le_bytes());
}
pub(super) fn put_u64(buf: &mut [u8], field: Field, v: u64) {
    put(buf, field, v.to_le_bytes());
}
pub(super) fn put_f32(buf: &mut [u8], field: Field, v: f32) {
    put(buf, field, v.to_le_bytes());
}

/// The `i`-th `f32` of an array field.
fn element(field: &Field, i: usize) -> Field {
    let start = field.start + 4 * i;
    start..start + 4
}

/// A pose from three consecutive `f32` fields starting at `x`.
pub(super) fn pose_at(buf: &[u8], x: Field, y: Field, theta: Field) -> Pose {
    Pose::new(f32_at(buf, x), f32_at(buf, y), f32_at(buf, theta))
}

pub(super) fn put_pose(buf: &mut [u8], x: Field, y: Field, theta: Field, p: &Pose) {
    put_f32(buf, x, p.x_m);
    put_f32(buf, y, p.y_m);
    put_f32(buf, theta, p.theta_rad);
}

/// A row-major 3×3 matrix of `f32` from a 36-byte field.
pub(super) fn matrix_at(buf: &[u8], field: Field) -> [[f32; 3]; 3] {
    let mut m = [[0.0; 3]; 3];
    for (i, v) in m.iter_mut().flatten().enumerate() {
        *v = f32_at(buf, element(&field, i));
    }
    m
}

pub(super) fn put_matrix(buf: &mut [u8], field: Field, m: &[[f32; 3]; 3]) {
    for (i, v) in m.iter().flatten().enumerate() {
        put_f32(buf, element(&field, i), *v);
    }
}

/// The result of a range check: `Err` holds the payload offset of the offending field.
pub(super) type Check = Result<(), usize>;

/// `Ok` when `ok`, else the offset of `field`.
pub(super) fn require(ok: bool, field: &Field) -> Check {
    if ok {
        Ok(())
    } else {
        Err(field.start)
    }
}

/// Finite, at most [`MAX_POSITION_M`] from the origin along each axis, heading within
/// `±`[`MAX_THETA_RAD`].
pub(super) fn check_pose(p: &Pose, x: &Field, y: &Field, theta: &Field) -> Check {
    require(p.x_m.is_finite() && p.x_m.abs() <= MAX_POSITION_M, x)?;
    require(p.y_m.is_finite() && p.y_m.abs() <= MAX_POSITION_M, y)?;
    require(
        p.theta_rad.is_finite() && p.theta_rad.abs() <= MAX_THETA_RAD,
        theta,
    )
}

/// Every entry finite, the diagonal non-negative, and the matrix exactly symmetric
/// (`m[j][i] == m[i][j]` bit for bit up to the sign of zero). The offending entry's offset.
pub(super) fn check_covariance(m: &[[f32; 3]; 3], field: &Field) -> Check {
    for (i, row) in m.iter().enumerate() {
        for (j, &v) in row.iter().enumerate() {
            let at = element(field, 3 * i + j);
            require(v.is_finite(), &at)?;
            if i == j {
                require(v >= 0.0, &at)?;
            }
            let mirror = m.get(j).and_then(|r| r.get(i)).copied();
            require(mirror == Some(v), &at)?;
        }
    }
    Ok(())
}
