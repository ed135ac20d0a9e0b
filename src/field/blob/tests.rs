//! Unit tests of the blob header: the layout by hand, every check of the parser, the writers'
//! errors and the distance codes.

use super::*;

fn sample() -> (FieldHeader, Vec<u8>) {
    let h = FieldHeader::new(3, 2, 0.05, -1.0, 2.0);
    let codes = vec![0, 1, 2, 253, 254, 255];
    let mut out = vec![0u8; h.required_len().unwrap()];
    assert_eq!(emit_blob(&h, &codes, &mut out), Ok(54));
    (h, out)
}

/// Rewrites the header CRC so that a deliberately wrong field reaches its own check.
fn reseal(b: &mut [u8]) {
    let crc = CRC32.checksum(&b[..44]);
    b[44..48].copy_from_slice(&crc.to_le_bytes());
}

#[test]
fn crc_is_the_zlib_crc() {
    // The standard check value of CRC-32/ISO-HDLC.
    assert_eq!(CRC32.checksum(b"123456789"), 0xCBF4_3926);
}

#[test]
fn each_field_check_is_reached() {
    let (_, good) = sample();
    type Edit = fn(&mut Vec<u8>);
    let cases: [(Edit, BlobError); 15] = [
        (|b| b[3] = b'X', BlobError::BadMagic),
        (|b| b[4] = 2, BlobError::UnsupportedVersion(2)),
        (|b| b[6] = 47, BlobError::BadHeaderLength),
        (|b| b[9] ^= 1, BlobError::HeaderChecksum),
        (|b| b[32] = 3, BlobError::UnsupportedEncoding(3)),
        (|b| b[34] = 1, BlobError::ReservedNonZero),
        // Byte 33 is a clamp code for encoding 2 only: reserved for encoding 1.
        (|b| b[33] = 1, BlobError::ReservedNonZero),
        (|b| b[8..12].fill(0), BlobError::ZeroSize),
        (
            |b| b[8..12].copy_from_slice(&(1u32 << 25).to_le_bytes()),
            BlobError::TooLarge,
        ),
        (|b| b[36] = 7, BlobError::PayloadLengthMismatch),
        (
            |b| b[16..20].copy_from_slice(&f32::NAN.to_le_bytes()),
            BlobError::BadCellSize,
        ),
        (
            |b| b[16..20].copy_from_slice(&(-0.05f32).to_le_bytes()),
            BlobError::BadCellSize,
        ),
        (
            |b| b[20..24].copy_from_slice(&f32::INFINITY.to_le_bytes()),
            BlobError::BadOrigin,
        ),
        (
            |b| b[28..32].copy_from_slice(&0f32.to_le_bytes()),
            BlobError::BadMaxDist,
        ),
        (|b| b[50] ^= 0x10, BlobError::PayloadChecksum),
    ];
    for (i, (edit, want)) in cases.into_iter().enumerate() {
        let mut b = good.clone();
        edit(&mut b);
        if want != BlobError::HeaderChecksum && i > 3 && want != BlobError::PayloadChecksum {
            reseal(&mut b);
        }
        assert_eq!(parse_blob(&b).err(), Some(want), "case {i}");
    }
    assert_eq!(parse_blob(&good[..53]).err(), Some(BlobError::Truncated));
    assert_eq!(parse_blob(&good[..47]).err(), Some(BlobError::Truncated));
}

#[test]
fn encoding_table() {
    let h = FieldHeader::new(1, 1, 0.05, 0.0, 0.0);
    let step = 2.0 / 255.0;
    let cases: [(f64, u8); 8] = [
        (0.0, 0),
        (0.49 * step, 0),
        (0.51 * step, 1),
        (10.0 * step, 10),
        (2.0, 255),
        (50.0, 255),
        (f64::INFINITY, 255),
        (f64::NAN, 0),
    ];
    for (d, want) in cases {
        assert_eq!(h.encode_distance_m(d), want, "d = {d}");
    }
    // 0.05 m · √(25) = 0.25 m = 31.875 steps → 32.
    assert_eq!(h.encode_squared_cells(25), 32);
    assert_eq!(h.encode_squared_cells(super::super::EDT_INFINITY), 255);
}

#[test]
fn writer_errors() {
    let h = FieldHeader::new(3, 2, 0.05, 0.0, 0.0);
    let mut small = [0u8; 53];
    assert_eq!(
        emit_blob(&h, &[0; 6], &mut small),
        Err(BlobError::BufferTooSmall)
    );
    let mut out = [0u8; 60];
    assert_eq!(
        emit_blob(&h, &[0; 5], &mut out),
        Err(BlobError::CellCountMismatch)
    );
    assert!(out.iter().all(|&b| b == 0));
}
