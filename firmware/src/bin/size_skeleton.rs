//! The skeleton of [`size_core`](../size_core/index.html) and [`size_lf`](../size_lf/index.html): the same program without the calls
//! of the scoring core, so that `cargo xtask budgets` can subtract everything that is not the
//! core (start-up code, the blob, the inputs, the exit). Body: `firmware/src/size_common.rs`.
#![no_std]
#![no_main]

/// This program does not call the scoring core.
const SCORE: bool = false;

/// Nor the beam model.
const BEAM_MODEL: bool = false;

include!("../size_common.rs");
