//! Fuzzes the distance-field blob parser: any bytes must give `Ok` or a typed error, never a
//! panic; an accepted blob must answer every lookup (on and off the map) without panicking,
//! and re-emitting it must give back the same bytes.
//!
//! Run: `cargo +nightly fuzz run blob_parse` from the repository root.

#![no_main]

use beamfield::field::{emit_blob, FieldView, LikelihoodField, LikelihoodParams};
use beamfield::{BeamLayout, Pose, Scan, SensorMount};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = FieldView::parse_prefix(data);
    let Ok(view) = FieldView::parse(data) else {
        return;
    };
    // Round trip: the writer reproduces an accepted blob bit for bit.
    let mut again = vec![0u8; data.len()];
    let n = emit_blob(view.header(), view.codes(), &mut again).expect("re-emit");
    assert_eq!(&again[..n], data);
    // Lookups, including off-map, non-finite and huge coordinates.
    let h = view.header();
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
    let s = lf.score(&layout, &scan, &Pose::new(h.origin_x_m, h.origin_y_m, 0.3));
    assert!(s.log_likelihood.is_finite());
});
