//! Flash and RAM of the scoring core, with [`size_skeleton`](../size_skeleton/index.html): this
//! program scores (tempered likelihood field over the linked Intel blob, weight normalization,
//! beam model with ray casting), the skeleton is the same program without the scoring calls.
//! `cargo xtask budgets` subtracts their `llvm-size -A` sections. Built with the feature
//! `nopanic`, it is the link-time proof that the scoring core cannot panic (`cargo xtask
//! nopanic`). Body: `beamfield_firmware::size_program!` (firmware/src/size_program.rs).
#![no_std]
#![no_main]

beamfield_firmware::size_program!(score: true, beam_model: true);
