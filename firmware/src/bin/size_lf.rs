//! Flash of the likelihood-field scoring core alone, with
//! [`size_skeleton`](../size_skeleton/index.html): blob parsing, the tempered likelihood field
//! (`score` and a `PreparedScan`), the beam layout, the scan and weight normalization; no beam
//! model. It is what a user who localizes with the likelihood field flashes (AMCL's default
//! model). `cargo xtask budgets` subtracts the skeleton's `llvm-size -A` sections.
//! Body: `beamfield_firmware::size_program!` (firmware/src/size_program.rs).
#![no_std]
#![no_main]

beamfield_firmware::size_program!(score: true, beam_model: false);
