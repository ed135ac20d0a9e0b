//! Host side of the on-target model checks (`firmware/src/bin/models.rs`):
//! the generated `firmware/src/model_cases.rs` is current, and the host numbers it carries agree
//! with the independent f64 references, so "the target matches the host" also means "the target
//! matches the reference".

use host_tests::field_reference::{expected_distance, lf_term};
use host_tests::firmware_models::*;
use std::path::Path;

#[test]
fn model_cases_file_is_fresh() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(GENERATED_PATH);
    let on_disk = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        on_disk == render(),
        "{} is stale or missing: run `cargo xtask modelcases` and commit it",
        path.display()
    );
}

/// The tempered likelihood-field scores against the f64 reference: exact EDT by brute force,
/// the blob's quantization, the Table 6.3 term in f64, summed and divided by κ. Tolerance as in
/// `field_likelihood.rs`: 2e-6 relative + 1e-4 nats on the untempered sum (36 beams), /κ.
#[test]
fn tempered_room_scores_match_the_f64_reference() {
    let e = expected();
    let g = room_grid();
    let seeds = g.seeds();
    let scan = room_scan();
    let (zh, zr, s) = LF_PARAMS;
    for (stride, got) in [(1usize, &e.tempered), (3, &e.tempered_stride3)] {
        for (p, &got) in POSES.iter().zip(got.iter()) {
            let mut sum = 0.0f64;
            for k in (0..ROOM_BEAMS).step_by(stride) {
                let r = f64::from(scan[k]);
                if !(r >= 0.0 && r < f64::from(ROOM_MAX_RANGE_M)) {
                    continue;
                }
                let a = f64::from(p[2]) + f64::from((k as f32 * 10.0).to_radians());
                // The crate's bearings are f32 values of 10°·k; the angle sum is what matters
                // to ~1e-7 rad, far below a cell at these ranges.
                let x = f64::from(p[0]) + r * a.cos();
                let y = f64::from(p[1]) + r * a.sin();
                // The blob's code of the nearest on-map cell, plus the off-map distance rounded
                // to whole code steps, clamped at code 255 (documented in src/field/view.rs:
                // the term table is indexed by code, so the off-map charge is quantized too).
                let (gx, gy) = ((x - g.origin.0) / g.res, (y - g.origin.1) / g.res);
                let (cx, cy) = (
                    gx.clamp(0.0, g.width as f64),
                    gy.clamp(0.0, g.height as f64),
                );
                let off_m = ((gx - cx).powi(2) + (gy - cy).powi(2)).sqrt() * g.res;
                let on_map = (g.origin.0 + cx * g.res, g.origin.1 + cy * g.res);
                let (d_cell, _) = expected_distance(
                    &g,
                    &seeds,
                    on_map.0.min(g.origin.0 + (g.width as f64 - 0.5) * g.res),
                    on_map.1.min(g.origin.1 + (g.height as f64 - 0.5) * g.res),
                    1.0,
                );
                let step = 1.0 / 255.0;
                let code = (d_cell / step).round() + (off_m / step).round();
                let d_quantized = code.min(255.0) * step;
                sum += lf_term(
                    d_quantized,
                    f64::from(zh),
                    f64::from(zr),
                    f64::from(s),
                    f64::from(ROOM_MAX_RANGE_M),
                );
            }
            let want = sum / f64::from(KAPPA);
            let tol = (2e-6 * sum.abs() + 1e-4) / f64::from(KAPPA);
            assert!(
                (f64::from(got) - want).abs() <= tol,
                "stride {stride} pose {p:?}: {got} vs {want}"
            );
        }
    }
    // The truth scores best, and the weights are a distribution.
    assert_eq!(e.best, 0);
    let total: f32 = e.weights.iter().sum();
    assert!((total - 1.0).abs() < 1e-6);
    assert!(e.ess >= 1.0 && e.ess <= POSES.len() as f32);
    assert!(e.lag1.is_finite());
}

/// The landmark cases against Table 6.4 written out in f64.
#[test]
fn landmark_cases_match_the_f64_formula() {
    let e = expected();
    for ((f, l, p, q), &got) in LANDMARK_CASES.iter().zip(&e.landmark) {
        let f: Vec<f64> = f.iter().map(|&v| f64::from(v)).collect();
        let l: Vec<f64> = l.iter().map(|&v| f64::from(v)).collect();
        let p: Vec<f64> = p.iter().map(|&v| f64::from(v)).collect();
        let q: Vec<f64> = q.iter().map(|&v| f64::from(v)).collect();
        let (dx, dy) = (l[0] - p[0], l[1] - p[1]);
        let r_hat = dx.hypot(dy);
        let phi_hat = dy.atan2(dx) - p[2];
        let mut dphi = (f[1] - phi_hat).rem_euclid(std::f64::consts::TAU);
        if dphi >= std::f64::consts::PI {
            dphi -= std::f64::consts::TAU;
        }
        let lg = |e: f64, s: f64| {
            -0.5 * (e / s).powi(2) - (s * (2.0 * std::f64::consts::PI).sqrt()).ln()
        };
        let want = lg(f[0] - r_hat, q[0]) + lg(dphi, q[1]) + lg(f[2] - l[2], q[2]);
        // f32 evaluation: residuals to ~1e-6 of their scale, squared over σ².
        let tol = 1e-5 * want.abs().max(1.0);
        assert!(
            (f64::from(got) - want).abs() <= tol,
            "{f:?} {l:?} {p:?}: {got} vs {want}"
        );
    }
}

/// The correlation and sampler cases against the f64 values of `landmark_correlation_cases`.
#[test]
fn correlation_and_sampler_match_the_f64_values() {
    use host_tests::landmark_correlation_cases::{
        correlation_case, sampler_poses, POSE_TOL, RHO_TOL,
    };
    let e = expected();
    let want = correlation_case().expected_rho;
    assert!(
        (f64::from(e.rho) - want).abs() <= RHO_TOL,
        "{} vs {want}",
        e.rho
    );
    for (got, want) in e.sampled.iter().zip(sampler_poses()) {
        for (g, w) in got.iter().zip(want) {
            assert!((f64::from(*g) - w).abs() <= POSE_TOL, "{got:?} vs {want:?}");
        }
    }
}
