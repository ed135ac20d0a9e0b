//! Flash of the likelihood-field scoring core alone, with
//! [`size_skeleton`](../size_skeleton/index.html): blob parsing, the tempered likelihood field
//! (`score` and a `PreparedScan`), the beam layout, the scan and weight normalization; no beam
//! model. It is what a user who localizes with the likelihood field flashes (AMCL's default
//! model). `cargo xtask budgets` subtracts the skeleton's `llvm-size -A` sections.
//! Body: `firmware/src/size_common.rs`.
#![no_std]
#![no_main]

/// This program calls the scoring core.
const SCORE: bool = true;

/// Without the beam model.
const BEAM_MODEL: bool = false;

include!("../size_common.rs");
