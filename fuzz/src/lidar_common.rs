//! Shared by the LiDAR fuzz targets: turns fuzz bytes into a stream
//! of valid frames (checksums recomputed, so mutations reach the frame contents and the
//! assembler) interleaved with raw bytes, then checks what every decoder must guarantee.

use beamfield::lidar::{AssemblerConfig, DecoderStats, LidarPoint, ScanAssembler, StreamDecoder};
use beamfield::{BeamLayout, SensorMount};

/// Splits `data` into segments: a tag byte, then either a raw run (tag % 4 == 0, length from the
/// tag) or `frame_len` bytes handed to `frame` (which returns a whole valid frame).
pub fn build_stream(
    data: &[u8],
    field_len: usize,
    mut frame: impl FnMut(&[u8]) -> Vec<u8>,
) -> Vec<u8> {
    let mut out = Vec::new();
    let mut rest = data;
    while let Some((&tag, tail)) = rest.split_first() {
        if tag % 4 == 0 {
            let n = usize::from(tag / 4).min(tail.len());
            out.extend_from_slice(&tail[..n]);
            rest = &tail[n..];
        } else {
            let n = field_len.min(tail.len());
            let mut f = frame(&tail[..n]);
            // tag % 4 == 3: cut the frame short (a lost tail).
            if tag % 4 == 3 && f.len() > 1 {
                f.truncate(usize::from(tag) % f.len());
            }
            out.extend_from_slice(&f);
            rest = &tail[n..];
        }
    }
    out
}

/// Feeds `stream` in pieces whose sizes come from `sizes`, through the decoder and two
/// assemblers (a full turn and a front half), and checks the invariants.
pub fn check<D: StreamDecoder>(
    mut decoder: D,
    stream: &[u8],
    sizes: &[u8],
    points_per_frame: u32,
    accounted: impl Fn(&D, DecoderStats) -> usize,
) {
    let full = BeamLayout::<360>::uniform(0.0, 1f32.to_radians(), 360, 20.0, SensorMount::CENTERED)
        .expect("layout");
    let front = BeamLayout::<360>::uniform(
        -core::f32::consts::FRAC_PI_2,
        0.5f32.to_radians(),
        360,
        20.0,
        SensorMount::CENTERED,
    )
    .expect("layout");
    let mut a = ScanAssembler::new(&full, AssemblerConfig::for_layout(&full)).expect("asm");
    let mut b = ScanAssembler::new(&front, AssemblerConfig::for_layout(&front)).expect("asm");
    let mut emitted = 0u32;
    let mut at = 0usize;
    let mut k = 0usize;
    while at < stream.len() {
        let n = usize::from(*sizes.get(k % sizes.len().max(1)).unwrap_or(&64)).max(1);
        let end = (at + n).min(stream.len());
        for &byte in &stream[at..end] {
            decoder.push_byte(byte, &mut |p: LidarPoint| {
                emitted += 1;
                assert!((0.0..360.0).contains(&p.angle_cw_deg), "{p:?}");
                assert!(p.range_m.is_finite() && p.range_m >= 0.0, "{p:?}");
                for asm in [&mut a, &mut b] {
                    if let Some(scan) = asm.push(p) {
                        assert_eq!(scan.len(), 360);
                        assert!(scan
                            .ranges_m()
                            .iter()
                            .all(|r| r.is_nan() || (*r >= 0.0 && *r <= 20.0)));
                    }
                }
            });
        }
        at = end;
        k += 1;
    }
    let s = decoder.stats();
    assert_eq!(s.bytes as usize, stream.len());
    assert_eq!(s.points, emitted);
    if points_per_frame > 0 {
        assert_eq!(s.points % points_per_frame, 0);
    }
    assert_eq!(accounted(&decoder, s), stream.len());
    for asm in [&a, &b] {
        let t = asm.stats();
        assert_eq!(t.points, emitted);
        assert_eq!(
            t.points,
            t.accepted
                + t.flagged_invalid
                + t.out_of_range
                + t.low_quality
                + t.bad_angle
                + t.outside_layout
        );
    }
}

/// For the LD06 target: when the top bit of the fuzzed speed's high byte is set (a speed of
/// 32,768 °/s or more, which the plausibility check rejects anyway), pins the frame's fields
/// (`fields` = frame bytes 2..46) to a plausible frame: speed into 1,800–4,680 °/s, start angle
/// below 36,000, end angle within `Ld06Frame::max_span_cdeg` of it. The other half of the frames
/// keep their random fields, so the implausible and out-of-range branches are reached too.
#[allow(dead_code)] // only the LD06 target calls it
pub fn ld06_pin_plausible(fields: &mut [u8]) {
    use beamfield::lidar::ld06::{
        Ld06Frame, FULL_TURN_CDEG, MAX_SPEED_DEG_PER_S, MIN_SPEED_DEG_PER_S,
    };
    if fields.len() < 42 || fields[1] & 0x80 == 0 {
        return;
    }
    let le = |i: usize| u16::from_le_bytes([fields[i], fields[i + 1]]);
    let range = MAX_SPEED_DEG_PER_S - MIN_SPEED_DEG_PER_S + 1;
    let speed = MIN_SPEED_DEG_PER_S + (le(0) & 0x7fff) % range;
    let start = le(2) % FULL_TURN_CDEG;
    let span = (u32::from(le(40)) % (Ld06Frame::max_span_cdeg(speed) + 1)) as u16;
    let end = (start + span) % FULL_TURN_CDEG;
    fields[0..2].copy_from_slice(&speed.to_le_bytes());
    fields[2..4].copy_from_slice(&start.to_le_bytes());
    fields[40..42].copy_from_slice(&end.to_le_bytes());
}
