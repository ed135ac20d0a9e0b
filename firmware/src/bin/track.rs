//! The localizer on the device: Monte Carlo localization ([`beamfield::mcl`]) of a real Intel
//! lab log segment, bit for bit the run the host recomputes.
//!
//! The input (`fixtures/assets/track.rs`, standing in for the sensor and wheel drivers) is the
//! log's first 90 scans, a loop of the corridor with four corners, with their logged poses and
//! the odometry `beamfield track` synthesizes for the same seed. The run is that of
//! `fixtures/src/track_plan.rs`, shared word for word with `cargo xtask track`, which recomputes it on
//! the host and requires every reported value to match bit for bit.
//!
//! Per update it sends the estimate as the device link's `Estimate` frame (pose, covariance,
//! ESS, the resampled flag; `beamfield::link`) and a [`TrackStep`] report (the scan, a hash of
//! every particle's pose and weight bits, whether the update was skipped, the error against the
//! logged pose), at the end a [`TrackSummary`] (the RMSE over the segment, the final and the
//! largest error, the resamplings): data lines in hex (`beamfield_fixtures::report`), which the
//! host decodes and compares bit for bit. Beside them, the same in readable decimals for a
//! person. Output is integers and fixed decimals ([`Fixed`]), so no `core::fmt` float code is
//! linked.
//! Per scan, three regions lie between the instruction-count markers: the prediction, the
//! scoring alone of every particle (a baseline), and the whole update (`docs/localization.md`,
//! "On the device"). Exit status 1 when the run could not be set up.
#![no_std]
#![no_main]

use beamfield::link::{Encoder, Message};
use beamfield::mcl::Particles;
use beamfield_firmware::{
    bench_mark_end, exit, println, send_frame, send_report, start_region, Fixed,
};
use beamfield_fixtures::report::{track_estimate, Report, TrackStep, TrackSummary};
use cortex_m_rt::entry;
#[cfg(feature = "defmt")]
use panic_probe as _;
#[cfg(not(feature = "defmt"))]
use panic_semihosting as _;

use beamfield_fixtures::track_plan::asset::{MAX_RANGE_M, ODOM_ALPHA, SEED, TRACK};
use beamfield_fixtures::track_plan::{run, Mark, Step, BEAMS, KAPPA, PARTICLES};

/// The 5 cm distance field of the Intel map (the demo's, see `docs/demo.md`).
static BLOB: &[u8] = include_bytes!("../../assets/intel.bin");

/// Sends the update's data, its estimate frame (sequence number: the update's index) and its
/// step report, then prints it for a person.
///
/// Out of line: the plan's `run`, with the counted regions, is inlined into `main`, and the
/// reporting's code there would change what the compiler makes of the regions (the prediction
/// still moves by 2 instructions per particle, see `docs/localization.md`).
#[inline(never)]
fn report(s: &Step) {
    let log_index = TRACK.get(s.k).map_or(0, |t| t.log_index);
    let mut encoder = Encoder::starting_at(s.k as u16);
    send_frame!(encoder, Message::Estimate(track_estimate(s)));
    send_report!(Report::TrackStep(TrackStep::of(s, log_index)));
    let e = &s.estimate;
    let resampled = matches!(s.update, Ok(u) if u.resampled);
    println!(
        "update {} (scan {}): ({}, {}, {} deg) ESS {}, error {} cm {} deg{}{}",
        s.k,
        log_index,
        Fixed::new(f64::from(e.pose.x_m), 3),
        Fixed::new(f64::from(e.pose.y_m), 3),
        Fixed::new(f64::from(e.pose.theta_rad.to_degrees()), 2),
        Fixed::new(f64::from(e.ess), 1),
        Fixed::new(s.trans_err_m * 100.0, 1),
        Fixed::new(s.heading_err_deg, 2),
        if resampled { ", resampled" } else { "" },
        if s.update.is_err() { ", skipped" } else { "" },
    );
}

#[entry]
fn main() -> ! {
    // The particles, in `.bss` (taken once).
    let Some(store) = cortex_m::singleton!(: Particles<PARTICLES> = Particles::new()) else {
        println!("track: particle storage taken twice");
        exit(false)
    };
    println!(
        "beamfield track: {} real scans of {} beams, {} particles ({} bytes), kappa {}, odom_alpha {}, seed {}",
        TRACK.len(),
        BEAMS,
        PARTICLES,
        core::mem::size_of::<Particles<PARTICLES>>(),
        Fixed::new(f64::from(KAPPA), 2),
        Fixed::new(f64::from(ODOM_ALPHA), 3),
        SEED,
    );
    let mark = |m: Mark| match m {
        Mark::Start(name) => start_region!(name),
        Mark::End => bench_mark_end(),
    };
    match run(
        store,
        BLOB,
        &TRACK,
        MAX_RANGE_M,
        ODOM_ALPHA,
        SEED,
        mark,
        report,
    ) {
        Ok(sum) => {
            send_report!(Report::TrackSummary(TrackSummary::of(&sum)));
            println!(
                "final error {} cm {} deg; RMSE over {} updates {} cm {} deg; max error {} m; {} resamplings",
                Fixed::new(sum.final_err.0 * 100.0, 2),
                Fixed::new(sum.final_err.1, 2),
                sum.updates,
                Fixed::new(sum.trans_rmse_m * 100.0, 2),
                Fixed::new(sum.heading_rmse_deg, 3),
                Fixed::new(sum.max_trans_m, 3),
                sum.resamplings,
            );
            exit(true)
        }
        Err(e) => {
            println!("track: {}", e);
            exit(false)
        }
    }
}
