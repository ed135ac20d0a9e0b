//! Fuzzes the distance-field blob parser, both encodings: any bytes must give `Ok` or a typed
//! error, never a panic; an accepted blob must answer every lookup (on and off the map) without
//! panicking, and re-emitting its codes must give them back (the same bytes for encoding 1,
//! whose layout has one spelling).
//!
//! Checksums: a mutated header almost never passes the header CRC, so without help the fuzzer
//! never reaches the size, cell-size and origin checks or lookups on unusual headers. The first
//! input byte is therefore a set of repair flags, applied to the rest (the blob) before parsing:
//! bit 0 writes a valid magic, version and header length; bit 1 a valid encoding (bit 5 set:
//! encoding 2, tiled; clear: encoding 1, raw) and zero reserved bytes (bit 6 set with bit 5:
//! header byte 33, encoding 2's clamp code, is left as the fuzzer wrote it); bit 2 sets the
//! payload-length field to `W·H` (encoding 1's rule); bit 3 recomputes the payload CRC (over
//! the stated payload length, as far as the bytes go); bit 4 recomputes the header CRC (last, over the
//! repaired header). Each flag clear leaves that field as the fuzzer wrote it, so every check
//! of docs/blob-format.md's reader rules stays reachable both ways.
//!
//! Run: `cargo +nightly fuzz run blob_parse` from the repository root.

#![no_main]

use beamfield::field::{
    emit_blob, emit_blob_tiled_clamped, tiled_max_len, tiled_scratch_len, FieldView, LikelihoodField,
    LikelihoodParams, ENCODING_TILED,
};
use beamfield::{BeamLayout, Pose, Scan, SensorMount};
use libfuzzer_sys::fuzz_target;

/// CRC-32/ISO-HDLC, the blob's checksum (docs/blob-format.md).
const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// Applies the repair `flags` (see the module docs) to `blob` in place.
fn repair(flags: u8, blob: &mut [u8]) {
    if blob.len() < 48 {
        return;
    }
    if flags & 1 != 0 {
        blob[0..4].copy_from_slice(b"BFDF");
        blob[4..6].copy_from_slice(&1u16.to_le_bytes());
        blob[6..8].copy_from_slice(&48u16.to_le_bytes());
    }
    if flags & 2 != 0 {
        // Bit 5 picks the encoding: 2 (tiled) when set, 1 (raw) when clear.
        blob[32] = if flags & 32 != 0 { ENCODING_TILED } else { 1 };
        let keep_clamp = flags & 32 != 0 && flags & 64 != 0;
        blob[if keep_clamp { 34 } else { 33 }..36].fill(0);
    }
    let cells = u64::from(u32_at(blob, 8)) * u64::from(u32_at(blob, 12));
    if flags & 4 != 0 {
        blob[36..40].copy_from_slice(&(cells as u32).to_le_bytes());
    }
    if flags & 8 != 0 {
        // Over the payload length the header states (W·H for encoding 1, the tile table's and
        // pool's length for encoding 2), as far as the bytes go.
        let stated = u64::from(u32_at(blob, 36));
        let end = 48usize.saturating_add(stated.min(blob.len() as u64) as usize).min(blob.len());
        let crc = CRC.checksum(&blob[48..end]);
        blob[40..44].copy_from_slice(&crc.to_le_bytes());
    }
    if flags & 16 != 0 {
        let crc = CRC.checksum(&blob[0..44]);
        blob[44..48].copy_from_slice(&crc.to_le_bytes());
    }
}

fn check(data: &[u8]) {
    let _ = FieldView::parse_prefix(data);
    let Ok(view) = FieldView::parse(data) else {
        return;
    };
    let h = *view.header();
    // Every cell (bounded, so huge grids stay fast), then just past the edges.
    let mut codes = Vec::new();
    if u64::from(h.width) * u64::from(h.height) <= 1 << 20 {
        for iy in 0..h.height {
            for ix in 0..h.width {
                codes.push(view.code(ix, iy).expect("on-map cell"));
            }
        }
        assert_eq!(view.code(h.width, 0), None);
        assert_eq!(view.code(0, h.height), None);
        if view.encoding() == ENCODING_TILED {
            // Re-emitted tiled with the same clamp, the codes come back (the input's pool order
            // or padding may differ from the canonical writer's, so the bytes may not). Every
            // code is at most the clamp code (the parser checked the pool).
            let clamp = view.clamp_code().unwrap_or(0);
            assert!(clamp == 0 || codes.iter().all(|&c| c <= clamp));
            let mut scratch = vec![0u32; tiled_scratch_len(&h).expect("scratch")];
            let mut out = vec![0u8; tiled_max_len(&h).expect("len")];
            let n = emit_blob_tiled_clamped(&h, &codes, clamp, &mut scratch, &mut out)
                .expect("re-emit");
            let again = FieldView::parse(&out[..n]).expect("re-parse");
            assert_eq!(again.clamp_code(), view.clamp_code());
            for iy in 0..h.height {
                for ix in 0..h.width {
                    assert_eq!(
                        again.code(ix, iy),
                        Some(codes[(iy * h.width + ix) as usize])
                    );
                }
            }
        } else {
            // Round trip: the writer reproduces an accepted raw blob bit for bit.
            let mut again = vec![0u8; data.len()];
            let n = emit_blob(&h, &codes, &mut again).expect("re-emit");
            assert_eq!(&again[..n], data);
        }
    }
    // Lookups, including off-map, non-finite and huge coordinates.
    for (x, y) in [
        (h.origin_x_m, h.origin_y_m),
        (h.origin_x_m - 1.0, h.origin_y_m + 1e6),
        (f32::NAN, 0.0),
        (f32::INFINITY, f32::NEG_INFINITY),
        (f32::MAX, f32::MIN),
    ] {
        let _ = view.distance_m(x, y);
    }
    let lf = LikelihoodField::new(view, LikelihoodParams::amcl_defaults(10.0).expect("params"));
    let layout =
        BeamLayout::<8>::uniform(-1.0, 0.3, 8, 10.0, SensorMount::CENTERED).expect("layout");
    let scan = Scan::<8>::from_ranges(&[0.0, 1.0, 9.9, 10.0, f32::NAN, -1.0, f32::INFINITY, 5.0])
        .expect("scan");
    let pose = Pose::new(h.origin_x_m, h.origin_y_m, 0.3);
    let s = lf.score(&layout, &scan, &pose);
    assert!(s.log_likelihood.is_finite());
    let p = lf.prepare(&layout, &scan).score(&pose);
    assert!(p.log_likelihood.is_finite());
}

fuzz_target!(|input: &[u8]| {
    let Some((&flags, rest)) = input.split_first() else {
        return;
    };
    let mut owned = rest.to_vec();
    repair(flags, &mut owned);
    check(&owned);
});
