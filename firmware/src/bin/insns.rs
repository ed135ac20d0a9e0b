//! Instruction counts: scores a synthetic 360-beam scan with the beam mixture (given z*)
//! between `bench_mark_start`/`bench_mark_end`, after three baselines measured the same way.
//! Run under the QEMU counting plugin by `cargo xtask insns`, which divides by the beam count.
//!
//! Regions, in order, each named right before it is measured (`start_region`, with the names of
//! `beamfield_fixtures::regions::insns`; `cargo xtask insns` takes the counts by name):
//! 0. empty loop: sum the ranges, +∞ read as the max range (the loop and load cost alone);
//! 1. `beamfield::math::ln` of each range (the host bench's baseline);
//! 2. `beamfield::math::exp` of each range;
//! 3. `BeamModel::scan_log_likelihood`: the beam mixture, AMCL default intrinsics, 30 m lidar.
//!
//! Then the likelihood field over the Intel map blob the demo links (`assets/intel.bin`) and
//! the demo's 8 real 180-beam scans (`fixtures/assets/scans.rs`), each at `POSES_PER_SCAN` poses
//! scattered around its logged pose (±25 cm, ±10°):
//! 4. `LikelihoodField::prepare` of the 8 scans (divided by beam slots);
//! 5. empty loop over the prepared endpoints at every pose (the loop and load cost alone);
//! 6. `PreparedScan::score` at every pose (per kept beam, per-pose work included);
//! 7. `PreparedScan::score` of a scan with no kept beam (all max-range) at the same poses:
//!    the per-pose work alone, so `(6 − 7) / beams` is the per-beam cost;
//! 8. `LikelihoodField::score` (the per-pose path) at the same poses, per kept beam;
//! 9. `BeamFieldModel` (the race, docs/race.md): the beam model *with* ray casting through the same
//!    blob, scoring the 8 real scans (1,440 beams) at their logged poses, with the intrinsics EM
//!    fitted on that log (constants in the module [`intel`]).
//!
//!
//! Then the same likelihood field over the same map stored tiled (distance encoding 2,
//! `assets/intel-tiled.bin`: the same codes in deduplicated 4 × 4 tiles), same scans, same poses:
//! 10. `PreparedScan::score` at every pose, tiled blob (per kept beam, per-pose work included);
//! 11. `PreparedScan::score` of the scan with no kept beam, tiled blob (per pose);
//!     so `(10 − 11) / beams` is the per-beam cost on the tiled blob, beside `(6 − 7) / beams`.
//!     The sum must equal region 6's bit for bit (the encoding is lossless).
//!
//! Then the LiDAR stream decoders (`beamfield::lidar`), on streams the library's encoders write
//! (outside the regions) from the 8 real scans, one clockwise revolution of 360 points each,
//! assembled on the scans' own 180-beam layout; all divided by the bytes of the stream:
//! 12. empty loop over the LD06 stream's bytes (the loop and load cost alone);
//! 13. `Ld06Decoder::feed` alone (CRC, 12 points per frame handed to a closure);
//! 14. LD06 decode plus `ScanAssembler::push` of every point (the firmware's sensor path);
//! 15. RPLIDAR decode plus assembly;
//! 16. XV-11 decode plus assembly;
//! 17. YDLIDAR decode (triangulation angle correction) plus assembly.
//!
//! The last lines printed give each region's divisor by name (`insns divisor: NAME N`), which
//! `cargo xtask insns` reads.
#![no_std]
#![no_main]

use beamfield::{
    math, BeamIntrinsics, BeamLayout, BeamModel, FieldView, LikelihoodField, LikelihoodParams,
    Pose, PreparedScan, Scan, SensorMount,
};
use beamfield_firmware::{bench_mark_end, exit, println, start_region, Fixed};
use beamfield_fixtures::regions::insns;
use core::hint::black_box;
use cortex_m_rt::entry;
use panic_semihosting as _;

/// Beams per scan (a common 1° lidar).
pub const BEAMS: usize = 360;
/// The sensor's maximum range, metres.
const MAX_RANGE_M: f32 = 30.0;

/// The demo's real scans (180 beams each) and the log's maximum range.
mod real {
    pub use beamfield_fixtures::demo_scans::{MAX_RANGE_M, SCANS};
    pub use beamfield_fixtures::intel_setup::BEAMS;
}

/// The 5 cm distance field of the Intel map, as the demo links it.
static BLOB: &[u8] = include_bytes!("../../assets/intel.bin");
/// The same field, tiled (distance encoding 2), for regions 10–11.
static BLOB_TILED: &[u8] = include_bytes!("../../assets/intel-tiled.bin");
/// Poses per real scan in regions 4–8.
const POSES_PER_SCAN: usize = 32;
/// Real scans in regions 4–8.
const REAL_SCANS: usize = 8;

/// xorshift32: a deterministic stand-in for a sensor.
struct Rng(u32);
impl Rng {
    fn unit(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        (self.0 >> 8) as f32 / (1u32 << 24) as f32
    }
}

/// A scan with a realistic mix: ~85% hits within ±2σ of the wall, ~8% short readings (clutter
/// before the wall), ~4% max-range (no return), ~3% uniform random.
fn synthetic(rng: &mut Rng, ranges: &mut [f32; BEAMS], z_star: &mut [f32; BEAMS]) {
    for (z, zs) in ranges.iter_mut().zip(z_star.iter_mut()) {
        let wall = 0.5 + 28.5 * rng.unit();
        let kind = rng.unit();
        *zs = wall;
        *z = if kind < 0.85 {
            wall + 0.4 * (rng.unit() - 0.5)
        } else if kind < 0.93 {
            wall * rng.unit()
        } else if kind < 0.97 {
            f32::INFINITY
        } else {
            MAX_RANGE_M * rng.unit()
        };
    }
}

/// One decode-plus-assembly region (14–16): a new decoder of type `D` is fed `stream` and every
/// point it hands out is pushed into a new [`ScanAssembler`](beamfield::lidar::ScanAssembler) on
/// `layout`, all between the region marks. Returns the scans finished and the ranges binned, or
/// `None` when the assembler rejected the layout.
#[inline(always)]
fn decode_assemble_region<D, const N: usize>(
    region: &str,
    stream: &[u8],
    layout: &BeamLayout<N>,
    config: beamfield::lidar::AssemblerConfig,
) -> Option<(u32, u32)>
where
    D: beamfield::lidar::StreamDecoder + Default,
{
    start_region!(region);
    let mut dec = D::default();
    let mut asm = beamfield::lidar::ScanAssembler::new(layout, config).ok()?;
    let mut scans = 0u32;
    dec.feed(stream, |p| {
        if let Some(s) = asm.push(p) {
            black_box(s);
            scans += 1;
        }
    });
    bench_mark_end();
    Some((scans, asm.stats().accepted))
}

/// Regions 12–17: the LiDAR decoders and the assembler, per received byte. Returns the bytes of
/// the four streams, or `None` if an encoder or the layout was rejected. Not inlined.
#[inline(never)]
fn lidar_regions() -> Option<[usize; 4]> {
    use beamfield::lidar::assembler::sample_revolution;
    use beamfield::lidar::ld06::{self, Ld06Decoder, Ld06Sample};
    use beamfield::lidar::rplidar::{self, RplidarDecoder};
    use beamfield::lidar::xv11::{self, Xv11Decoder, Xv11Reading};
    use beamfield::lidar::AssemblerConfig;
    const REVS: usize = REAL_SCANS;
    const POINTS: usize = 360;
    let layout = BeamLayout::<{ real::BEAMS }>::uniform(
        -core::f32::consts::FRAC_PI_2,
        core::f32::consts::PI / real::BEAMS as f32,
        real::BEAMS,
        real::MAX_RANGE_M,
        SensorMount::CENTERED,
    )
    .ok()?;
    let config = AssemblerConfig::for_layout(&layout);
    let mut revs = [[0.0f32; POINTS]; REVS];
    for (rev, s) in revs.iter_mut().zip(real::SCANS.iter()) {
        let scan = Scan::<{ real::BEAMS }>::from_ranges(&s.ranges_m).ok()?;
        sample_revolution(&layout, &scan, rev).ok()?;
    }
    // One buffer, the largest stream (XV-11: 1,980 bytes per revolution).
    let mut buf = [0u8; REVS * xv11::REVOLUTION_LEN];

    // LD06 at 10 Hz.
    let mut n = 0;
    for (k, rev) in revs.iter().enumerate() {
        let samples = rev.map(|r| Ld06Sample::from_range_m(r, 200));
        n += ld06::encode_revolution(&samples, 3600, (k * 100) as u16, buf.get_mut(n..)?).ok()?;
    }
    let ld06_len = n;
    let stream = black_box(buf.get(..n)?);
    start_region!(insns::EMPTY_BYTES.name);
    let mut sum = 0u32;
    for &b in stream {
        sum = sum.wrapping_add(u32::from(b));
    }
    bench_mark_end();
    let sum = black_box(sum);
    start_region!(insns::LD06_DECODE.name);
    let mut dec = Ld06Decoder::new();
    let mut pts = 0u32;
    dec.feed(stream, |p| {
        black_box(p);
        pts += 1;
    });
    bench_mark_end();
    let (ld06_scans, ld06_accepted) = decode_assemble_region::<Ld06Decoder, _>(
        insns::LD06_ASSEMBLE.name,
        stream,
        &layout,
        config,
    )?;

    // RPLIDAR: the scan descriptor, then nodes.
    let mut n = 0;
    buf.get_mut(..rplidar::DESCRIPTOR_LEN)?
        .copy_from_slice(&rplidar::SCAN_DESCRIPTOR);
    n += rplidar::DESCRIPTOR_LEN;
    for rev in &revs {
        n += rplidar::encode_revolution(rev, 47, buf.get_mut(n..)?).ok()?;
    }
    let rp_len = n;
    let stream = black_box(buf.get(..n)?);
    let (rp_scans, rp_accepted) = decode_assemble_region::<RplidarDecoder, _>(
        insns::RPLIDAR_ASSEMBLE.name,
        stream,
        &layout,
        config,
    )?;

    // XV-11 at 300 rpm.
    let mut n = 0;
    for rev in &revs {
        let readings: [Xv11Reading; POINTS] = core::array::from_fn(|a| {
            Xv11Reading::from_range_m(rev.get(a).copied().unwrap_or(f32::NAN), 1000)
        });
        n += xv11::encode_revolution(&readings, 300 * 64, buf.get_mut(n..)?).ok()?;
    }
    let xv_len = n;
    let stream = black_box(buf.get(..n)?);
    let (xv_scans, xv_accepted) = decode_assemble_region::<Xv11Decoder, _>(
        insns::XV11_ASSEMBLE.name,
        stream,
        &layout,
        config,
    )?;

    // YDLIDAR (region 17): a zero packet and packets of 40 samples per revolution, at uniform
    // rotor angles; the decoder applies the X4's triangulation correction (an `atanf` per
    // measured sample), so the points land about 7° before their rotor angle.
    let mut n = 0;
    for rev in &revs {
        let q2 = rev.map(beamfield::lidar::ydlidar::distance_q2_from_range_m);
        n += beamfield::lidar::ydlidar::encode_revolution(&q2, 40, 100, buf.get_mut(n..)?).ok()?;
    }
    let yd_len = n;
    let stream = black_box(buf.get(..n)?);
    let (yd_scans, yd_accepted) = decode_assemble_region::<
        beamfield::lidar::ydlidar::YdlidarDecoder,
        _,
    >(insns::YDLIDAR_ASSEMBLE.name, stream, &layout, config)?;

    println!(
        "insns: lidar: {} real scans as revolutions of {} points; byte sum {}; ld06 {} bytes, {} points, {} scans, {} ranges binned; rplidar {} bytes, {} scans, {} binned; xv11 {} bytes, {} scans, {} binned; ydlidar {} bytes, {} scans, {} binned",
        REVS, POINTS, sum, ld06_len, pts, ld06_scans, ld06_accepted, rp_len, rp_scans, rp_accepted, xv_len, xv_scans, xv_accepted, yd_len, yd_scans, yd_accepted
    );
    // Every revolution but the last (no wrap after it) is emitted, and every range a protocol's
    // distance field carries (counted here from the samples) was binned.
    let carried = |unit_per_m: f32, max_units: f32| {
        revs.iter()
            .flatten()
            .filter(|&&r| (0.5..max_units + 0.5).contains(&(r * unit_per_m)))
            .count() as u32
    };
    let ok = pts as usize == REVS * POINTS
        && [ld06_scans, rp_scans, xv_scans] == [REVS as u32 - 1; 3]
        && ld06_accepted == carried(1000.0, 65_535.0)
        && rp_accepted == carried(4000.0, 65_535.0)
        && xv_accepted == carried(1000.0, 16_383.0)
        // YDLIDAR: the corrected points cross 0° about 7° into each revolution (so the first,
        // partial one is emitted too), and the last packet waits for a header that never comes;
        // every carried range is binned or lands on an already filled beam, at most.
        && (REVS as u32 - 1..=REVS as u32).contains(&yd_scans)
        && yd_accepted > 0
        && yd_accepted <= carried(4000.0, 65_535.0);
    ok.then_some([ld06_len, rp_len, xv_len, yd_len])
}

/// Region 9's beam model: the intrinsics fitted on the Intel log (the scans and the blob are
/// the ones of [`real`] and [`BLOB`]).
mod intel {
    /// `[z_hit, z_short, z_max, z_rand]`, σ_hit (m), λ_short (1/m): `beamfield fit` on the log
    /// (docs/beam-on-device.md, truncated update).
    pub const WEIGHTS: [f32; 4] = [0.878328, 0.057550, 0.023807, 0.040316];
    /// σ_hit, metres.
    pub const SIGMA_HIT_M: f32 = 0.058836;
    /// λ_short, 1/m.
    pub const LAMBDA_SHORT: f32 = 0.070119;
}

/// Region 9: scores every embedded real scan at its logged pose with the beam model and
/// on-device ray casting, between the markers. Returns the summed log-likelihood and the beams
/// scored, or `None` if the blob, intrinsics or a scan were rejected (reported by the caller).
/// Not inlined, to keep its code apart from `main`'s regions.
#[inline(never)]
fn beam_model_with_ray_casting() -> Option<(f32, usize)> {
    use beamfield::{
        BeamFieldModel, BeamLayout, FieldView, Pose, RayCaster, SensorModel, SensorMount,
    };
    let caster = RayCaster::new(FieldView::parse(BLOB).ok()?).ok()?;
    let s: f32 = intel::WEIGHTS.iter().sum();
    let w = intel::WEIGHTS.map(|x| x / s);
    let intr = BeamIntrinsics::new(
        w[0],
        w[1],
        w[2],
        w[3],
        intel::SIGMA_HIT_M,
        intel::LAMBDA_SHORT,
        real::MAX_RANGE_M,
    )
    .ok()?;
    let model = BeamFieldModel::new(BeamModel::new(intr), caster);
    // CARMEN FLASER: beam i at −90° + i·1°; the logged poses are the laser's (no mount).
    let layout = BeamLayout::<{ real::BEAMS }>::uniform(
        -core::f32::consts::FRAC_PI_2,
        core::f32::consts::PI / real::BEAMS as f32,
        real::BEAMS,
        real::MAX_RANGE_M,
        SensorMount::CENTERED,
    )
    .ok()?;
    let mut scans = [const { None }; real::SCANS.len()];
    for (slot, d) in scans.iter_mut().zip(real::SCANS.iter()) {
        let scan = Scan::<{ real::BEAMS }>::from_ranges(&d.ranges_m).ok()?;
        *slot = Some((scan, Pose::new(d.pose[0], d.pose[1], d.pose[2])));
    }
    let scans = black_box(&scans);

    start_region!(insns::BEAM_RAY_CAST.name);
    let mut sum = 0.0f32;
    let mut scored = 0usize;
    for (scan, pose) in scans.iter().flatten() {
        let score = model.score(&layout, scan, pose);
        sum += score.log_likelihood;
        scored += usize::from(score.scored);
    }
    bench_mark_end();
    Some((sum, scored))
}

/// Regions 10 and 11: [`PreparedScan::score`] over the tiled blob at the same poses as region 6,
/// then the no-beam scan at the same poses. Returns both sums, or `None` if the blob is
/// rejected. Not inlined, to keep its code apart from `main`'s regions.
#[inline(never)]
fn tiled_regions(
    layout: &BeamLayout<{ real::BEAMS }>,
    scans: &[Scan<{ real::BEAMS }>; REAL_SCANS],
    poses: &[[Pose; POSES_PER_SCAN]; REAL_SCANS],
    params: LikelihoodParams,
) -> Option<(f32, f32)> {
    let field = LikelihoodField::new(FieldView::parse(BLOB_TILED).ok()?, params);
    let no_return = Scan::<{ real::BEAMS }>::from_ranges(&[f32::INFINITY; real::BEAMS]).ok()?;
    let empty_prep = field.prepare(layout, &no_return);
    let prepared: [PreparedScan<'_, { real::BEAMS }>; REAL_SCANS] =
        core::array::from_fn(|i| field.prepare(layout, black_box(&scans[i % REAL_SCANS])));

    start_region!(insns::LF_PREPARED_TILED.name);
    let mut sum = 0.0f32;
    for (prep, ps) in prepared.iter().zip(poses) {
        for p in ps {
            sum += prep.score(black_box(p)).log_likelihood;
        }
    }
    bench_mark_end();

    start_region!(insns::LF_PREPARED_NO_BEAMS_TILED.name);
    let mut overhead = 0.0f32;
    for ps in poses {
        for p in ps {
            overhead += empty_prep.score(black_box(p)).log_likelihood;
        }
    }
    bench_mark_end();
    Some((sum, overhead))
}

#[entry]
fn main() -> ! {
    let mut rng = Rng(0x1234_5678);
    let mut ranges = [0.0f32; BEAMS];
    let mut z_star = [0.0f32; BEAMS];
    synthetic(&mut rng, &mut ranges, &mut z_star);
    let Ok(scan) = Scan::<BEAMS>::from_ranges(&ranges) else {
        println!("insns: scan rejected");
        exit(false)
    };
    let Ok(intr) = BeamIntrinsics::amcl_defaults(MAX_RANGE_M) else {
        println!("insns: intrinsics rejected");
        exit(false)
    };
    let model = BeamModel::new(intr);
    let ranges = black_box(scan.ranges_m());
    let finite = |z: f32| if z < MAX_RANGE_M { z } else { MAX_RANGE_M };

    start_region!(insns::EMPTY_LOOP.name);
    let mut sum = 0.0f32;
    for &z in ranges {
        sum += black_box(finite(z));
    }
    bench_mark_end();
    let empty = sum;

    start_region!(insns::LN.name);
    let mut sum = 0.0f32;
    for &z in ranges {
        sum += math::ln(black_box(finite(z)));
    }
    bench_mark_end();
    let ln_sum = sum;

    start_region!(insns::EXP.name);
    let mut sum = 0.0f32;
    for &z in ranges {
        sum += math::exp(-black_box(finite(z)));
    }
    bench_mark_end();
    let exp_sum = sum;

    start_region!(insns::BEAM_MIXTURE.name);
    let score = model.scan_log_likelihood(black_box(&scan), black_box(&z_star[..]));
    bench_mark_end();

    // The likelihood field on the real map and scans.
    let Ok(view) = FieldView::parse(BLOB) else {
        println!("insns: map blob rejected");
        exit(false)
    };
    let Ok(params) = LikelihoodParams::new(0.95, 0.05, 0.0588, real::MAX_RANGE_M) else {
        println!("insns: likelihood parameters rejected");
        exit(false)
    };
    let field = LikelihoodField::new(view, params);
    let Ok(layout) = BeamLayout::<{ real::BEAMS }>::uniform(
        -core::f32::consts::FRAC_PI_2,
        core::f32::consts::PI / real::BEAMS as f32,
        real::BEAMS,
        real::MAX_RANGE_M,
        SensorMount::CENTERED,
    ) else {
        println!("insns: layout rejected");
        exit(false)
    };
    let mut scans: [Scan<{ real::BEAMS }>; REAL_SCANS] = Default::default();
    let mut poses = [[Pose::default(); POSES_PER_SCAN]; REAL_SCANS];
    for ((demo, scan), ps) in real::SCANS.iter().zip(&mut scans).zip(&mut poses) {
        let Ok(s) = Scan::from_ranges(&demo.ranges_m) else {
            println!("insns: scan {} rejected", demo.log_index);
            exit(false)
        };
        *scan = s;
        for p in ps.iter_mut() {
            *p = Pose::new(
                demo.pose[0] + 0.5 * (rng.unit() - 0.5),
                demo.pose[1] + 0.5 * (rng.unit() - 0.5),
                demo.pose[2] + 0.35 * (rng.unit() - 0.5),
            );
        }
    }
    let Ok(no_return) = Scan::<{ real::BEAMS }>::from_ranges(&[f32::INFINITY; real::BEAMS]) else {
        println!("insns: scan rejected");
        exit(false)
    };
    let empty_prep = field.prepare(&layout, &no_return);

    start_region!(insns::LF_PREPARE.name);
    let prepared: [PreparedScan<'_, { real::BEAMS }>; REAL_SCANS] =
        core::array::from_fn(|i| field.prepare(&layout, black_box(&scans[i % REAL_SCANS])));
    bench_mark_end();
    let kept: usize = prepared.iter().map(PreparedScan::len).sum();
    let evaluations = kept * POSES_PER_SCAN;

    start_region!(insns::EMPTY_PREPARED.name);
    let mut acc = 0i32;
    for (prep, ps) in prepared.iter().zip(&poses) {
        for p in ps {
            let _ = black_box(p);
            for e in prep.endpoints() {
                acc = acc.wrapping_add(e[0] ^ e[1]);
            }
        }
    }
    bench_mark_end();
    let empty_real = black_box(acc);

    start_region!(insns::LF_PREPARED.name);
    let mut lf_sum = 0.0f32;
    for (prep, ps) in prepared.iter().zip(&poses) {
        for p in ps {
            lf_sum += prep.score(black_box(p)).log_likelihood;
        }
    }
    bench_mark_end();

    start_region!(insns::LF_PREPARED_NO_BEAMS.name);
    let mut overhead_sum = 0.0f32;
    for ps in &poses {
        for p in ps {
            overhead_sum += empty_prep.score(black_box(p)).log_likelihood;
        }
    }
    bench_mark_end();

    start_region!(insns::LF_PER_POSE.name);
    let mut old_sum = 0.0f32;
    for (scan, ps) in scans.iter().zip(&poses) {
        for p in ps {
            old_sum += field
                .score(&layout, black_box(scan), black_box(p))
                .log_likelihood;
        }
    }
    bench_mark_end();

    let fixed_point_poses = prepared
        .iter()
        .zip(&poses)
        .map(|(prep, ps)| ps.iter().filter(|p| prep.uses_fixed_point(p)).count())
        .sum::<usize>();
    println!(
        "insns: likelihood field on the Intel map: {} real scans x {} poses, {} kept beams of {} ({} beam evaluations; {} poses on the fixed-point path); prepared sum {}, per-pose path sum {}, empty-scan sum {}, empty loop {}",
        REAL_SCANS,
        POSES_PER_SCAN,
        kept,
        REAL_SCANS * real::BEAMS,
        evaluations,
        fixed_point_poses,
        Fixed::new(f64::from(lf_sum), 3),
        Fixed::new(f64::from(old_sum), 3),
        Fixed::new(f64::from(overhead_sum), 1),
        empty_real
    );

    println!(
        "insns: {} beams; regions: 0 empty loop (sum {}), 1 ln per beam (sum {}), 2 exp per beam (sum {}), 3 beam mixture (log-likelihood {}, {} scored, {} invalid)",
        BEAMS,
        Fixed::new(f64::from(empty), 3),
        Fixed::new(f64::from(ln_sum), 3),
        Fixed::new(f64::from(exp_sum), 6),
        Fixed::new(f64::from(score.log_likelihood), 3),
        score.scored,
        score.invalid
    );
    // Region 9 (the race, docs/race.md): the beam model with ray casting on the real Intel map.
    let Some((race_ll, race_scored)) = beam_model_with_ray_casting() else {
        println!("insns: region 9: Intel blob, intrinsics or scans rejected");
        exit(false)
    };
    println!(
        "insns: region 9 beam model with ray casting, Intel map: {} scans x {} beams, log-likelihood {}, {} scored",
        real::SCANS.len(),
        real::BEAMS,
        Fixed::new(f64::from(race_ll), 3),
        race_scored
    );
    let race_ok = race_ll.is_finite() && race_scored == real::SCANS.len() * real::BEAMS;
    // Regions 10–11: the prepared path over the tiled blob, same scans and poses.
    let Some((tiled_sum, tiled_overhead)) = tiled_regions(&layout, &scans, &poses, params) else {
        println!("insns: tiled blob rejected");
        exit(false)
    };
    let tiled_ok = tiled_sum.to_bits() == lf_sum.to_bits() && tiled_overhead == 0.0;
    println!(
        "insns: regions 10-11 tiled blob ({} bytes, raw {}): prepared sum {} ({}), empty-scan sum {}",
        BLOB_TILED.len(),
        BLOB.len(),
        Fixed::new(f64::from(tiled_sum), 3),
        if tiled_ok { "bit for bit the raw blob's" } else { "DIFFERS from the raw blob's" },
        Fixed::new(f64::from(tiled_overhead), 1)
    );
    // Regions 12–17: the LiDAR stream decoders.
    let Some([ld06_len, rp_len, xv_len, yd_len]) = lidar_regions() else {
        println!("insns: regions 12-17: a LiDAR encoder, layout or decoded count was wrong");
        exit(false)
    };
    // Divisors of each region for `cargo xtask insns`, by name: beams, beam slots, beam
    // evaluations, poses, bytes.
    let divisors = [
        (insns::EMPTY_LOOP.name, BEAMS),
        (insns::LN.name, BEAMS),
        (insns::EXP.name, BEAMS),
        (insns::BEAM_MIXTURE.name, BEAMS),
        (insns::LF_PREPARE.name, REAL_SCANS * real::BEAMS),
        (insns::EMPTY_PREPARED.name, evaluations),
        (insns::LF_PREPARED.name, evaluations),
        (
            insns::LF_PREPARED_NO_BEAMS.name,
            REAL_SCANS * POSES_PER_SCAN,
        ),
        (insns::LF_PER_POSE.name, evaluations),
        (insns::BEAM_RAY_CAST.name, real::SCANS.len() * real::BEAMS),
        (insns::LF_PREPARED_TILED.name, evaluations),
        (
            insns::LF_PREPARED_NO_BEAMS_TILED.name,
            REAL_SCANS * POSES_PER_SCAN,
        ),
        (insns::EMPTY_BYTES.name, ld06_len),
        (insns::LD06_DECODE.name, ld06_len),
        (insns::LD06_ASSEMBLE.name, ld06_len),
        (insns::RPLIDAR_ASSEMBLE.name, rp_len),
        (insns::XV11_ASSEMBLE.name, xv_len),
        (insns::YDLIDAR_ASSEMBLE.name, yd_len),
    ];
    for (name, divisor) in divisors {
        println!("{}{} {}", insns::DIVISOR_LINE, name, divisor);
    }
    exit(
        score.log_likelihood.is_finite()
            && usize::from(score.scored) == BEAMS
            && fixed_point_poses == REAL_SCANS * POSES_PER_SCAN
            && overhead_sum == 0.0
            && race_ok
            && tiled_ok,
    )
}
