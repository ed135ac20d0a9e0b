//! Support code shared by the on-target programs in `src/bin/`: the reference-case type and its
//! generated table, a small fixed-point formatter (so no `core::fmt` float code is linked), the
//! instruction-count markers, the semihosting exit, and the STM32F405 USART receive driver
//! ([`usart`]).
//!
//! Every program here runs under QEMU (`cargo xtask qemu`, `cargo xtask insns`) or on a board
//! with a debugger that serves semihosting.
#![no_std]

// Generated data: its tuple table is the generator's format, not a design choice.
#[allow(clippy::type_complexity)]
#[rustfmt::skip]
pub mod fixed_cases;
#[cfg(target_has_atomic = "32")]
pub mod boards;
pub mod clock_f4;
pub mod reference_cases;
#[cfg(target_has_atomic = "32")]
pub mod serial;
pub mod size_program;
#[cfg(target_has_atomic = "32")]
pub mod stm32l4;
pub mod usart;

use core::fmt;
use cortex_m_semihosting::debug;
// The defmt logger (RTT) for every program when the feature `defmt` is on.
#[cfg(feature = "defmt")]
use defmt_rtt as _;

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
#[cfg(not(feature = "defmt"))]
#[macro_export]
macro_rules! println {
    ($($arg:tt)*) => { cortex_m_semihosting::hprintln!($($arg)*) };
}

/// Prints one line over defmt-RTT (feature `defmt`, for a board with a debug probe): the
/// line is formatted with `core::fmt` into a [`LINE_BYTES`]-byte buffer and sent as one
/// defmt string, so the output reads the same as under semihosting.
#[cfg(feature = "defmt")]
#[macro_export]
macro_rules! println {
    ($($arg:tt)*) => { $crate::defmt_line(format_args!($($arg)*)) };
}

/// Longest line [`println!`] sends over defmt; longer ones are cut and marked `[cut]`.
#[cfg(feature = "defmt")]
pub const LINE_BYTES: usize = 384;

/// Formats `args` and sends the text as one defmt message (see [`println!`]).
#[cfg(feature = "defmt")]
pub fn defmt_line(args: fmt::Arguments<'_>) {
    struct Line {
        bytes: [u8; LINE_BYTES],
        len: usize,
        cut: bool,
    }
    impl fmt::Write for Line {
        fn write_str(&mut self, s: &str) -> fmt::Result {
            for ch in s.chars() {
                let mut utf8 = [0u8; 4];
                let enc = ch.encode_utf8(&mut utf8).as_bytes();
                let end = self.len + enc.len();
                match self.bytes.get_mut(self.len..end) {
                    Some(dst) => {
                        dst.copy_from_slice(enc);
                        self.len = end;
                    }
                    None => {
                        self.cut = true;
                        return Ok(());
                    }
                }
            }
            Ok(())
        }
    }
    let mut line = Line {
        bytes: [0; LINE_BYTES],
        len: 0,
        cut: false,
    };
    let _ = fmt::write(&mut line, args);
    // Whole characters only were copied, so this is UTF-8.
    let text = line
        .bytes
        .get(..line.len)
        .and_then(|b| core::str::from_utf8(b).ok())
        .unwrap_or("");
    let mark = if line.cut { " [cut]" } else { "" };
    defmt::println!("{=str}{=str}", text, mark);
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
/// (`xtask/insncount/insncount.c`, run by `cargo xtask count`): it counts the instructions executed from a call of
/// this function to the next call of [`bench_mark_end`].
///
/// Never inlined and never merged with [`bench_mark_end`] (the bodies differ), so each has its
/// own address.
#[no_mangle]
#[inline(never)]
pub extern "C" fn bench_mark_start() {
    cortex_m::asm::nop();
}

/// Names the next measured region and starts it: prints
/// `beamfield_fixtures::regions::NAME_LINE` and the name (a name of
/// `beamfield_fixtures::regions`), then calls [`bench_mark_start`]. `cargo xtask` pairs the
/// names with the plugin's counts in order and takes the counts by name.
///
/// A macro, not a function of this library: only the programs that name regions then link
/// the fixtures crate. Linked into every program, its unused code changes what the optimizer
/// inlines under LTO, and so the flash and instruction figures of programs that have nothing
/// to do with it (the size programs of `cargo xtask budgets`).
#[macro_export]
macro_rules! start_region {
    ($name:expr) => {{
        $crate::println!("{}{}", beamfield_fixtures::regions::NAME_LINE, $name);
        $crate::bench_mark_start();
    }};
}

/// Bytes as lowercase hex, written a few dozen characters at a time (one `write_str` each:
/// under semihosting, one host call).
#[derive(Clone, Copy, Debug)]
pub struct Hex<'a>(pub &'a [u8]);

impl fmt::Display for Hex<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const DIGITS: &[u8; 16] = b"0123456789abcdef";
        let mut text = [0u8; 64];
        for piece in self.0.chunks(text.len() / 2) {
            for (pair, &b) in text.chunks_exact_mut(2).zip(piece) {
                if let [hi, lo] = pair {
                    *hi = DIGITS.get(usize::from(b >> 4)).copied().unwrap_or(b'0');
                    *lo = DIGITS.get(usize::from(b & 0xf)).copied().unwrap_or(b'0');
                }
            }
            let used = text.get(..2 * piece.len()).unwrap_or_default();
            f.write_str(core::str::from_utf8(used).map_err(|_| fmt::Error)?)?;
        }
        Ok(())
    }
}

/// Sends a frame of the device link (`beamfield::link`) on the program's output as one line,
/// `beamfield_fixtures::report::FRAME_LINE` and the frame's wire bytes (COBS and delimiter) in
/// hex: `send_frame!(encoder, message)` with a `beamfield::link::Encoder` and a
/// `beamfield::link::Message`. A message the encoder refuses is reported in words (the host
/// then misses a frame and fails).
///
/// A macro for the reason given at [`start_region!`]: only the programs that send frames link
/// the link's encoder and the fixtures crate.
#[macro_export]
macro_rules! send_frame {
    ($encoder:expr, $message:expr) => {{
        let mut wire = [0u8; beamfield::link::MAX_WIRE_LEN];
        match $encoder.encode(&$message, &mut wire) {
            Ok(n) => $crate::println!(
                "{}{}",
                beamfield_fixtures::report::FRAME_LINE,
                $crate::Hex(wire.get(..n).unwrap_or_default())
            ),
            Err(e) => $crate::println!("link frame not encodable: {}", e),
        }
    }};
}

/// Sends a `beamfield_fixtures::report::Report` on the program's output as one line,
/// `beamfield_fixtures::report::REPORT_LINE` and the report's bytes in hex. See
/// [`send_frame!`].
#[macro_export]
macro_rules! send_report {
    ($report:expr) => {{
        let mut bytes = [0u8; beamfield_fixtures::report::MAX_REPORT_LEN];
        match $report.encode(&mut bytes) {
            Ok(n) => $crate::println!(
                "{}{}",
                beamfield_fixtures::report::REPORT_LINE,
                $crate::Hex(bytes.get(..n).unwrap_or_default())
            ),
            Err(e) => $crate::println!("report not encodable: {}", e),
        }
    }};
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
