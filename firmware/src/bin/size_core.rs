//! Flash and RAM of the scoring core, with [`size_skeleton`](../size_skeleton/index.html): this
//! program scores (tempered likelihood field over the linked Intel blob, weight normalization,
//! beam model with ray casting), the skeleton is the same program without the scoring calls.
//! `cargo xtask budgets` subtracts their `llvm-size -A` sections. Built with the feature
//! `nopanic`, it is the link-time proof that the scoring core cannot panic (`cargo xtask
//! nopanic`). Body: `firmware/src/size_common.rs`.
#![no_std]
#![no_main]

/// This program calls the scoring core.
const SCORE: bool = true;

/// This program links the beam model.
const BEAM_MODEL: bool = true;

include!("../size_common.rs");
