//! Reference values for the on-target (QEMU) check of the feature models: the landmark
//! log-likelihood (Table 6.4), the map correlation of a small grid (§6.5), and the first
//! poses the one-feature sampler (Table 6.5) draws from a fixed word stream.
//!
//! Every expected value is computed here in f64 from Thrun Tables 6.4–6.5 and §6.5 (`docs/models.md`)
//! (std's f64 math, not the crate's façade); inputs are f32 values widened exactly. The
//! integrator adds them to the firmware's generated reference cases (`render` gives the Rust
//! source of three `const` tables); `host-tests/tests/correlation.rs` checks the crate against
//! them on the host.
//!
//! # The random words
//! The sampler's generator on target must replay [`SAMPLER_WORDS`] (a `TryRng` whose
//! `next_u32` returns them in order): the crate draws, per pose, one word for `γ`
//! (`γ = 2π·(w >> 8)·2⁻²⁴`) and two for a Box–Muller pair (`u₁ = ((w₁ >> 8) + 1)·2⁻²⁴`,
//! `u₂ = (w₂ >> 8)·2⁻²⁴`, `ε = √(−2 ln u₁)·(cos, sin)(π(2u₂ − 1))`), as `src/gaussian.rs` and
//! `src/landmark/sample.rs` document. The words are chosen so that no range is redrawn.

use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;

/// Tolerance of a landmark log-likelihood, nats: `|got − expected| ≤ 1e-5 + 2e-6·|expected|`
/// (f32 `atan2`, `sqrt`, `ln` ≤ a few ulp each; the Mahalanobis term scales with `|expected|`).
pub const LANDMARK_TOL: (f64, f64) = (1e-5, 2e-6);
/// Tolerance of ρ: the crate's counts are exact, then one f32 division and two f32 `sqrt`.
pub const RHO_TOL: f64 = 1e-6;
/// Tolerance of a sampled pose coordinate (metres, radians): f32 `ln`, `sqrt`, `sin_cos` of
/// values ≤ 2π and ranges ≤ 10 m, a few ulp of 10 m.
pub const POSE_TOL: f64 = 1e-5;

/// `(feature r, φ, s)`, `(landmark x, y, s)`, `(pose x, y, θ)`, `(σ_r, σ_φ, σ_s)`.
pub type LandmarkInput = ([f32; 3], [f32; 3], [f32; 3], [f32; 3]);

/// One landmark case with its f64 log-likelihood.
#[derive(Clone, Debug, PartialEq)]
pub struct LandmarkCase {
    /// What it exercises.
    pub name: &'static str,
    /// The inputs.
    pub input: LandmarkInput,
    /// `ln q`, nats.
    pub expected: f64,
}

fn wrap(a: f64) -> f64 {
    let w = a - TAU * ((a + PI) / TAU).floor();
    if w >= PI {
        w - TAU
    } else {
        w
    }
}

fn ln_normal(residual: f64, sigma: f64) -> f64 {
    -0.5 * (residual / sigma).powi(2) - sigma.ln() - 0.5 * (2.0 * PI).ln()
}

/// `ln q` of Table 6.4 in f64.
pub fn landmark_ln_q(input: &LandmarkInput) -> f64 {
    let w = |v: [f32; 3]| v.map(f64::from);
    let (f, m, p, s) = (w(input.0), w(input.1), w(input.2), w(input.3));
    let r_hat = ((m[0] - p[0]).powi(2) + (m[1] - p[1]).powi(2)).sqrt();
    let phi_hat = (m[1] - p[1]).atan2(m[0] - p[0]) - p[2];
    ln_normal(f[0] - r_hat, s[0])
        + ln_normal(wrap(f[1] - phi_hat), s[1])
        + ln_normal(f[2] - m[2], s[2])
}

/// The landmark cases: on the nose, off in each component, and the wrap cases (a bearing of
/// 179° against a prediction of −179°, and headings beyond ±π).
pub fn landmark_cases() -> Vec<LandmarkCase> {
    let deg = std::f32::consts::PI / 180.0;
    let noise = [0.1f32, 0.05, 0.5];
    let inputs: [(&'static str, LandmarkInput); 6] = [
        (
            "exact",
            (
                [5.0, 0.6435011, 3.0],
                [4.0, 3.0, 3.0],
                [0.0, 0.0, 0.0],
                noise,
            ),
        ),
        (
            "range off",
            (
                [5.3, 0.6435011, 3.0],
                [4.0, 3.0, 3.0],
                [0.0, 0.0, 0.0],
                noise,
            ),
        ),
        (
            "signature off",
            (
                [5.0, 0.6435011, 4.0],
                [4.0, 3.0, 3.0],
                [0.0, 0.0, 0.0],
                noise,
            ),
        ),
        // Landmark behind-left: predicted bearing −179°, observed +179°: 2° apart.
        (
            "wrap 179 vs -179",
            (
                [2.0, 179.0 * deg, 1.0],
                [-2.0, -0.034_91, 1.0],
                [0.0, 0.0, 0.0],
                noise,
            ),
        ),
        (
            "heading beyond pi",
            (
                [3.0, -0.2, 0.0],
                [1.0, 2.0, 0.0],
                [-1.0, 0.5, 7.0],
                [0.2, 0.1, 1.0],
            ),
        ),
        (
            "far off",
            (
                [1.0, 3.0, 0.0],
                [10.0, -4.0, 2.0],
                [0.5, 0.5, -2.5],
                [0.05, 0.02, 0.3],
            ),
        ),
    ];
    inputs
        .into_iter()
        .map(|(name, input)| LandmarkCase {
            name,
            input,
            expected: landmark_ln_q(&input),
        })
        .collect()
}

/// The small correlation case: an 8 × 6 map of 0.5 m cells at origin (−1, −1) (`MAP`, row 0
/// at the bottom, `#` occupied), a 7 × 5 window, 8 beams.
pub struct CorrelationCase {
    /// Map rows, bottom row first; `#` = occupied.
    pub map: [&'static str; 6],
    /// Cell size, metres.
    pub cell_m: f32,
    /// Map origin, metres.
    pub origin_m: (f32, f32),
    /// Window width and height, cells.
    pub window: (u32, u32),
    /// First bearing and step, radians; maximum range, metres.
    pub bearings: (f32, f32, f32),
    /// Ranges, metres.
    pub ranges_m: [f32; 8],
    /// Robot pose (sensor centred).
    pub pose: [f32; 3],
    /// ρ by the f64 definition.
    pub expected_rho: f64,
}

/// The correlation case with its ρ computed in f64 from the definition (m̄ over both maps).
pub fn correlation_case() -> CorrelationCase {
    let map = [
        "########", "#......#", "#..##..#", "#......#", "#......#", "########",
    ];
    let (cell, origin, window) = (0.5f32, (-1.0f32, -1.0f32), (7u32, 5u32));
    let bearings = (-2.8f32, 0.8f32, 3.0f32);
    let ranges_m = [1.3f32, 1.6, 0.9, 2.0, 1.1, 3.5, f32::NAN, 1.45];
    let pose = [0.9f32, 0.6, 0.3];
    let occ = |ix: i64, iy: i64| -> f64 {
        if !(0..8).contains(&ix) || !(0..6).contains(&iy) {
            return 0.0;
        }
        f64::from(u8::from(map[iy as usize].as_bytes()[ix as usize] == b'#'))
    };
    let g = |v: f64, o: f32| (v - f64::from(o)) / f64::from(cell);
    let (px, py, pt) = (f64::from(pose[0]), f64::from(pose[1]), f64::from(pose[2]));
    let (ox, oy) = (
        g(px, origin.0).floor() as i64 - i64::from(window.0 / 2),
        g(py, origin.1).floor() as i64 - i64::from(window.1 / 2),
    );
    let n = (window.0 * window.1) as usize;
    let mut local = vec![0.0f64; n];
    for (k, &r) in ranges_m.iter().enumerate() {
        if r.is_nan() || r >= bearings.2 {
            continue;
        }
        let b = f64::from(bearings.0) + k as f64 * f64::from(bearings.1);
        let ex = g(px + f64::from(r) * (pt + b).cos(), origin.0).floor() as i64 - ox;
        let ey = g(py + f64::from(r) * (pt + b).sin(), origin.1).floor() as i64 - oy;
        if (0..i64::from(window.0)).contains(&ex) && (0..i64::from(window.1)).contains(&ey) {
            local[(ey * i64::from(window.0) + ex) as usize] = 1.0;
        }
    }
    let global: Vec<f64> = (0..n as i64)
        .map(|i| occ(ox + i % i64::from(window.0), oy + i / i64::from(window.0)))
        .collect();
    let mean = (global.iter().sum::<f64>() + local.iter().sum::<f64>()) / (2.0 * n as f64);
    let num: f64 = global
        .iter()
        .zip(&local)
        .map(|(a, b)| (a - mean) * (b - mean))
        .sum();
    let va: f64 = global.iter().map(|a| (a - mean).powi(2)).sum();
    let vb: f64 = local.iter().map(|b| (b - mean).powi(2)).sum();
    CorrelationCase {
        map,
        cell_m: cell,
        origin_m: origin,
        window,
        bearings,
        ranges_m,
        pose,
        expected_rho: num / (va * vb).sqrt(),
    }
}

/// The words the sampler's generator replays on target.
pub const SAMPLER_WORDS: [u32; 9] = [
    0x1234_5678,
    0x9ABC_DEF0,
    0x0F1E_2D3C,
    0x4B5A_6978,
    0xDEAD_BEEF,
    0x7FFF_FF00,
    0x3C3C_3C3C,
    0xA5A5_A5A5,
    0x0000_0100,
];

/// The sampler case: feature `(r, φ, s)`, landmark `(x, y, s)`, noise `(σ_r, σ_φ, σ_s)`.
pub const SAMPLER_INPUT: LandmarkInput = (
    [4.0, 0.5, 2.0],
    [1.5, -2.0, 2.0],
    [0.0, 0.0, 0.0],
    [0.2, 0.1, 1.0],
);

/// The three poses `sample_pose` must draw from [`SAMPLER_WORDS`], in f64 (Table 6.5).
pub fn sampler_poses() -> Vec<[f64; 3]> {
    let (f, m, _, s) = SAMPLER_INPUT;
    let u = |w: u32| f64::from(w >> 8) * 2f64.powi(-24);
    let u_oc = |w: u32| (f64::from(w >> 8) + 1.0) * 2f64.powi(-24);
    SAMPLER_WORDS
        .chunks_exact(3)
        .map(|w| {
            let gamma = TAU * u(w[0]);
            let radius = (-2.0 * u_oc(w[1]).ln()).sqrt();
            let alpha = PI * (2.0 * u(w[2]) - 1.0);
            let (er, ep) = (radius * alpha.cos(), radius * alpha.sin());
            let r = f64::from(f[0]) + f64::from(s[0]) * er;
            assert!(r >= 0.0, "a redraw would be needed: pick other words");
            let phi = f64::from(f[1]) + f64::from(s[1]) * ep;
            [
                f64::from(m[0]) + r * gamma.cos(),
                f64::from(m[1]) + r * gamma.sin(),
                wrap(gamma - PI - phi),
            ]
        })
        .collect()
}

fn lit(x: f32) -> String {
    if x.is_nan() {
        "f32::NAN".into()
    } else {
        format!("{x:?}f32")
    }
}

/// Rust source of the three tables, for the firmware's generated reference cases.
pub fn render() -> String {
    let mut s = String::from(
        "// Generated by host_tests::landmark_correlation_cases::render(); do not edit.\n",
    );
    let _ = writeln!(
        s,
        "/// (name, [feature r, φ, s], [landmark x, y, s], [pose x, y, θ], [σ_r, σ_φ, σ_s], ln q)\npub const LANDMARK_CASES: &[(&str, [f32; 3], [f32; 3], [f32; 3], [f32; 3], f64)] = &["
    );
    for c in landmark_cases() {
        let a = |v: [f32; 3]| format!("[{}, {}, {}]", lit(v[0]), lit(v[1]), lit(v[2]));
        let _ = writeln!(
            s,
            "    ({:?}, {}, {}, {}, {}, {:?}),",
            c.name,
            a(c.input.0),
            a(c.input.1),
            a(c.input.2),
            a(c.input.3),
            c.expected
        );
    }
    s.push_str("];\n");
    let c = correlation_case();
    let _ = writeln!(s, "/// Map rows (bottom first, '#' occupied), cell, origin, window, (first bearing, step, max range), ranges, pose, ρ.");
    let _ = writeln!(s, "pub const CORRELATION_MAP: [&str; 6] = {:?};", c.map);
    let _ = writeln!(
        s,
        "pub const CORRELATION_GEOMETRY: (f32, (f32, f32), (u32, u32), (f32, f32, f32)) = ({}, ({}, {}), ({}, {}), ({}, {}, {}));",
        lit(c.cell_m),
        lit(c.origin_m.0),
        lit(c.origin_m.1),
        c.window.0,
        c.window.1,
        lit(c.bearings.0),
        lit(c.bearings.1),
        lit(c.bearings.2)
    );
    let ranges: Vec<String> = c.ranges_m.iter().map(|&r| lit(r)).collect();
    let _ = writeln!(
        s,
        "pub const CORRELATION_RANGES: [f32; 8] = [{}];",
        ranges.join(", ")
    );
    let _ = writeln!(
        s,
        "pub const CORRELATION_POSE: [f32; 3] = [{}, {}, {}];\npub const CORRELATION_RHO: f64 = {:?};",
        lit(c.pose[0]),
        lit(c.pose[1]),
        lit(c.pose[2]),
        c.expected_rho
    );
    let words: Vec<String> = SAMPLER_WORDS.iter().map(|w| format!("{w:#010x}")).collect();
    let _ = writeln!(
        s,
        "pub const SAMPLER_WORDS: [u32; 9] = [{}];",
        words.join(", ")
    );
    let poses: Vec<String> = sampler_poses()
        .iter()
        .map(|p| format!("[{:?}, {:?}, {:?}]", p[0], p[1], p[2]))
        .collect();
    let _ = writeln!(
        s,
        "pub const SAMPLER_POSES: [[f64; 3]; 3] = [{}];",
        poses.join(", ")
    );
    s
}
