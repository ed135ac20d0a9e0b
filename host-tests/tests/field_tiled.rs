//! The tiled blob (distance encoding 2) against the raw blob (encoding 1) it was made from:
//! every cell of the three shared maps, every score of the demo's scans (prepared, per-pose,
//! fixed-point and ray cast) bit for bit, and a malformed-blob corpus (every truncation, every
//! single-bit flip, and every single-bit flip with the checksums recomputed, so that the
//! structural checks are reached).

use beamfield::field::{
    emit_blob, BlobError, FieldHeader, FieldView, LikelihoodField, LikelihoodParams, ENCODING_TILED,
};
use beamfield::fixed_point::{FixedField, FixedLayout, FixedPose, FixedScan};
use beamfield::{BeamLayout, Pose, RayCaster, Scan, SensorMount};
use beamfield_fixtures::demo_plan::{fine_search, COARSE, SIGMA_HIT_M, Z_HIT, Z_RAND};
use beamfield_tools::blob::{build_blob, tile_blob, tile_blob_clamped};
use beamfield_tools::demo_assets::SCAN_INDICES;
use beamfield_tools::input::carmen::{CarmenLog, ReadOptions};
use beamfield_tools::input::map::load_map;
use proptest::prelude::*;

const N: usize = 180;

fn crc32(bytes: &[u8]) -> u32 {
    // CRC-32/ISO-HDLC, bit by bit (independent of the crate's table-driven one).
    let mut crc = 0xFFFF_FFFFu32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// Recomputes the payload CRC and then the header CRC, as a corrupting writer would.
fn reseal(b: &mut [u8]) {
    let payload = crc32(&b[48..]);
    b[40..44].copy_from_slice(&payload.to_le_bytes());
    let head = crc32(&b[..44]);
    b[44..48].copy_from_slice(&head.to_le_bytes());
}

fn every_code(v: &FieldView<'_>) -> Vec<u8> {
    let mut out = Vec::with_capacity((v.width() * v.height()) as usize);
    for iy in 0..v.height() {
        for ix in 0..v.width() {
            out.push(v.code(ix, iy).unwrap());
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Random grids with few distinct values (so tiles repeat): the tiled blob gives back every
    /// code, and the same header.
    #[test]
    fn tiled_round_trip(w in 1u32..40, h in 1u32..40, levels in 1u8..4, seed in any::<u64>()) {
        let header = FieldHeader::new(w, h, 0.05, -3.0, 2.0);
        let mut s = seed | 1;
        let codes: Vec<u8> = (0..w * h)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s % u64::from(levels)) as u8 * 100
            })
            .collect();
        let mut raw = vec![0u8; header.required_len().unwrap()];
        emit_blob(&header, &codes, &mut raw).unwrap();
        let tiled = tile_blob(&raw).unwrap();
        let v = FieldView::parse(&tiled).unwrap();
        prop_assert_eq!(v.encoding(), ENCODING_TILED);
        prop_assert_eq!(*v.header(), header);
        prop_assert_eq!(every_code(&v), codes);
        // Re-tiling a tiled blob gives the same bytes (the output is canonical).
        prop_assert_eq!(tile_blob(&tiled).unwrap(), tiled);
    }

    /// Small maps of any width and height (so the last row and column of tiles are often
    /// partial) scored from poses all over and around them: the prepared path on the tiled blob
    /// (whose per-beam loop leaves the partial last row of tiles to its slow path) gives the
    /// raw blob's scores bit for bit, and so does the per-pose path.
    #[test]
    fn tiled_scores_equal_raw_on_small_maps(
        w in 1u32..24,
        h in 1u32..24,
        seed in any::<u64>(),
        poses in proptest::collection::vec((-0.3f32..1.5, -0.3f32..1.5, -3.2f32..3.2), 1..8),
    ) {
        let header = FieldHeader::new(w, h, 0.05, 0.0, 0.0);
        let mut s = seed | 1;
        let codes: Vec<u8> = (0..w * h)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s % 256) as u8
            })
            .collect();
        let mut raw = vec![0u8; header.required_len().unwrap()];
        emit_blob(&header, &codes, &mut raw).unwrap();
        let tiled = tile_blob(&raw).unwrap();
        let params = LikelihoodParams::new(0.95, 0.05, 0.05, 2.0).unwrap();
        let fields: Vec<LikelihoodField<'_>> = [&raw[..], &tiled[..]]
            .iter()
            .map(|b| LikelihoodField::new(FieldView::parse(b).unwrap(), params))
            .collect();
        // 24 beams over the full circle, ranges 0.02 … 1.2 m: endpoints on and off every edge.
        let layout = BeamLayout::<24>::uniform(-3.1, 0.26, 24, 2.0, SensorMount::CENTERED).unwrap();
        let ranges: Vec<f32> = (0..24).map(|i| 0.02 + 0.05 * i as f32).collect();
        let scan = Scan::<24>::from_ranges(&ranges).unwrap();
        let prepared: Vec<_> = fields.iter().map(|f| f.prepare(&layout, &scan)).collect();
        for &(x, y, t) in &poses {
            let p = Pose::new(x * w as f32 * 0.05, y * h as f32 * 0.05, t);
            let a = prepared[0].score(&p).log_likelihood;
            let b = prepared[1].score(&p).log_likelihood;
            prop_assert_eq!(a.to_bits(), b.to_bits(), "prepared at {:?}", p);
            let a2 = fields[0].score(&layout, &scan, &p).log_likelihood;
            let b2 = fields[1].score(&layout, &scan, &p).log_likelihood;
            prop_assert_eq!(a2.to_bits(), b2.to_bits(), "per-pose at {:?}", p);
        }
    }
}

fn blob_of(rel: &str) -> Vec<u8> {
    build_blob(&load_map(&host_tests::data_dir().join(rel)).unwrap(), 2.0).unwrap()
}

fn intel_blob() -> Vec<u8> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    std::fs::read(root.join("firmware/assets/intel.bin")).unwrap()
}

/// Every cell, and `distance_m` at points on and off the map, agree between the encodings.
fn same_field(name: &str, raw: &[u8]) -> f64 {
    let tiled = tile_blob(raw).unwrap();
    let (r, t) = (
        FieldView::parse(raw).unwrap(),
        FieldView::parse(&tiled).unwrap(),
    );
    assert_eq!(r.header(), t.header());
    assert_eq!(every_code(&t), r.codes(), "{name}");
    let h = r.header();
    let (w_m, h_m) = (
        h.width as f32 * h.cell_size_m,
        h.height as f32 * h.cell_size_m,
    );
    let mut s = 0x2545_F491_4F6C_DD1Du64;
    for _ in 0..20_000 {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        let fx = (s & 0xFFFF) as f32 / 65_536.0 * 1.2 - 0.1;
        let fy = ((s >> 16) & 0xFFFF) as f32 / 65_536.0 * 1.2 - 0.1;
        let (x, y) = (h.origin_x_m + fx * w_m, h.origin_y_m + fy * h_m);
        assert_eq!(
            r.distance_m(x, y).to_bits(),
            t.distance_m(x, y).to_bits(),
            "{name} ({x}, {y})"
        );
    }
    let bpc = tiled.len() as f64 / (f64::from(h.width) * f64::from(h.height));
    eprintln!(
        "{name}: raw {} bytes, tiled {} bytes ({bpc:.4} bytes/cell, {} distinct tiles)",
        raw.len(),
        tiled.len(),
        t.pool_tiles().unwrap()
    );
    bpc
}

#[test]
fn every_cell_equal_on_the_shared_maps() {
    let tb3 = same_field("turtlebot3", &blob_of("map_turtlebot3_world/map.yaml"));
    let willow = same_field(
        "willow",
        &blob_of("map_willow_garage/willow-full-0.05.yaml"),
    );
    let intel = same_field("intel", &intel_blob());
    // What the encoding is for: Willow Garage (1.10 MB raw) fits an STM32F405's 1 MiB flash
    // with room for the firmware.
    assert!(willow * 1165.0 * 945.0 < 600_000.0, "willow {willow}");
    eprintln!(
        "mean bytes/cell over the three maps: {:.4}",
        (tb3 + willow + intel) / 3.0
    );
}

/// The demo's eight scans at every coarse pose of the demo's grid: prepared, per-pose and
/// fixed-point scores are bit for bit those of the raw blob, and so are the best and fine-best
/// poses; ray casts from the logged pose give the same ranges.
#[test]
fn intel_demo_scores_bit_identical() {
    let raw = intel_blob();
    let tiled = tile_blob(&raw).unwrap();
    let log = CarmenLog::read_path(
        &host_tests::data_dir().join("laser_intel_lab/intel-corrected.log"),
        ReadOptions::default(),
    )
    .unwrap();
    let max_range = log.max_range.value_m().unwrap();
    let params = LikelihoodParams::new(Z_HIT, Z_RAND, SIGMA_HIT_M, max_range).unwrap();
    let fields: Vec<LikelihoodField<'_>> = [&raw[..], &tiled[..]]
        .iter()
        .map(|b| LikelihoodField::new(FieldView::parse(b).unwrap(), params))
        .collect();
    assert_eq!(fields[1].view().encoding(), ENCODING_TILED);
    let fixed: Vec<FixedField<'_>> = fields.iter().map(|f| FixedField::new(f).unwrap()).collect();
    let casters: Vec<RayCaster<'_>> = fields
        .iter()
        .map(|f| RayCaster::new(*f.view()).unwrap())
        .collect();
    let layout: BeamLayout<N> = log.layout_with_mount(SensorMount::CENTERED).unwrap();
    let fl = FixedLayout::new(&layout).unwrap();
    let mut compared = 0usize;
    for &i in SCAN_INDICES.iter() {
        let s = &log.scans[i];
        let scan: Scan<N> = s.to_scan().unwrap();
        let logged = s.pose;
        let prepared: Vec<_> = fields.iter().map(|f| f.prepare(&layout, &scan)).collect();
        let fscans: Vec<_> = fixed
            .iter()
            .map(|f| FixedScan::from_scan(&scan, f))
            .collect();
        let mut best = [(f32::NEG_INFINITY, 0usize); 2];
        for k in 0..COARSE.len() {
            let p = COARSE.pose(&logged, k);
            let a = prepared[0].score(&p).log_likelihood;
            let b = prepared[1].score(&p).log_likelihood;
            assert_eq!(a.to_bits(), b.to_bits(), "scan {i} pose {k}: {a} vs {b}");
            let a2 = fields[0].score(&layout, &scan, &p).log_likelihood;
            let b2 = fields[1].score(&layout, &scan, &p).log_likelihood;
            assert_eq!(
                a2.to_bits(),
                b2.to_bits(),
                "scan {i} pose {k} (per-pose path)"
            );
            let fp = FixedPose::from_pose(&p).unwrap();
            let fa = fixed[0].score_with(&fl, &fscans[0], &fp, |_, _| {});
            let fb = fixed[1].score_with(&fl, &fscans[1], &fp, |_, _| {});
            assert_eq!(fa, fb, "scan {i} pose {k} (fixed point)");
            for (j, ll) in [a, b].into_iter().enumerate() {
                if ll > best[j].0 {
                    best[j] = (ll, k);
                }
            }
            compared += 1;
        }
        assert_eq!(best[0].1, best[1].1, "scan {i}: best pose");
        assert_eq!(
            fine_search(&prepared[0], &logged),
            fine_search(&prepared[1], &logged),
            "scan {i}: fine best pose"
        );
        for b in layout.beams() {
            let a = logged.theta_rad + b.bearing_rad;
            let (ra, rb) = (
                casters[0].cast(logged.x_m, logged.y_m, a, max_range),
                casters[1].cast(logged.x_m, logged.y_m, a, max_range),
            );
            assert_eq!(ra.to_bits(), rb.to_bits(), "scan {i}: cast at {a} rad");
        }
    }
    assert_eq!(compared, SCAN_INDICES.len() * COARSE.len());
}

/// [`small_tiled`] clamped at code 100 (byte 33 = 100; every pool code at most 100).
fn small_clamped() -> Vec<u8> {
    tile_blob_clamped(&small_tiled(), Some(100.0 * 2.0 / 255.0)).unwrap()
}

/// A small tiled blob with repeated tiles and a partial last row and column of tiles.
fn small_tiled() -> Vec<u8> {
    let header = FieldHeader::new(10, 7, 0.05, -1.25, 3.5);
    let codes: Vec<u8> = (0..70u32)
        .map(|i| if (i % 10) < 4 { 255 } else { (i * 7) as u8 })
        .collect();
    let mut raw = vec![0u8; header.required_len().unwrap()];
    emit_blob(&header, &codes, &mut raw).unwrap();
    tile_blob(&raw).unwrap()
}

/// Every lookup a caller can make on an accepted view, on and off the map: must not panic.
fn probe_all(v: &FieldView<'_>) -> u64 {
    let mut acc = 0u64;
    for iy in 0..v.height() + 2 {
        for ix in 0..v.width() + 2 {
            acc += u64::from(v.code(ix, iy).unwrap_or(0));
        }
    }
    let h = v.header();
    let params = LikelihoodParams::amcl_defaults(10.0).unwrap();
    let lf = LikelihoodField::new(*v, params);
    let layout = BeamLayout::<8>::uniform(-1.0, 0.3, 8, 10.0, SensorMount::CENTERED).unwrap();
    let scan = Scan::<8>::from_ranges(&[0.0, 0.1, 0.2, 0.3, 9.0, 0.05, 0.15, 5.0]).unwrap();
    let prepared = lf.prepare(&layout, &scan);
    for k in 0..20 {
        let p = Pose::new(
            h.origin_x_m + 0.03 * k as f32,
            h.origin_y_m + 0.02 * k as f32,
            0.3 * k as f32,
        );
        acc += prepared.score(&p).log_likelihood.to_bits() as u64;
        acc += lf.score(&layout, &scan, &p).log_likelihood.to_bits() as u64;
        acc += v.distance_m(p.x_m, p.y_m).to_bits() as u64;
    }
    acc
}

#[test]
fn every_truncation_is_an_error() {
    for blob in [small_tiled(), small_clamped()] {
        truncations(&blob);
    }
    assert_eq!(small_clamped()[33], 100);
}

fn truncations(blob: &[u8]) {
    assert!(FieldView::parse(blob).is_ok());
    for n in 0..blob.len() {
        assert_eq!(
            FieldView::parse(&blob[..n]).err(),
            Some(BlobError::Truncated),
            "length {n}"
        );
    }
    let mut longer = blob.to_vec();
    longer.push(0);
    assert_eq!(
        FieldView::parse(&longer).err(),
        Some(BlobError::TrailingBytes)
    );
}

#[test]
fn every_single_bit_flip_is_an_error() {
    for blob in [small_tiled(), small_clamped()] {
        for bit in 0..blob.len() * 8 {
            let mut b = blob.clone();
            b[bit / 8] ^= 1 << (bit % 8);
            assert!(FieldView::parse(&b).is_err(), "flip of bit {bit} accepted");
        }
    }
}

/// The checksums recomputed after each flip: the parser's structural checks must catch it, or
/// the view it accepts must answer every lookup without panicking (a flipped code in the pool
/// is a valid, different field).
#[test]
fn every_resealed_bit_flip_is_typed_or_safe() {
    let mut kinds = std::collections::BTreeMap::<String, usize>::new();
    for blob in [small_tiled(), small_clamped()] {
        resealed_flips(&blob, &mut kinds);
    }
    for k in [
        "BadTileTable",
        "TileIndexOutOfRange",
        "PayloadLengthMismatch",
        "BadClamp",
        "accepted",
    ] {
        assert!(kinds.contains_key(k), "{k} never seen: {kinds:?}");
    }
    eprintln!("{kinds:?}");
}

fn resealed_flips(blob: &[u8], kinds: &mut std::collections::BTreeMap<String, usize>) {
    for bit in 0..(blob.len() - 48) * 8 + 40 * 8 {
        // Header bytes 0..40 and the payload; the CRC fields themselves are recomputed.
        let byte = if bit < 320 {
            bit / 8
        } else {
            48 + (bit - 320) / 8
        };
        let mut b = blob.to_vec();
        b[byte] ^= 1 << (bit % 8);
        reseal(&mut b);
        let r = std::panic::catch_unwind(|| match FieldView::parse(&b) {
            Ok(v) => {
                probe_all(&v);
                "accepted".to_string()
            }
            Err(e) => format!("{e:?}"),
        });
        let k = r.unwrap_or_else(|_| panic!("panic on resealed flip of byte {byte} bit {bit}"));
        *kinds.entry(k).or_default() += 1;
    }
}
