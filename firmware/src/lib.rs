//! Support code shared by the on-target programs in `src/bin/`: the reference-case type and its
//! generated table, a small fixed-point formatter (so no `core::fmt` float code is linked), the
//! instruction-count markers, and the semihosting exit.
//!
//! Every program here runs under QEMU (`cargo xtask qemu`, `cargo xtask insns`) or on a board
//! with a debugger that serves semihosting.
#![no_std]

// Generated data: its tuple table is the generator's format, not a design choice.
#[allow(clippy::type_complexity)]
#[rustfmt::skip]
pub mod fixed_cases;
pub mod reference_cases;

use core::fmt;
use cortex_m_semihosting::debug;

/// One reference case (see `host-tests/src/firmware_cases.rs`, which generates the table).
#[derive(Clone, Copy, Debug)]
pub struct Case {
    /// What the case exercises.
    pub name: &'static str,
    /// `[z_hit, z_short, z_max, z_rand, sigma_hit_m, lambda_short_per_m, max_range_m]`.
    pub intrinsics: [f32; 7],
    /// The reading, metres.
    pub range_m: f32,
    /// The ray-cast range, metres.
    pub z_star_m: f32,
    /// `ln p(z | z*)` by the host's f64 reference; `None` for an invalid reading.
    pub expected: Option<f64>,
    /// Allowed `|got − expected|`, nats.
    pub tolerance: f64,
}

/// A real number printed with a fixed number of decimals from an integer, without linking
/// `core::fmt`'s float formatting (about 25 KiB of text and a 2 KiB stack frame).
///
/// Values whose scaled magnitude exceeds `i64` print as `inf`/`-inf`; NaN prints as `NaN`.
#[derive(Clone, Copy, Debug)]
pub struct Fixed {
    value: f64,
    decimals: u32,
}

impl Fixed {
    /// `value` with `decimals` digits after the point (at most 12).
    pub fn new(value: f64, decimals: u32) -> Self {
        Self {
            value,
            decimals: decimals.min(12),
        }
    }
}

impl fmt::Display for Fixed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.value.is_nan() {
            return f.write_str("NaN");
        }
        let scale = 10u64.pow(self.decimals);
        let scaled = self.value * scale as f64;
        // Round half away from zero, in f64 (exact for the magnitudes printed here). NaN was
        // handled above, so the range test below also catches ±∞.
        let rounded = if scaled < 0.0 {
            scaled - 0.5
        } else {
            scaled + 0.5
        };
        if rounded.abs() >= 9.2e18 {
            return f.write_str(if self.value < 0.0 { "-inf" } else { "inf" });
        }
        let n = rounded as i64;
        let sign = if n < 0 { "-" } else { "" };
        let m = n.unsigned_abs();
        if self.decimals == 0 {
            write!(f, "{sign}{m}")
        } else {
            let width = self.decimals as usize;
            write!(f, "{sign}{}.{:0width$}", m / scale, m % scale)
        }
    }
}

/// Prints through semihosting (the host's stdout under QEMU).
#[macro_export]
macro_rules! println {
    ($($arg:tt)*) => { cortex_m_semihosting::hprintln!($($arg)*) };
}

/// Ends the program: semihosting exit status 0 when `ok`, 1 otherwise.
pub fn exit(ok: bool) -> ! {
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    // Without a debugger serving semihosting, exit returns: park the core.
    loop {
        cortex_m::asm::bkpt();
    }
}

/// Marks the start of a measured region for the QEMU instruction-count plugin
/// (`../shared/tools/qemu-insncount/`): it counts the instructions executed from a call of
/// this function to the next call of [`bench_mark_end`].
///
/// Never inlined and never merged with [`bench_mark_end`] (the bodies differ), so each has its
/// own address.
#[no_mangle]
#[inline(never)]
pub extern "C" fn bench_mark_start() {
    cortex_m::asm::nop();
}

/// Marks the end of a measured region; see [`bench_mark_start`].
#[no_mangle]
#[inline(never)]
pub extern "C" fn bench_mark_end() {
    cortex_m::asm::nop();
    cortex_m::asm::nop();
}

/// The models program's cases, generated on the host (`cargo xtask modelcases`).
#[allow(missing_docs, clippy::all)]
pub mod model_cases {
    include!("model_cases.rs");
}
