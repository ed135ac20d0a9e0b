//! Instruction counts of the Monte Carlo localizer's own work (`beamfield::mcl`), per particle
//! per update, on the Cortex-M4F under QEMU's counting plugin:
//!
//! 0. `Mcl::predict`: one odometry motion-model sample per particle (Table 5.6);
//! 1. `Mcl::update_with` with a trivial score (a quadratic bowl): log-weight bookkeeping,
//!    `normalize_log_weights`, the estimate, low-variance resampling (forced: ESS threshold 1);
//! 2. the same score alone over the particles (the baseline to subtract from 1).
//!
//! Filter overhead per particle per update = region 0 + region 1 − region 2, each divided by
//! the particle count; the program prints the divisors on its `mcl divisors:` line. Run:
//! `cd firmware && cargo build --release --target thumbv7em-none-eabihf --bin mcl_insns`, then
//! from the repository's root `cargo xtask count firmware/target/thumbv7em-none-eabihf/release/mcl_insns`.
#![no_std]
#![no_main]

use beamfield::mcl::{Mcl, MclConfig, OdometryNoise, OdometryStep, Particles, SplitMix64};
use beamfield::Pose;
use beamfield_firmware::{bench_mark_end, bench_mark_start, exit, println};
use core::hint::black_box;
use cortex_m_rt::entry;
use panic_semihosting as _;

/// Particles measured.
const N: usize = 1000;

fn bowl(p: &Pose) -> f32 {
    let (dx, dy) = (p.x_m - 1.0, p.y_m + 2.0);
    -(dx * dx + dy * dy) * 20.0 - p.theta_rad * p.theta_rad * 50.0
}

#[entry]
fn main() -> ! {
    let mut store = Particles::<N>::new();
    let Ok(noise) = OdometryNoise::uniform(0.005) else {
        exit(false)
    };
    let Ok(config) = MclConfig::new(noise, 1.0, 0.0, 0.0) else {
        exit(false)
    };
    let Ok(mut mcl) = Mcl::new(&mut store, config) else {
        exit(false)
    };
    let mut rng = SplitMix64::new(7);
    if mcl
        .init_gaussian(N, &Pose::new(1.0, -2.0, 0.1), 0.3, 0.2, &mut rng)
        .is_err()
    {
        exit(false);
    }
    let Ok(step) = OdometryStep::new(0.3, 0.7, -0.2) else {
        exit(false)
    };
    let step = black_box(step);

    bench_mark_start();
    mcl.predict(&step, &mut rng);
    bench_mark_end();

    bench_mark_start();
    let r = mcl.update_with(bowl, None, &mut rng);
    bench_mark_end();

    bench_mark_start();
    let mut s = 0.0f32;
    for p in mcl.poses() {
        s += bowl(black_box(p));
    }
    bench_mark_end();
    black_box(s);

    let ok = match r {
        Ok(u) => {
            println!(
                "mcl update: resampled {}, ess {}, estimate ({}, {}, {})",
                u.resampled,
                u.estimate.ess,
                u.estimate.pose.x_m,
                u.estimate.pose.y_m,
                u.estimate.pose.theta_rad
            );
            u.resampled
        }
        Err(_) => false,
    };
    println!(
        "mcl particles {} bytes of Particles<{}> = {} per particle",
        core::mem::size_of::<Particles<N>>(),
        N,
        core::mem::size_of::<Particles<N>>() / N
    );
    println!("mcl divisors: {} {} {}", N, N, N);
    exit(ok)
}
