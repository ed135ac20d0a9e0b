//! Unit tests: binning, field of view, stopped motor, lost data across the wrap, rejected
//! layouts.

use super::*;
use crate::pose::SensorMount;

fn pt(angle_cw_deg: f32, range_m: f32) -> LidarPoint {
    LidarPoint {
        angle_cw_deg,
        range_m,
        quality: 100,
        valid: true,
        timestamp_ms: None,
    }
}

fn layout360() -> BeamLayout<360> {
    full_turn_layout(360, 12.0, SensorMount::CENTERED).unwrap()
}

#[test]
fn clockwise_points_land_on_counter_clockwise_beams() {
    let layout = layout360();
    let mut a = ScanAssembler::new(&layout, AssemblerConfig::for_layout(&layout)).unwrap();
    // CW 90° is bearing −90° = 270° CCW → beam 270. CW 1° → beam 359. CW 0 → beam 0.
    assert!(a.push(pt(0.0, 1.0)).is_none());
    assert!(a.push(pt(1.0, 2.0)).is_none());
    assert!(a.push(pt(90.0, 3.0)).is_none());
    assert!(a.push(pt(180.0, 5.0)).is_none());
    assert!(a.push(pt(270.0, 6.0)).is_none());
    assert!(a.push(pt(359.6, 4.0)).is_none()); // 0.4° CCW: beam 0 would be nearer...
    let scan = a.push(pt(0.5, 9.0)).expect("wrap").clone();
    let r = scan.ranges_m();
    assert_eq!(r.len(), 360);
    assert_eq!(r[0], 1.0); // ...but the point exactly on beam 0 wins
    assert_eq!(r[359], 2.0);
    assert_eq!(r[270], 3.0);
    assert!(r[1].is_nan() && r[100].is_nan());
    let s = a.stats();
    assert_eq!(r[180], 5.0);
    assert_eq!(r[90], 6.0);
    assert_eq!((s.accepted, s.replaced, s.revolutions), (7, 1, 1));
    assert_eq!(a.revolution().filled, 5);
    assert_eq!(a.revolution().points, 6);
}

#[test]
fn half_layout_and_out_of_view_points() {
    // The Intel/CARMEN layout: −90° .. +89°, 1° apart.
    let layout = BeamLayout::<180>::uniform(
        -core::f32::consts::FRAC_PI_2,
        1f32.to_radians(),
        180,
        50.0,
        SensorMount::CENTERED,
    )
    .unwrap();
    let mut a = ScanAssembler::new(&layout, AssemblerConfig::for_layout(&layout)).unwrap();
    a.push(pt(90.0, 1.0)); // bearing −90 → beam 0
    a.push(pt(271.0, 2.0)); // bearing −271 = +89 → beam 179
    a.push(pt(180.0, 3.0)); // behind: outside
    a.push(pt(90.4, 4.0)); // bearing −90.4: 0.4 step below beam 0 → beam 0, farther
    let scan = a.finish().unwrap();
    assert_eq!(scan.ranges_m()[0], 1.0);
    assert_eq!(scan.ranges_m()[179], 2.0);
    assert_eq!(a.stats().outside_layout, 1);
    assert_eq!(a.stats().replaced, 1);
}

#[test]
fn stopped_motor_never_emits_and_thresholds_count() {
    let layout = layout360();
    let cfg = AssemblerConfig {
        min_range_m: 0.1,
        max_range_m: 5.0,
        min_quality: 10,
        timestamp_wrap_ms: 0,
        sensor_timestamps: true,
    };
    let mut a = ScanAssembler::new(&layout, cfg).unwrap();
    for i in 0..100_000 {
        let mut p = pt(42.0 + (i % 3) as f32 * 0.01, 1.0);
        match i % 5 {
            0 => p.valid = false,
            1 => p.range_m = 0.05,
            2 => p.range_m = 6.0,
            3 => p.quality = 9,
            _ => {}
        }
        assert!(a.push(p).is_none());
    }
    assert!(a.push(pt(f32::NAN, 1.0)).is_none());
    assert!(a.push(pt(360.0, 1.0)).is_none());
    let s = a.stats();
    assert_eq!(s.revolutions, 0);
    assert_eq!(s.flagged_invalid, 20_000);
    assert_eq!(s.out_of_range, 40_000);
    assert_eq!(s.low_quality, 20_000);
    assert_eq!(s.accepted, 20_000);
    assert_eq!(s.bad_angle, 2);
    assert_eq!(a.pending_filled(), 1);
}

/// A 10 Hz rotor (3.6°/ms) seen through points 1° apart stamped with the time they were
/// taken; `lost` is a range of point indices that never arrive.
fn rotor(
    a: &mut ScanAssembler<360>,
    points: core::ops::Range<u32>,
    lost: core::ops::Range<u32>,
) -> Vec<(u32, Revolution, Vec<f32>)> {
    let mut out = Vec::new();
    for k in points {
        if lost.contains(&k) {
            continue;
        }
        let p = LidarPoint {
            angle_cw_deg: (k % 360) as f32,
            range_m: 1.0 + (k / 360) as f32, // the revolution's number, in metres
            quality: 1,
            valid: true,
            timestamp_ms: Some(((k as f32 / 3.6).round() as u32 % 30_000) as u16),
        };
        if a.push(p).is_some() {
            out.push((k, a.revolution(), a.scan().ranges_m().to_vec()));
        }
    }
    out
}

#[test]
fn data_lost_across_the_wrap_never_mixes_revolutions() {
    let layout = layout360();
    let mut a = ScanAssembler::new(&layout, AssemblerConfig::for_layout(&layout)).unwrap();
    // Revolutions 0..3 whole; then points 3·360+170 .. 4·360+250 are lost: the angle goes
    // from 169° to 250°, which looks like a forward step within one turn.
    let got = rotor(&mut a, 0..6 * 360, 3 * 360 + 170..4 * 360 + 250);
    let ks: Vec<u32> = got.iter().map(|g| g.0).collect();
    assert_eq!(ks, vec![360, 720, 1080, 4 * 360 + 250, 5 * 360]);
    for (_, rev, ranges) in &got {
        let finite: Vec<f32> = ranges.iter().copied().filter(|r| r.is_finite()).collect();
        assert!(!finite.is_empty());
        assert!(
            finite.iter().all(|&r| r == finite[0]),
            "mixed revolutions in {rev:?}"
        );
    }
    // The revolution cut short by the loss holds its 170 points.
    assert_eq!(got[3].1.filled, 170);
    assert_eq!(got[3].1.points, 170);
    assert_eq!(a.stats().missed_revolutions, 0);
    // Whole turns lost are counted.
    let mut b = ScanAssembler::new(&layout, AssemblerConfig::for_layout(&layout)).unwrap();
    let got = rotor(&mut b, 0..9 * 360, 2 * 360 + 100..5 * 360 + 90);
    assert_eq!(
        got.iter().map(|g| g.0).collect::<Vec<_>>(),
        vec![360, 720, 5 * 360 + 90, 6 * 360, 7 * 360, 8 * 360]
    );
    assert_eq!(b.stats().missed_revolutions, 2);
}

#[test]
fn rejects_bad_layouts_and_thresholds() {
    let m = SensorMount::CENTERED;
    let l = BeamLayout::<3>::from_bearings(&[0.0, 0.1, 0.3], 5.0, m).unwrap();
    assert_eq!(
        ScanAssembler::new(&l, AssemblerConfig::for_layout(&l)).err(),
        Some(AssemblerError::NotUniform(2))
    );
    let l = BeamLayout::<3>::from_bearings(&[0.0, -0.1, -0.2], 5.0, m).unwrap();
    assert!(ScanAssembler::new(&l, AssemblerConfig::for_layout(&l)).is_err());
    let l = BeamLayout::<3>::from_bearings(&[0.0, 3.0, 6.0], 5.0, m).unwrap();
    assert_eq!(
        ScanAssembler::new(&l, AssemblerConfig::for_layout(&l)).err(),
        Some(AssemblerError::MoreThanOneTurn)
    );
    let mut c = AssemblerConfig::for_layout(&l);
    c.min_range_m = f32::NAN;
    let l = layout360();
    assert_eq!(
        ScanAssembler::new(&l, c).err(),
        Some(AssemblerError::BadRange)
    );
}
