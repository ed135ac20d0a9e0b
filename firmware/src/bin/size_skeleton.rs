//! The skeleton of [`size_core`](../size_core/index.html) and [`size_lf`](../size_lf/index.html): the same program without the calls
//! of the scoring core, so that `cargo xtask budgets` can subtract everything that is not the
//! core (start-up code, the blob, the inputs, the exit). Body: `beamfield_firmware::size_program!` (firmware/src/size_program.rs).
#![no_std]
#![no_main]

beamfield_firmware::size_program!(score: false, beam_model: false);
