//! Instruction counts: scores a synthetic 360-beam scan with the beam mixture (given z*)
//! between `bench_mark_start`/`bench_mark_end`, after three baselines measured the same way.
//! Run under the QEMU counting plugin by `cargo xtask insns`, which divides by the beam count.
//!
//! Regions, in order (the plugin numbers them from 0):
//! 0. empty loop: sum the ranges, +∞ read as the max range (the loop and load cost alone);
//! 1. `beamfield::math::ln` of each range (the host bench's baseline);
//! 2. `beamfield::math::exp` of each range;
//! 3. `BeamModel::scan_log_likelihood`: the beam mixture, AMCL default intrinsics, 30 m lidar.
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
    exit(score.log_likelihood.is_finite() && usize::from(score.scored) == BEAMS)
}
