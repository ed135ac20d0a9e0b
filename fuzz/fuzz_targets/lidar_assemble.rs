//! Fuzzes the scan assembler with arbitrary points (any f32 bits for angles and ranges, any
//! flags and timestamps), on layouts built from the fuzz bytes too. Checks: no panic, every
//! emitted scan has the layout's length and holds only NaN or ranges that were pushed and
//! accepted during that revolution, the counters add up.
//!
//! Run: `cargo +nightly fuzz run lidar_assemble` from the repository root.

#![no_main]

use beamfield::lidar::{AssemblerConfig, LidarPoint, ScanAssembler};
use beamfield::{BeamLayout, SensorMount};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() < 8 {
        return;
    }
    let beams = 1 + usize::from(data[0]) % 360;
    let step_deg = 360.0 / beams as f32 * (0.25 + f32::from(data[1]) / 340.0);
    let first_deg = f32::from(i8::from_le_bytes([data[2]])) * 2.0;
    let Ok(layout) = BeamLayout::<360>::uniform(
        first_deg.to_radians(),
        step_deg.to_radians(),
        beams,
        10.0,
        SensorMount::CENTERED,
    ) else {
        return;
    };
    let cfg = AssemblerConfig {
        min_range_m: f32::from(data[3]) / 100.0,
        max_range_m: 10.0,
        min_quality: u16::from(data[4] % 8),
        timestamp_wrap_ms: u16::from_le_bytes([data[5], data[6]]),
        sensor_timestamps: data[3] % 2 == 0,
    };
    let Ok(mut asm) = ScanAssembler::new(&layout, cfg) else {
        return;
    };
    let mut pushed: Vec<f32> = Vec::new();
    for c in data[7..].chunks_exact(11) {
        let angle = if c[0] & 1 == 0 {
            f32::from(u16::from_le_bytes([c[1], c[2]])) / 65_536.0 * 360.0
        } else {
            f32::from_le_bytes([c[1], c[2], c[3], c[4]])
        };
        let p = LidarPoint {
            angle_cw_deg: angle,
            range_m: f32::from_le_bytes([c[5], c[6], c[7], c[8]]),
            quality: u16::from(c[9] % 16),
            valid: c[0] & 2 == 0,
            timestamp_ms: (c[0] & 4 == 0).then(|| u16::from_le_bytes([c[9], c[10]])),
        };
        if let Some(scan) = asm.push(p) {
            assert_eq!(scan.len(), beams);
            for r in scan.ranges_m() {
                assert!(
                    r.is_nan() || pushed.iter().any(|q| q.to_bits() == r.to_bits()),
                    "{r}"
                );
            }
            // The point that closed the revolution belongs to the next one.
            pushed.clear();
        }
        pushed.push(p.range_m);
    }
    let s = asm.stats();
    assert_eq!(
        s.points,
        s.accepted
            + s.flagged_invalid
            + s.out_of_range
            + s.low_quality
            + s.bad_angle
            + s.outside_layout
    );
    if let Some(scan) = asm.finish() {
        assert_eq!(scan.len(), beams);
    }
});
