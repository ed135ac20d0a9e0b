//! Fuzzes the distance-field blob parser, both encodings: any bytes must give `Ok` or a typed
//! error, never a panic; an accepted blob must answer every lookup (on and off the map) without
//! panicking, and re-emitting its codes must give them back (the same bytes for encoding 1,
//! whose layout has one spelling).
//!
//! Each input is tried twice: as given, and with both CRCs recomputed (payload CRC over the
//! length the header states, then the header CRC), so that mutations get past the checksums
//! and reach the structural checks (sizes, the tile table).
//!
//! Run: `cargo +nightly fuzz run blob_parse` from the repository root.

#![no_main]

use beamfield::field::{
    emit_blob, emit_blob_tiled, tiled_max_len, tiled_scratch_len, FieldView, LikelihoodField,
    LikelihoodParams, ENCODING_TILED,
};
use beamfield::{BeamLayout, Pose, Scan, SensorMount};
use libfuzzer_sys::fuzz_target;

/// CRC-32/ISO-HDLC, bit by bit.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
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
            // Re-emitted tiled, the codes come back (the input's pool order or padding may
            // differ from the canonical writer's, so the bytes may not).
            let mut scratch = vec![0u32; tiled_scratch_len(&h).expect("scratch")];
            let mut out = vec![0u8; tiled_max_len(&h).expect("len")];
            let n = emit_blob_tiled(&h, &codes, &mut scratch, &mut out).expect("re-emit");
            let again = FieldView::parse(&out[..n]).expect("re-parse");
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

fuzz_target!(|data: &[u8]| {
    check(data);
    if data.len() >= 48 {
        let mut b = data.to_vec();
        let stated = u32::from_le_bytes([b[36], b[37], b[38], b[39]]) as usize;
        if let Some(payload) = b.get(48..48usize.saturating_add(stated)) {
            let crc = crc32(payload);
            b[40..44].copy_from_slice(&crc.to_le_bytes());
        }
        let crc = crc32(&b[..44]);
        b[44..48].copy_from_slice(&crc.to_le_bytes());
        check(&b);
    }
});
