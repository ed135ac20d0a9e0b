//! Blob format: round-trip, a malformed-blob corpus (every truncation, every single-bit flip),
//! and `field query` against an exact transform on the TurtleBot3 and Willow maps.

use beamfield::field::{emit_blob, BlobError, FieldHeader, FieldView, BLOB_HEADER_LEN};
use beamfield_tools::blob::build_blob;
use beamfield_tools::cmd::field::query::run_query;
use beamfield_tools::input::map::{load_map, Occupancy};
use host_tests::field_reference::{expected_distance, Grid};
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn emit_parse_round_trip(
        w in 1u32..40,
        h in 1u32..40,
        cell in 0.001f32..2.0,
        ox in -1e4f32..1e4,
        oy in -1e4f32..1e4,
        dmax in 0.01f32..20.0,
        seed in any::<u8>(),
    ) {
        let header = FieldHeader { width: w, height: h, cell_size_m: cell, origin_x_m: ox, origin_y_m: oy, max_dist_m: dmax };
        let codes: Vec<u8> = (0..w * h).map(|i| (i as u8).wrapping_mul(31).wrapping_add(seed)).collect();
        let mut out = vec![0xA5u8; header.required_len().unwrap() + 3];
        let n = emit_blob(&header, &codes, &mut out).unwrap();
        prop_assert_eq!(n, BLOB_HEADER_LEN + codes.len());
        prop_assert!(out[n..].iter().all(|&b| b == 0xA5), "bytes past the blob touched");
        let v = FieldView::parse(&out[..n]).unwrap();
        prop_assert_eq!(*v.header(), header);
        prop_assert_eq!(v.codes(), &codes[..]);
        for iy in 0..h {
            for ix in 0..w {
                prop_assert_eq!(v.code(ix, iy), Some(codes[(iy * w + ix) as usize]));
            }
        }
    }
}

fn small_blob() -> Vec<u8> {
    let header = FieldHeader::new(5, 4, 0.05, -1.25, 3.5);
    let codes: Vec<u8> = (0..20).map(|i| (i * 13) as u8).collect();
    let mut out = vec![0; header.required_len().unwrap()];
    emit_blob(&header, &codes, &mut out).unwrap();
    out
}

#[test]
fn every_truncation_is_an_error() {
    let blob = small_blob();
    assert!(FieldView::parse(&blob).is_ok());
    for n in 0..blob.len() {
        let r = std::panic::catch_unwind(|| FieldView::parse(&blob[..n]).err());
        assert_eq!(r.unwrap(), Some(BlobError::Truncated), "length {n}");
    }
    let mut longer = blob.clone();
    longer.push(0);
    assert_eq!(
        FieldView::parse(&longer).err(),
        Some(BlobError::TrailingBytes)
    );
}

#[test]
fn every_single_bit_flip_is_an_error() {
    let blob = small_blob();
    let mut kinds = std::collections::BTreeMap::<String, usize>::new();
    for bit in 0..blob.len() * 8 {
        let mut b = blob.clone();
        b[bit / 8] ^= 1 << (bit % 8);
        let r = std::panic::catch_unwind(|| FieldView::parse(&b).err());
        let err = r.unwrap_or_else(|_| panic!("panic on flip of bit {bit}"));
        let err = err.unwrap_or_else(|| panic!("flip of bit {bit} accepted"));
        *kinds.entry(format!("{err:?}")).or_default() += 1;
    }
    // Flips land on magic, version, header length, other header fields (header CRC) and the
    // payload (payload CRC); each must be caught by its own check.
    for k in [
        "BadMagic",
        "BadHeaderLength",
        "HeaderChecksum",
        "PayloadChecksum",
    ] {
        assert!(kinds.contains_key(k), "{k} never seen: {kinds:?}");
    }
}

fn grid_of(name: &str) -> (beamfield_tools::input::map::OccupancyMap, Grid) {
    let m = load_map(&host_tests::data_dir().join(name)).unwrap();
    let g = Grid {
        width: m.width as usize,
        height: m.height as usize,
        res: m.resolution_m,
        origin: (m.origin_x_m, m.origin_y_m),
        occupied: m.cells.iter().map(|c| *c == Occupancy::Occupied).collect(),
    };
    (m, g)
}

/// Query points at random offsets within ±0.4 cell of cell centres (so f32 and f64 agree on the
/// cell), some of them off the map; `field query`'s answer must equal the exact transform
/// within half a quantization step (plus f32 rounding).
fn query_agreement(name: &str, n_points: usize, max_dist: f32) {
    let (map, grid) = grid_of(name);
    let blob = build_blob(&map, max_dist).unwrap();
    let view = FieldView::parse(&blob).unwrap();
    let seeds = grid.seeds();
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut input = String::new();
    let mut points = Vec::new();
    for i in 0..n_points {
        // 1 in 10 points up to 3 m off the map.
        let margin = if i % 10 == 0 { 60.0 } else { 0.0 };
        let ix = (rnd() * (grid.width as f64 + 2.0 * margin) - margin).floor();
        let iy = (rnd() * (grid.height as f64 + 2.0 * margin) - margin).floor();
        let x = grid.origin.0 + (ix + 0.5 + 0.8 * (rnd() - 0.5)) * grid.res;
        let y = grid.origin.1 + (iy + 0.5 + 0.8 * (rnd() - 0.5)) * grid.res;
        // Exactly what will be printed and parsed back.
        let (x, y) = (x as f32, y as f32);
        input.push_str(&format!("{x},{y}\n"));
        points.push((x, y));
    }
    input.push_str("not a point\n");
    let mut out = Vec::new();
    let mut err = Vec::new();
    let report = run_query(&view, input.as_bytes(), &mut out, &mut err, false).unwrap();
    assert_eq!((report.answered, report.bad), (n_points, 1));
    assert!(String::from_utf8(err)
        .unwrap()
        .starts_with(&format!("line {}:", n_points + 1)));
    let step = f64::from(max_dist) / 255.0;
    let mut worst = 0.0f64;
    for (line, &(x, y)) in String::from_utf8(out).unwrap().lines().zip(&points) {
        let f: Vec<f64> = line.split(',').map(|t| t.parse().unwrap()).collect();
        assert_eq!((f[0] as f32, f[1] as f32), (x, y));
        let (quantized, exact) = expected_distance(
            &grid,
            &seeds,
            f64::from(x),
            f64::from(y),
            f64::from(max_dist),
        );
        let tol_f32 = 1e-6 * (1.0 + exact);
        assert!(
            (f[2] - quantized).abs() <= tol_f32,
            "({x}, {y}): got {}, quantized reference {quantized}",
            f[2]
        );
        let e = (f[2] - exact).abs();
        assert!(
            e <= step / 2.0 + tol_f32,
            "({x}, {y}): {} vs exact {exact}",
            f[2]
        );
        worst = worst.max(e);
    }
    eprintln!(
        "{name}: worst |query − exact| = {worst:.6} m (half step {:.6} m)",
        step / 2.0
    );
}

#[test]
fn query_agrees_with_exact_transform_turtlebot3() {
    query_agreement("map_turtlebot3_world/map.yaml", 5000, 2.0);
}

#[test]
fn query_agrees_with_exact_transform_willow() {
    query_agreement("map_willow_garage/willow-full-0.05.yaml", 1500, 2.0);
    // Another clamp distance: a different step, the same guarantee.
    query_agreement("map_willow_garage/willow-full-0.05.yaml", 300, 0.75);
}
