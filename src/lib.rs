//! Probabilistic range-sensor models for microcontrollers: `no_std`, no allocation, no panics
//! on the scoring path.
//!
//! ```toml
//! [dependencies]
//! beamfield = "0.1"
//! ```
//!
//! The crate implements the range-finder models of Thrun, Burgard & Fox, *Probabilistic
//! Robotics*, chapter 6 (the beam mixture, the likelihood field, map correlation, landmarks), a
//! crosstalk-aware model for rings of ultrasonic rangers, decoders for the UART streams of common
//! 2-D LiDARs, and a Monte Carlo localizer (chapter 8) on top of them. Maps reach the device as a
//! distance-field blob that the host tool `beamfield` (package `beamfield-tools` in the
//! repository) builds from a ROS map_server map; the device reads it in place from flash.
//!
//! Units: metres, radians (counter-clockwise; x forward, y left), nats. Names carry units
//! (`range_m`, `sigma_hit_m`, `bearing_rad`).
//!
//! # Features for your part
//!
//! | part | target | features | why |
//! |---|---|---|---|
//! | Cortex-M4F / M7 (STM32F4, nRF52, …) | `thumbv7em-none-eabihf` | defaults (`tiled-field`); add `micromath` for ~20-instruction sin/cos (1.1e-3 rad error, once per pose) | the f32 path runs on the FPU: about 19 instructions per beam through a prepared scan |
//! | Cortex-M0 / M0+ (RP2040, STM32G0, nRF51) | `thumbv6m-none-eabi` | `default-features = false, features = ["fixed"]` (keep `tiled-field` if the map is stored tiled) | no FPU: every f32 operation is a soft-float call; `fixed_point` scores in integers, 12× fewer instructions per beam on an M0 |
//! | RISC-V without F (ESP32-C3, GD32VF103) | `riscv32imc-unknown-none-elf` | `default-features = false, features = ["fixed"]` | the same reason as the M0; with the F extension use the defaults |
//!
//! Optional on any part: `defmt` (`defmt::Format` on every error and report), `hal` (the
//! embedded-hal 1.0 ultrasonic-ring driver and LiDAR readers over `embedded-io` / `embedded-hal-nb`).
//!
//! ```toml
//! # A Cortex-M0 with a map stored tiled:
//! beamfield = { version = "0.1", default-features = false, features = ["fixed", "tiled-field"] }
//! ```
//!
//! # A particle filter's measurement update
//!
//! Every constructor validates its input once and returns its own error type; each converts into
//! [`Error`], so one `?` works for all of them. Scoring a pose cannot fail.
//! ```rust,no_run
//! use beamfield::{
//!     normalize_log_weights, BeamLayout, Error, FieldView, LikelihoodField, LikelihoodParams, Pose,
//!     Scan, SensorMount, Tempered,
//! };
//! use core::f32::consts::PI;
//!
//! /// Beams per scan (the scan and layout capacity).
//! const BEAMS: usize = 360;
//!
//! /// Replaces `log_weights[i]` by the normalized weight of `particles[i]` given one scan, and
//! /// returns the effective sample size.
//! fn measurement_update(
//!     map_blob: &[u8],      // e.g. `include_bytes!("map.bin")`, in flash
//!     ranges_m: &[f32],     // from the sensor driver, one range per beam
//!     particles: &[Pose],
//!     log_weights: &mut [f32],
//! ) -> Result<f32, Error> {
//!     let view = FieldView::parse(map_blob)?; // BlobError: checked once, no panic on any bytes
//!     let params = LikelihoodParams::amcl_defaults(30.0)?; // LikelihoodError
//!     let field = LikelihoodField::new(view, params);
//!     let model = Tempered::new(field, 8.0, 1)?; // TemperError; κ from `beamfield calibrate`
//!     let step_rad = 2.0 * PI / BEAMS as f32;
//!     let layout = BeamLayout::<BEAMS>::uniform(-PI, step_rad, BEAMS, 30.0, SensorMount::CENTERED)?;
//!     let scan = Scan::<BEAMS>::from_ranges(ranges_m)?; // ScanError, like the layout
//!
//!     // `model.score(&layout, &scan, &pose)` scores one pose (nats, never NaN). For many poses,
//!     // prepare the scan once: each pose then costs about 19 instructions per beam on a Cortex-M4F.
//!     let prepared = model.prepare(&layout, &scan);
//!     for (pose, w) in particles.iter().zip(log_weights.iter_mut()) {
//!         *w = prepared.score(pose).log_likelihood;
//!     }
//!     let normalized = normalize_log_weights(log_weights)?; // NormalizeError
//!     Ok(normalized.ess)
//! }
//! ```
//!
//! # From a LiDAR's bytes to a pose
//!
//! The decoders ([`lidar::ld06`], [`lidar::rplidar`], [`lidar::xv11`], [`lidar::ydlidar`]) take the
//! UART's bytes one slice at a time (from an interrupt, a DMA ring or a polled read), the
//! [`lidar::ScanAssembler`] closes each revolution into a [`Scan`], and the localizer in [`mcl`]
//! takes every scan with the odometry step since the last one. The field file carries the
//! free-space section that global initialization and recovery draw from
//! (`beamfield field build map.yaml -o map.bin --free-space`).
//! ```rust,no_run
//! use beamfield::field::FreeSpace;
//! use beamfield::lidar::{ld06::Ld06Decoder, AssemblerConfig, ScanAssembler};
//! use beamfield::mcl::{Mcl, MclConfig, MclError, OdometryNoise, OdometryStep, Particles, SplitMix64};
//! use beamfield::{
//!     BeamLayout, Error, FieldView, LikelihoodField, LikelihoodParams, Pose, SensorMount, Tempered,
//! };
//! use core::f32::consts::PI;
//!
//! /// Beams of the scans the filter scores (one per degree).
//! const BEAMS: usize = 360;
//! /// Particle capacity: 18 bytes each.
//! const PARTICLES: usize = 500;
//!
//! /// Tracks the robot from `start` through the LD06 bytes in `uart_bytes`; `odometry(k)` is the
//! /// wheel-odometry pose when revolution `k` ended. Returns the last estimate.
//! fn track(
//!     map_file: &[u8],
//!     uart_bytes: &[u8],
//!     start: Pose,
//!     odometry: impl Fn(usize) -> Pose,
//! ) -> Result<Pose, Error> {
//!     let (view, rest) = FieldView::parse_prefix(map_file)?; // BlobError
//!     let free = FreeSpace::parse(rest)?; // FreeSpaceError
//!     let field = LikelihoodField::new(view, LikelihoodParams::amcl_defaults(12.0)?);
//!     let model = Tempered::new(field, 8.0, 1)?;
//!     let layout =
//!         BeamLayout::<BEAMS>::uniform(-PI, 2.0 * PI / BEAMS as f32, BEAMS, 12.0, SensorMount::CENTERED)?;
//!     let mut assembler = ScanAssembler::new(&layout, AssemblerConfig::for_layout(&layout))?;
//!     let mut decoder = Ld06Decoder::new();
//!
//!     let mut store = Particles::<PARTICLES>::new(); // or a `static`, placed where the RAM is
//!     let config = MclConfig::new(OdometryNoise::uniform(0.02)?, 0.5, 0.0, 0.0)?; // MotionError, MclError
//!     let mut mcl = Mcl::new(&mut store, config)?; // MclError
//!     let mut rng = SplitMix64::new(1);
//!     mcl.init_gaussian(PARTICLES, &start, 0.05, 0.035, &mut rng)?;
//!
//!     let (mut estimate, mut revolution, mut last_odom) = (start, 0, odometry(0));
//!     let mut failure = None;
//!     decoder.feed(uart_bytes, |point| {
//!         let Some(scan) = assembler.push(point) else { return };
//!         revolution += 1;
//!         let odom = odometry(revolution);
//!         let step = OdometryStep::between(&last_odom, &odom);
//!         last_odom = odom;
//!         let result = step.map_err(Error::from).and_then(|step| {
//!             mcl.predict(&step, &mut rng);
//!             Ok(mcl.update_prepared(&model.prepare(&layout, scan), Some(&free), &mut rng)?)
//!         });
//!         match result {
//!             Ok(update) => estimate = update.estimate.pose,
//!             // A revolution with no usable beam changes nothing (the motion is kept).
//!             Err(Error::Mcl(MclError::EmptyScan)) => {}
//!             Err(e) => failure = Some(e),
//!         }
//!     });
//!     match failure {
//!         Some(e) => Err(e),
//!         None => Ok(estimate),
//!     }
//! }
//! ```
//!
//! The decoder's and the assembler's counters (`decoder.stats()`, `assembler.stats()`) say what
//! became of every byte and point.
//!
//! # Where things are
//!
//! | what | items |
//! |---|---|
//! | beam mixture (Table 6.1), its EM (Table 6.2) | [`BeamModel`], [`BeamIntrinsics`], [`em`] |
//! | likelihood field (Table 6.3) over a distance-field blob | [`FieldView`], [`LikelihoodField`], [`PreparedScan`], [`field`] |
//! | beam model with z* cast through the blob | [`RayCaster`], [`BeamFieldModel`] |
//! | tempering, weight normalization, effective sample size | [`Tempered`], [`normalize_log_weights`], [`Lag1`] |
//! | map correlation (§6.5), landmarks (Tables 6.4, 6.5) | [`MapCorrelation`], [`landmark`], [`gaussian`] |
//! | ultrasonic ring with crosstalk-aware `z_rand` | [`sonar`] |
//! | fixed-point likelihood field (feature `fixed`) | `fixed_point` (built with the feature) |
//! | LiDAR decoders and scan assembly | [`lidar`] |
//! | Monte Carlo localization | [`mcl`] |
//! | scans, layouts, reading policy | [`Scan`], [`BeamLayout`], [`Reading`] |
//!
//! The repository (README, `docs/`) documents the blob format byte by byte, every model's
//! derivation and measurements, the firmware programs that run these paths under QEMU, and the
//! host tool.
#![cfg_attr(not(test), no_std)]

/// The README's Rust examples, compiled as doctests: the README is the repository's front page,
/// not this crate's documentation.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

pub mod beam;
pub mod beam_field;
mod build_info;
pub mod correlation;
pub mod diagnostic;
pub mod em;
mod error;
pub mod field;
#[cfg(feature = "fixed")]
pub mod fixed_point;
pub mod gaussian;
pub mod intrinsics;
pub mod landmark;
pub mod lidar;
pub mod link;
pub mod math;
pub mod mcl;
pub mod model;
pub mod pose;
pub mod raycast;
pub mod robot;
pub mod scan;
pub mod sonar;
pub mod tempered;
mod wire;

pub use beam::{BeamModel, Components, BEAM_LOG_FLOOR};
pub use beam_field::BeamFieldModel;
pub use build_info::{BuildInfo, BUILD_INFO};
pub use correlation::{
    Correlation, CorrelationError, MapCorrelation, CORRELATION_EPSILON, MAX_WINDOW_CELLS,
};
pub use diagnostic::Lag1;
pub use error::Error;
pub use field::{
    edt_scratch_len, emit_blob, emit_blob_from_squared_cells, emit_blob_tiled,
    emit_blob_tiled_clamped, squared_edt, tiled_max_len, tiled_scratch_len, BlobError, EdtError,
    EdtScratch, FieldHeader, FieldView, LikelihoodError, LikelihoodField, LikelihoodParam,
    LikelihoodParams, PreparedScan, DEFAULT_MAX_DIST_M, EDT_INFINITY,
};
pub use intrinsics::{BeamIntrinsics, IntrinsicsError, Param};
pub use landmark::{
    Feature, FeatureNoise, IntersectionError, Landmark, LandmarkError, TwoFeaturePoses,
};
pub use link::LinkError;
pub use model::{SensorModel, Stride};
pub use pose::{wrap_angle, Pose, SensorMount};
pub use raycast::{CastTrace, RayCastError, RayCaster};
pub use scan::{Beam, BeamLayout, Reading, Scan, ScanError, ScanScore};
pub use tempered::{
    effective_sample_size, normalize_log_weights, NormalizeError, Normalized, TemperError,
    Tempered, TemperedScan,
};
