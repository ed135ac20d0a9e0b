//! The table of reference cases the on-target check program runs (`firmware/src/bin/check.rs`).
//!
//! [`cases`] picks inputs (hand-chosen edge cases and a fixed pseudo-random sample), evaluates
//! each with the f64 reference ([`crate::reference`]), and [`render`] writes them as the Rust
//! source `firmware/src/reference_cases.rs`. The file is checked in; `cargo xtask refcases`
//! rewrites it and `host-tests/tests/target_checks.rs` fails when it is stale.
//!
//! Inputs are chosen as f32 values and widened exactly to f64 for the reference, so the only
//! difference between the two sides is the f32 arithmetic of the crate, not input rounding.

use crate::reference::{self, Intrinsics};
use std::fmt::Write as _;

/// Path of the generated file, relative to the repository root.
pub const GENERATED_PATH: &str = "firmware/src/reference_cases.rs";

/// Absolute part of the per-beam tolerance, nats.
///
/// Error budget of the crate's f32 per-beam log-likelihood against the exact value: in the
/// linear path the mixture `p` carries the relative errors of `erf`, `exp` (≤ 2.5e-7 each,
/// `crate::math` docs) and of about ten rounded operations (≤ 6e-8 each), so
/// `|Δ ln p| = |Δp/p| ≤ ~1.5e-6`; `ln` adds 1.2e-7·|ln p|. A margin of about 6× over that gives
/// 1e-5.
pub const TOL_ABS: f64 = 1e-5;

/// Relative part of the per-beam tolerance (multiplies `|expected|`).
///
/// In the log path the result is dominated by `−½·d²` with `d = (z − z*)/σ`: the rounding of
/// `z − z*` and of `1/σ` (≤ 6e-8 each, relative) makes `d²` wrong by ≤ 2.4e-7 relative, and
/// `ln`/sums add a few ulp of the result. 2e-6 leaves a margin of about 5×.
pub const TOL_REL: f64 = 2e-6;

/// One case: intrinsics, reading, ray-cast range, and the reference's answer.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// What the case exercises.
    pub name: String,
    /// `[z_hit, z_short, z_max, z_rand, sigma_hit_m, lambda_short_per_m, max_range_m]`.
    pub intrinsics: [f32; 7],
    /// The reading, metres (may be NaN, negative or +∞).
    pub range_m: f32,
    /// The ray-cast range, metres (may be NaN).
    pub z_star_m: f32,
    /// `ln p(z | z*)` by the f64 reference; `None` for an invalid reading.
    pub expected: Option<f64>,
    /// Allowed `|got − expected|`, nats.
    pub tolerance: f64,
}

fn reference_intrinsics(p: &[f32; 7]) -> Intrinsics {
    Intrinsics {
        z_hit: f64::from(p[0]),
        z_short: f64::from(p[1]),
        z_max: f64::from(p[2]),
        z_rand: f64::from(p[3]),
        sigma_hit: f64::from(p[4]),
        lambda_short: f64::from(p[5]),
        max_range: f64::from(p[6]),
    }
}

fn case(name: &str, intrinsics: [f32; 7], range_m: f32, z_star_m: f32) -> Case {
    let expected = reference::beam_log_likelihood(
        &reference_intrinsics(&intrinsics),
        f64::from(range_m),
        f64::from(z_star_m),
    );
    Case {
        name: name.to_string(),
        intrinsics,
        range_m,
        z_star_m,
        expected,
        // Rounded to the 4 digits the generated file prints, so host and target use one value.
        tolerance: expected.map_or(0.0, |e| round4(TOL_ABS + TOL_REL * e.abs())),
    }
}

/// `x` rounded to 4 significant digits, exactly as `{:.3e}` prints it.
fn round4(x: f64) -> f64 {
    format!("{x:.3e}").parse().unwrap_or(x)
}

/// A small deterministic generator (64-bit LCG, Knuth's MMIX constants), so the table is the
/// same on every machine without a dependency.
struct Lcg(u64);

impl Lcg {
    fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// Random weights on the simplex, rounded to f32 (the sum stays within 1e-6 of 1).
fn simplex(rng: &mut Lcg) -> [f32; 4] {
    let raw = [
        rng.range(0.05, 1.0),
        rng.range(0.0, 0.5),
        rng.range(0.0, 0.3),
        rng.range(0.0, 0.3),
    ];
    let s: f64 = raw.iter().sum();
    raw.map(|w| (w / s) as f32)
}

/// The whole table, in a fixed order.
pub fn cases() -> Vec<Case> {
    let mut out = Vec::new();
    // The chapter's example (docs/models.md#mixture): all weights 0.25, σ = 1, λ = 0.5, z_max = 10.
    let toy = [0.25, 0.25, 0.25, 0.25, 1.0, 0.5, 10.0];
    for z in [4.5f32, 5.0, 3.0, 7.0, 10.0] {
        out.push(case("worked example", toy, z, 5.0));
    }
    // Reading policy edges.
    out.push(case("z = 0", toy, 0.0, 5.0));
    out.push(case("z beyond z_max", toy, 12.0, 5.0));
    out.push(case("z = +inf (max range)", toy, f32::INFINITY, 5.0));
    out.push(case("z NaN (invalid)", toy, f32::NAN, 5.0));
    out.push(case("z negative (invalid)", toy, -1.0, 5.0));
    out.push(case("z* = 0", toy, 0.5, 0.0));
    out.push(case("z* tiny", toy, 0.5, 1e-4));
    out.push(case("z* near z_max", toy, 9.9, 9.999));
    out.push(case("z* beyond z_max (clamped)", toy, 9.0, 15.0));
    out.push(case("z* NaN (read as z_max)", toy, 9.0, f32::NAN));
    out.push(case("z = z*", toy, 5.0, 5.0));
    // AMCL's defaults (renormalized as BeamIntrinsics::amcl_defaults does) on a 30 m lidar.
    let s = 0.95f32 + 0.1 + 0.05 + 0.05;
    let amcl = [0.95 / s, 0.1 / s, 0.05 / s, 0.05 / s, 0.2, 0.1, 30.0];
    for (z, zs) in [
        (2.0f32, 2.05f32),
        (1.0, 8.0),
        (8.5, 8.0),
        (29.99, 3.0),
        (30.0, 30.0),
    ] {
        out.push(case("amcl defaults", amcl, z, zs));
    }
    // Narrow Gaussian: far readings leave the linear path (the mixture underflows f32).
    let narrow = [0.7, 0.1, 0.1, 0.1, 0.01, 1.0, 10.0];
    for (z, zs) in [
        (5.0f32, 5.0f32),
        (5.02, 5.0),
        (5.3, 5.0),
        (6.0, 5.0),
        (2.0, 5.0),
    ] {
        out.push(case("narrow sigma", narrow, z, zs));
    }
    let hit_only = [1.0, 0.0, 0.0, 0.0, 0.01, 1.0, 10.0];
    for (z, zs) in [(5.001f32, 5.0f32), (5.5, 5.0), (6.0, 5.0), (9.0, 1.0)] {
        out.push(case("hit only (log path, floor)", hit_only, z, zs));
    }
    // The short component on the log-space path: no max or uniform weight, a narrow Gaussian
    // and a steep exponential, so the linear mixture underflows (below 1e-30) while the short
    // term `ln z_short + ln λ − λz − ln(1 − e^(−λz*))` is the largest (or, last pair, tied
    // with the hit term). A wrong sign or a dropped term in that expression moves these
    // values by tens of nats.
    let short_log = [0.5, 0.5, 0.0, 0.0, 0.01, 5.0, 40.0];
    for (z, zs) in [
        (20.0f32, 25.0f32),
        (30.0, 30.5),
        (24.84, 25.0),
        (36.0, 39.0),
    ] {
        out.push(case("short on the log path", short_log, z, zs));
    }
    let short_steep = [0.2, 0.8, 0.0, 0.0, 0.02, 50.0, 10.0];
    for (z, zs) in [(2.0f32, 2.5f32), (1.5, 2.0)] {
        out.push(case("short on the log path", short_steep, z, zs));
    }
    let wide = [0.5, 0.2, 0.1, 0.2, 50.0, 0.05, 20.0];
    for (z, zs) in [(0.0f32, 0.0f32), (19.0, 10.0), (3.0, 7.0)] {
        out.push(case("wide sigma", wide, z, zs));
    }
    // A fixed pseudo-random sample over valid intrinsics and readings.
    let mut rng = Lcg(0x6265_616d_6669_656c); // "beamfiel"
    for _ in 0..40 {
        let w = simplex(&mut rng);
        let sigma = rng.range(0.01, 2.0) as f32;
        let lambda = rng.range(0.05, 5.0) as f32;
        let zmax = rng.range(4.0, 40.0) as f32;
        let zs = rng.range(0.0, f64::from(zmax)) as f32;
        let z = if rng.unit() < 0.5 {
            // Near the wall, within a few σ.
            (f64::from(zs) + rng.range(-4.0, 4.0) * f64::from(sigma)).max(0.0) as f32
        } else {
            rng.range(0.0, 1.05 * f64::from(zmax)) as f32
        };
        out.push(case(
            "random",
            [w[0], w[1], w[2], w[3], sigma, lambda, zmax],
            z,
            zs,
        ));
    }
    out
}

fn f32_literal(x: f32) -> String {
    if x.is_nan() {
        "f32::NAN".to_string()
    } else if x == f32::INFINITY {
        "f32::INFINITY".to_string()
    } else if x == f32::NEG_INFINITY {
        "f32::NEG_INFINITY".to_string()
    } else {
        // `{:?}` prints the shortest decimal that reads back to the same f32.
        let s = format!("{x:?}");
        if s.contains('.') || s.contains('e') {
            s
        } else {
            format!("{s}.0")
        }
    }
}

/// The generated Rust source of `firmware/src/reference_cases.rs`.
pub fn render() -> String {
    let mut s = String::new();
    s.push_str(
        "//! Reference cases for the on-target check, GENERATED from the host's f64 reference\n\
         //! (`host-tests/src/firmware_cases.rs`). Do not edit: run `cargo xtask refcases`.\n\
         //! `cargo test -p host-tests --test target_checks` fails when this file is stale.\n\n\
         use crate::Case;\n\n",
    );
    let _ = writeln!(
        s,
        "/// Tolerance of each case: {TOL_ABS:e} nats + {TOL_REL:e} × |expected| \
         (budget in host-tests/src/firmware_cases.rs)."
    );
    s.push_str("#[rustfmt::skip]\npub const CASES: &[Case] = &[\n");
    for c in cases() {
        let p = c.intrinsics.map(f32_literal).join(", ");
        let expected = match c.expected {
            // 12 significant digits: far below every tolerance, and immune to last-ulp
            // differences between platforms' f64 exp/ln.
            Some(e) => format!("Some({e:.11e})"),
            None => "None".to_string(),
        };
        let _ = writeln!(
            s,
            "    Case {{ name: {:?}, intrinsics: [{p}], range_m: {}, z_star_m: {}, expected: {expected}, tolerance: {:.3e} }},",
            c.name,
            f32_literal(c.range_m),
            f32_literal(c.z_star_m),
            c.tolerance,
        );
    }
    s.push_str("];\n");
    s
}
