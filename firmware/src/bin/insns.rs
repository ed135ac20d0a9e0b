//! Instruction counts: scores a synthetic 360-beam scan with the beam mixture (given z*)
//! between `bench_mark_start`/`bench_mark_end`, after three baselines measured the same way.
//! Run under the QEMU counting plugin by `cargo xtask insns`, which divides by the beam count.
//!
//! Regions, in order (the plugin numbers them from 0):
//! 0. empty loop: sum the ranges, +∞ read as the max range (the loop and load cost alone);
//! 1. `beamfield::math::ln` of each range (the host bench's baseline);
//! 2. `beamfield::math::exp` of each range;
//! 3. `BeamModel::scan_log_likelihood`: the beam mixture, AMCL default intrinsics, 30 m lidar;
//! 4. `BeamFieldModel` (issue 4's race): the beam model *with* ray casting through the real Intel
//!    map blob (`firmware/assets/intel.bin`), scoring the 8 real scans of `firmware/assets/scans.rs`
//!    (180 beams each, 1,440 beams) at their logged poses, with the intrinsics EM fitted on that
//!    log. Self-contained: its data and constants live in the module [`intel`].
#![no_std]
#![no_main]

use beamfield::{math, BeamIntrinsics, BeamModel, Scan};
use beamfield_firmware::{bench_mark_end, bench_mark_start, exit, println, Fixed};
use core::hint::black_box;
use cortex_m_rt::entry;
use panic_semihosting as _;

/// Beams per scan (a common 1° lidar).
pub const BEAMS: usize = 360;
/// The sensor's maximum range, metres.
const MAX_RANGE_M: f32 = 30.0;

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

/// Region 4's data: the demo's real scans and map blob, and the beam model fitted on that log.
mod intel {
    /// Beams per FLASER scan of the Intel log.
    pub const BEAMS: usize = 180;
    /// One real scan of the log with its logged laser pose (the shape `scans.rs` fills).
    pub struct DemoScan {
        /// Index of the FLASER line in the log.
        #[allow(dead_code)]
        pub log_index: u32,
        /// Logged laser pose `[x_m, y_m, theta_rad]`.
        pub pose: [f32; 3],
        /// The ranges, metres.
        pub ranges_m: [f32; BEAMS],
    }
    include!("../../assets/scans.rs");
    /// The 5 cm distance field of the Intel map, as the demo links it.
    pub static BLOB: &[u8] = include_bytes!("../../assets/intel.bin");
    /// `[z_hit, z_short, z_max, z_rand]`, σ_hit (m), λ_short (1/m): `beamfield fit` on the log
    /// (docs/beam-on-device.md, truncated update).
    pub const WEIGHTS: [f32; 4] = [0.878328, 0.057550, 0.023807, 0.040316];
    /// σ_hit, metres.
    pub const SIGMA_HIT_M: f32 = 0.058836;
    /// λ_short, 1/m.
    pub const LAMBDA_SHORT: f32 = 0.070119;
}

/// Region 4: scores every embedded real scan at its logged pose with the beam model and
/// on-device ray casting, between the markers. Returns the summed log-likelihood and the beams
/// scored, or `None` if the blob, intrinsics or a scan were rejected (reported by the caller).
/// Not inlined, so adding it leaves the code of `main`'s regions 0–3 as it was.
#[inline(never)]
fn beam_model_with_ray_casting() -> Option<(f32, usize)> {
    use beamfield::{
        BeamFieldModel, BeamLayout, FieldView, Pose, RayCaster, SensorModel, SensorMount,
    };
    let caster = RayCaster::new(FieldView::parse(intel::BLOB).ok()?).ok()?;
    let s: f32 = intel::WEIGHTS.iter().sum();
    let w = intel::WEIGHTS.map(|x| x / s);
    let intr = BeamIntrinsics::new(
        w[0],
        w[1],
        w[2],
        w[3],
        intel::SIGMA_HIT_M,
        intel::LAMBDA_SHORT,
        intel::MAX_RANGE_M,
    )
    .ok()?;
    let model = BeamFieldModel::new(BeamModel::new(intr), caster);
    // CARMEN FLASER: beam i at −90° + i·1°; the logged poses are the laser's (no mount).
    let layout = BeamLayout::<{ intel::BEAMS }>::uniform(
        -core::f32::consts::FRAC_PI_2,
        core::f32::consts::PI / intel::BEAMS as f32,
        intel::BEAMS,
        intel::MAX_RANGE_M,
        SensorMount::CENTERED,
    )
    .ok()?;
    let mut scans = [const { None }; intel::SCANS.len()];
    for (slot, d) in scans.iter_mut().zip(intel::SCANS.iter()) {
        let scan = Scan::<{ intel::BEAMS }>::from_ranges(&d.ranges_m).ok()?;
        *slot = Some((scan, Pose::new(d.pose[0], d.pose[1], d.pose[2])));
    }
    let scans = black_box(&scans);

    bench_mark_start();
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

    bench_mark_start();
    let mut sum = 0.0f32;
    for &z in ranges {
        sum += black_box(finite(z));
    }
    bench_mark_end();
    let empty = sum;

    bench_mark_start();
    let mut sum = 0.0f32;
    for &z in ranges {
        sum += math::ln(black_box(finite(z)));
    }
    bench_mark_end();
    let ln_sum = sum;

    bench_mark_start();
    let mut sum = 0.0f32;
    for &z in ranges {
        sum += math::exp(-black_box(finite(z)));
    }
    bench_mark_end();
    let exp_sum = sum;

    bench_mark_start();
    let score = model.scan_log_likelihood(black_box(&scan), black_box(&z_star[..]));
    bench_mark_end();

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
    let mixture_ok = score.log_likelihood.is_finite() && usize::from(score.scored) == BEAMS;

    // Region 4 (issue 4's race): the beam model with ray casting on the real Intel map.
    let Some((race_ll, race_scored)) = beam_model_with_ray_casting() else {
        println!("insns: region 4: Intel blob, intrinsics or scans rejected");
        exit(false)
    };
    println!(
        "insns: region 4 beam model with ray casting, Intel map: {} scans x {} beams, log-likelihood {}, {} scored",
        intel::SCANS.len(),
        intel::BEAMS,
        Fixed::new(f64::from(race_ll), 3),
        race_scored
    );
    let race_ok = race_ll.is_finite() && race_scored == intel::SCANS.len() * intel::BEAMS;
    exit(mixture_ok && race_ok)
}
