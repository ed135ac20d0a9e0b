//! The landmark model (Thrun Table 6.4) and the two-feature proposal against independent f64
//! computations: the wrap cases, an f64 log-likelihood from docs/models.md#features, and exact
//! recovery of known poses from two noiseless features.
//!
//! Tolerances are first-order f32 error models stated next to each check (ε = 2⁻²³), with a
//! safety factor of 2, never fitted to the observed errors; the largest observed error as a
//! fraction of its bound is printed (`cargo test -p host-tests --test landmark -- --nocapture`).

use beamfield::landmark::{
    likelihood, log_likelihood, residual, two_feature_poses, Feature, FeatureNoise,
    IntersectionError, Landmark,
};
use beamfield::Pose;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::f64::consts::{PI, TAU};

const EPS: f64 = f32::EPSILON as f64;
const DEG: f64 = PI / 180.0;

/// Uniform f64 in `[lo, hi)` from the top 53 bits of one `next_u64`.
fn unif(rng: &mut StdRng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * ((rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
}

/// `x` wrapped into `[−π, π)`, f64, written independently of the crate.
fn wrap64(x: f64) -> f64 {
    (x + PI).rem_euclid(TAU) - PI
}

/// The f64 reference of Table 6.4 (docs/models.md#features), from the f32 inputs widened exactly.
/// Returns the log-likelihood and the three residuals.
fn reference_ll(f: [f32; 3], l: [f32; 3], p: [f32; 3], s: [f32; 3]) -> (f64, [f64; 3]) {
    let [r, phi, sig] = f.map(f64::from);
    let [mx, my, sj] = l.map(f64::from);
    let [x, y, th] = p.map(f64::from);
    let (dx, dy) = (mx - x, my - y);
    let r_hat = dx.hypot(dy);
    let phi_hat = dy.atan2(dx) - th;
    let e = [r - r_hat, wrap64(phi - phi_hat), sig - sj];
    let ll = e
        .iter()
        .zip(s.map(f64::from))
        .map(|(e, s)| -0.5 * (e / s).powi(2) - (s * (2.0 * PI).sqrt()).ln())
        .sum();
    (ll, e)
}

fn ll32(f: [f32; 3], l: [f32; 3], p: [f32; 3], s: [f32; 3]) -> f32 {
    let noise = FeatureNoise::new(s[0], s[1], s[2]).unwrap();
    log_likelihood(
        &Feature::new(f[0], f[1], f[2]).unwrap(),
        &Landmark::new(l[0], l[1], l[2]).unwrap(),
        &Pose::new(p[0], p[1], p[2]),
        &noise,
    )
}

#[test]
fn bearings_179_and_minus_179_degrees_are_2_degrees_apart() {
    // Robot at the origin facing +x; landmark 5 m away at world bearing −179°: φ̂ = −179°.
    let lm = Landmark::new(
        (5.0 * (-179.0 * DEG).cos()) as f32,
        (5.0 * (-179.0 * DEG).sin()) as f32,
        0.0,
    )
    .unwrap();
    let pose = Pose::new(0.0, 0.0, 0.0);
    let f = Feature::new(5.0, (179.0 * DEG) as f32, 0.0).unwrap();
    let e = residual(&f, &lm, &pose);
    assert!(
        (f64::from(e.bearing_rad) + 2.0 * DEG).abs() < 1e-5,
        "wrap(179° − (−179°)) = {} rad, want −2°",
        e.bearing_rad
    );
    // And the likelihood is the one of a 2° residual, not of a 358° one.
    let noise = FeatureNoise::new(0.1, (3.0 * DEG) as f32, 1.0).unwrap();
    let ll = f64::from(log_likelihood(&f, &lm, &pose, &noise));
    let want = -0.5 * (2.0 / 3.0f64).powi(2) - (0.1f64 * (3.0 * DEG) * 1.0).ln() - 1.5 * TAU.ln();
    assert!((ll - want).abs() < 1e-4, "ll {ll} want {want}");
    // The mirrored case: a feature at −179° against a landmark predicted at +179°.
    let lm2 = Landmark::new(lm.x_m(), -lm.y_m(), 0.0).unwrap();
    let f2 = Feature::new(5.0, (-179.0 * DEG) as f32, 0.0).unwrap();
    let ll2 = f64::from(log_likelihood(&f2, &lm2, &pose, &noise));
    assert!((ll2 - want).abs() < 1e-4, "mirrored ll {ll2} want {want}");
}

#[test]
fn log_likelihood_is_symmetric_and_continuous_across_the_wrap() {
    let lm = [2.0f32, 1.0, 3.0];
    let pose = [-1.0f32, 0.5, 2.9];
    let phi_hat = {
        let (dx, dy) = (f64::from(lm[0] - pose[0]), f64::from(lm[1] - pose[1]));
        dy.atan2(dx) - f64::from(pose[2])
    };
    let sig = [0.2f32, 0.4, 1.0];
    let r = 3.2f32;
    // Residuals ±δ for δ from 0 to just under π (and the crossing at ±π): equal likelihoods.
    for delta in [0.0, 0.1, 1.0, 2.0, 3.0, PI - 1e-3, PI - 1e-5] {
        let plus = ll32([r, (phi_hat + delta) as f32, 3.0], lm, pose, sig);
        let minus = ll32([r, (phi_hat - delta) as f32, 3.0], lm, pose, sig);
        let (want, _) = reference_ll([r, (phi_hat + delta) as f32, 3.0], lm, pose, sig);
        // |ll| ≤ 35 here; bearings near 3 rad carry ~4ε·π of rounding, through ∂ll/∂e = e/σ².
        let tol = 2.0 * (4.0 * EPS * 35.0 + (delta / 0.16) * 8.0 * EPS * PI);
        assert!(
            (f64::from(plus) - f64::from(minus)).abs() <= tol,
            "δ = {delta}: +δ {plus}, −δ {minus}"
        );
        assert!(
            (f64::from(plus) - want).abs() <= tol,
            "δ = {delta}: {plus} vs {want}"
        );
    }
    // Crossing the wrap point: residual π − 1e-3 and −π + 1e-3 (= π + 1e-3 unwrapped) are both
    // π − 1e-3 away from zero in magnitude, so they score the same.
    let a = ll32([r, (phi_hat + PI - 1e-3) as f32, 3.0], lm, pose, sig);
    let b = ll32([r, (phi_hat + PI + 1e-3) as f32, 3.0], lm, pose, sig);
    assert!((a - b).abs() < 1e-4, "{a} vs {b}");
    // A bearing given 2πk away is the same feature.
    let base = ll32([r, phi_hat as f32, 3.0], lm, pose, sig);
    for k in -3..=3 {
        let shifted = ll32(
            [r, (phi_hat + f64::from(k) * TAU) as f32, 3.0],
            lm,
            pose,
            sig,
        );
        assert!(
            (shifted - base).abs() < 1e-4,
            "k = {k}: {shifted} vs {base}"
        );
    }
}

#[test]
fn log_likelihood_matches_f64_reference() {
    let mut rng = StdRng::seed_from_u64(0x1a4d_0001);
    let mut worst = 0.0f64;
    let n = 100_000;
    for _ in 0..n {
        let s = [
            unif(&mut rng, 0.01, 1.0) as f32,
            unif(&mut rng, 0.005, 0.5) as f32,
            unif(&mut rng, 0.1, 5.0) as f32,
        ];
        let l = [
            unif(&mut rng, -20.0, 20.0) as f32,
            unif(&mut rng, -20.0, 20.0) as f32,
            unif(&mut rng, -10.0, 10.0) as f32,
        ];
        let p = [
            unif(&mut rng, -20.0, 20.0) as f32,
            unif(&mut rng, -20.0, 20.0) as f32,
            unif(&mut rng, -10.0, 10.0) as f32,
        ];
        // A feature near the truth (residuals up to ~6σ), bearings given up to ±2 turns away.
        let (dx, dy) = (f64::from(l[0] - p[0]), f64::from(l[1] - p[1]));
        let r = (dx.hypot(dy) + unif(&mut rng, -6.0, 6.0) * f64::from(s[0])).max(0.0);
        let turns = (unif(&mut rng, -2.0, 3.0).floor()) * TAU;
        let phi = dy.atan2(dx) - f64::from(p[2]) + unif(&mut rng, -6.0, 6.0) * f64::from(s[1]);
        let f = [
            r as f32,
            (wrap64(phi) + turns) as f32,
            (f64::from(l[2]) + unif(&mut rng, -6.0, 6.0) * f64::from(s[2])) as f32,
        ];
        let got = f64::from(ll32(f, l, p, s));
        let (want, e) = reference_ll(f, l, p, s);
        // Error model: dx, dy, hypot and the range residual round at the coordinates' scale;
        // atan2 (≤ 2.4e-7), the subtraction of θ and φ and the wrap round at the angles' scale.
        let scale_xy =
            f64::from(l[0].abs() + l[1].abs() + p[0].abs() + p[1].abs()) + f64::from(f[0]);
        let d_range = 4.0 * EPS * scale_xy;
        let scale_ang = PI + f64::from(p[2].abs()) + f64::from(f[1].abs());
        let d_bearing = 2.4e-7 + EPS * scale_xy / (dx.hypot(dy) + 1e-3) + 4.0 * EPS * scale_ang;
        let d_sig = 2.0 * EPS * f64::from(f[2].abs() + l[2].abs());
        let d = [d_range, d_bearing, d_sig];
        let sum_abs_ln: f64 = s.iter().map(|s| f64::from(*s).ln().abs()).sum::<f64>() + 3.0;
        let mut bound = 4.0 * EPS * (want.abs() + sum_abs_ln);
        for i in 0..3 {
            let si = f64::from(s[i]);
            let t = (e[i] / si).powi(2);
            bound += e[i].abs() / (si * si) * d[i] + 3.0 * EPS * t;
        }
        bound *= 2.0;
        let err = (got - want).abs();
        assert!(
            err <= bound,
            "f {f:?} l {l:?} p {p:?} s {s:?}: {got} vs {want} (err {err:e} > {bound:e})"
        );
        worst = worst.max(err / bound);
    }
    println!("log-likelihood vs f64 over {n} cases: worst error = {worst:.3} of its bound");
}

#[test]
fn likelihood_is_exp_and_underflows_to_zero_as_documented() {
    let noise = FeatureNoise::new(0.1, 0.05, 1.0).unwrap();
    let lm = Landmark::new(4.0, 0.0, 0.0).unwrap();
    let pose = Pose::new(0.0, 0.0, 0.0);
    let mut seen_zero = false;
    let mut seen_positive = false;
    for k in 0..400 {
        let r = 4.0 + k as f32 * 0.01; // residuals 0 … 40σ
        let f = Feature::new(r, 0.0, 0.0).unwrap();
        let ll = log_likelihood(&f, &lm, &pose, &noise);
        let q = likelihood(&f, &lm, &pose, &noise);
        let want = f64::from(ll).exp();
        if ll < -103.98 {
            assert_eq!(q, 0.0, "ll {ll}");
            seen_zero = true;
        } else if ll > -87.3 {
            // Normal range: exp's relative error plus ll's own rounding (≤ 1e-6·|ll|).
            assert!(q > 0.0);
            let rel = (f64::from(q) - want).abs() / want;
            assert!(rel < 2.0 * (2.0 * EPS), "ll {ll}: {q} vs {want}");
            seen_positive = true;
        }
    }
    assert!(seen_zero && seen_positive);
}

// ---------------------------------------------------------------------------------------------
// Two-feature proposal, noiseless.

/// Exact features of landmark `l` seen from `p` (f64 geometry, rounded once to f32).
fn observe(l: [f64; 2], p: [f64; 3]) -> Feature {
    let (dx, dy) = (l[0] - p[0], l[1] - p[1]);
    Feature::new(dx.hypot(dy) as f32, wrap64(dy.atan2(dx) - p[2]) as f32, 0.0).unwrap()
}

fn landmark(l: [f64; 2]) -> Landmark {
    Landmark::new(l[0] as f32, l[1] as f32, 0.0).unwrap()
}

#[test]
fn two_features_recover_a_known_pose_exactly() {
    let mut rng = StdRng::seed_from_u64(0x1a4d_0002);
    let (mut worst_pos, mut worst_head) = (0.0f64, 0.0f64);
    let (mut tested, mut skipped, mut best_checked) = (0, 0, 0);
    while tested < 20_000 {
        // Landmarks and the pose on the f32 grid, so the reference geometry is exact for them.
        let l1 = [
            unif(&mut rng, -15.0, 15.0) as f32 as f64,
            unif(&mut rng, -15.0, 15.0) as f32 as f64,
        ];
        let l2 = [
            unif(&mut rng, -15.0, 15.0) as f32 as f64,
            unif(&mut rng, -15.0, 15.0) as f32 as f64,
        ];
        let p = [
            unif(&mut rng, -15.0, 15.0) as f32 as f64,
            unif(&mut rng, -15.0, 15.0) as f32 as f64,
            unif(&mut rng, -PI, PI) as f32 as f64,
        ];
        let d = (l2[0] - l1[0]).hypot(l2[1] - l1[1]);
        let r1 = (l1[0] - p[0]).hypot(l1[1] - p[1]);
        let r2 = (l2[0] - p[0]).hypot(l2[1] - p[1]);
        // Distance of the pose from the line through the landmarks: the circles' half-chord h.
        let h = ((l2[0] - l1[0]) * (p[1] - l1[1]) - (l2[1] - l1[1]) * (p[0] - l1[0])).abs() / d;
        // Near-collinear poses (h → 0, a tangency) are ill-conditioned by nature: tested below
        // separately. Keep h ≥ 0.05 m and landmarks ≥ 0.5 m apart and from the robot.
        if h < 0.05 || d < 0.5 || r1 < 0.5 || r2 < 0.5 {
            skipped += 1;
            continue;
        }
        tested += 1;
        let (f1, f2) = (observe(l1, p), observe(l2, p));
        let got = two_feature_poses(&f1, &landmark(l1), &f2, &landmark(l2)).unwrap();
        assert_eq!(got.len(), 2);
        let rmax = r1.max(r2);
        let dist = |c: &beamfield::landmark::PoseCandidate| {
            (f64::from(c.pose.x_m) - p[0]).hypot(f64::from(c.pose.y_m) - p[1])
        };
        let truth = got
            .as_slice()
            .iter()
            .min_by(|a, b| dist(a).total_cmp(&dist(b)))
            .unwrap();
        // Error model: ranges rounded to f32 (ε/2·r) and the f32 arithmetic of a (relative error
        // of a few ε at scale r²/d) and h (δ(h²)/(2h) with δ(h²) ~ ε·r²): δp ≈ ε·r·(r/d + r/h).
        // Coordinates add ε·|c|. Safety factor 2 over a constant of 16.
        let scale = rmax + l1[0].abs().max(l1[1].abs()) + 1.0;
        let pos_bound = 2.0 * 16.0 * EPS * scale * (1.0 + rmax / d + rmax / h);
        let pos_err = dist(truth);
        assert!(
            pos_err <= pos_bound,
            "l1 {l1:?} l2 {l2:?} p {p:?}: position off by {pos_err:e} > {pos_bound:e}"
        );
        // Heading: the position error seen from the nearer landmark, plus angle rounding.
        let head_bound = 2.0 * (pos_bound / r1.min(r2) + 8.0 * EPS * PI);
        let head_err = wrap64(f64::from(truth.pose.theta_rad) - p[2]).abs();
        assert!(
            head_err <= head_bound,
            "heading off by {head_err:e} > {head_bound:e}"
        );
        assert!(f64::from(truth.heading_spread_rad) <= 2.0 * head_bound);
        worst_pos = worst_pos.max(pos_err / pos_bound);
        worst_head = worst_head.max(head_err / head_bound);
        // The other candidate is the mirror image across the landmark line; its implied
        // headings disagree unless the geometry is symmetric. Where they clearly do, best()
        // must pick the truth.
        let mirror = got
            .as_slice()
            .iter()
            .find(|c| !std::ptr::eq(*c, truth))
            .unwrap();
        if mirror.heading_spread_rad > 1e-3 {
            best_checked += 1;
            assert_eq!(got.best(), *truth);
        }
    }
    assert!(best_checked > tested / 2, "{best_checked}");
    println!(
        "two-feature exact recovery: {tested} poses ({skipped} near-degenerate skipped); worst \
         position error {worst_pos:.3} of bound, heading {worst_head:.3} of bound; best() picked \
         the truth in all {best_checked} cases with mirror spread > 1e-3 rad"
    );
}

#[test]
fn tangent_circles_give_one_candidate() {
    // External tangency: landmarks 4 m apart, ranges 1 and 3: the point (1, 0).
    let (l1, l2) = (
        Landmark::new(0.0, 0.0, 0.0).unwrap(),
        Landmark::new(4.0, 0.0, 0.0).unwrap(),
    );
    // Robot at (1, 0) facing +y (θ = π/2): l1 lies at world bearing π, relative +π/2; l2 at
    // world bearing 0, relative −π/2.
    let f1 = Feature::new(1.0, core::f32::consts::FRAC_PI_2, 0.0).unwrap();
    let f2 = Feature::new(3.0, -core::f32::consts::FRAC_PI_2, 0.0).unwrap();
    let got = two_feature_poses(&f1, &l1, &f2, &l2).unwrap();
    assert_eq!(got.len(), 1);
    let c = got.best();
    assert!(
        (c.pose.x_m - 1.0).abs() < 1e-6 && c.pose.y_m.abs() < 1e-6,
        "{c:?}"
    );
    // l1 at world bearing π from (1, 0), seen at +π/2: heading π/2. Same from l2 (0 − (−π/2)).
    assert!(
        (c.pose.theta_rad - core::f32::consts::FRAC_PI_2).abs() < 1e-6,
        "{c:?}"
    );
    assert!(c.heading_spread_rad < 1e-6);
    // Internal tangency: landmarks 1 m apart, ranges 3 and 2: the point (3, 0).
    let l2 = Landmark::new(1.0, 0.0, 0.0).unwrap();
    let f1 = Feature::new(3.0, 0.0, 0.0).unwrap();
    let f2 = Feature::new(2.0, 0.0, 0.0).unwrap();
    let got = two_feature_poses(&f1, &l1, &f2, &l2).unwrap();
    assert_eq!(got.len(), 1);
    let c = got.best();
    assert!(
        (c.pose.x_m - 3.0).abs() < 1e-6 && c.pose.y_m.abs() < 1e-6,
        "{c:?}"
    );
    // Both landmarks straight behind (world bearing π, relative 0): heading π ≡ −π.
    assert!(
        (c.pose.theta_rad.abs() - core::f32::consts::PI).abs() < 1e-6,
        "{c:?}"
    );
}

#[test]
fn a_zero_range_feature_pins_the_position_and_leaves_the_heading_to_the_other() {
    // The robot sits on landmark 1 (range 0, bearing meaningless: given as 2.0 on purpose) and
    // sees landmark 2, 3 m east, at bearing 0.5 rad: position (0, 0), heading −0.5 rad.
    let (l1, l2) = (
        Landmark::new(0.0, 0.0, 0.0).unwrap(),
        Landmark::new(3.0, 0.0, 0.0).unwrap(),
    );
    let f1 = Feature::new(0.0, 2.0, 0.0).unwrap();
    let f2 = Feature::new(3.0, 0.5, 0.0).unwrap();
    let got = two_feature_poses(&f1, &l1, &f2, &l2).unwrap();
    assert_eq!(got.len(), 1);
    let c = got.best();
    assert_eq!((c.pose.x_m, c.pose.y_m), (0.0, 0.0));
    assert!((c.pose.theta_rad + 0.5).abs() < 1e-6, "{c:?}");
    assert_eq!(c.heading_spread_rad, 0.0);
    // Swapped order: the same answer.
    let got = two_feature_poses(&f2, &l2, &f1, &l1).unwrap().best();
    assert!(
        got.pose.x_m.abs() < 1e-6 && got.pose.y_m.abs() < 1e-6,
        "{got:?}"
    );
    assert!((got.pose.theta_rad + 0.5).abs() < 1e-6, "{got:?}");
}

#[test]
fn two_features_report_no_intersection() {
    let l1 = Landmark::new(0.0, 0.0, 0.0).unwrap();
    let l2 = Landmark::new(10.0, 0.0, 0.0).unwrap();
    let f = |r: f32| Feature::new(r, 0.0, 0.0).unwrap();
    // 10 m apart, ranges 4 + 5 < 10.
    assert_eq!(
        two_feature_poses(&f(4.0), &l1, &f(5.0), &l2),
        Err(IntersectionError::CirclesApart)
    );
    // Just apart: 4.99 + 5 < 10 by 1 cm.
    assert_eq!(
        two_feature_poses(&f(4.99), &l1, &f(5.0), &l2),
        Err(IntersectionError::CirclesApart)
    );
    // Nested: ranges 20 and 5, 10 m apart: 20 − 5 > 10.
    assert_eq!(
        two_feature_poses(&f(20.0), &l1, &f(5.0), &l2),
        Err(IntersectionError::CircleInside)
    );
    assert_eq!(
        two_feature_poses(&f(5.0), &l1, &f(20.0), &l2),
        Err(IntersectionError::CircleInside)
    );
    // The same landmark twice (or two at one place): concentric, whatever the ranges.
    for (r1, r2) in [(3.0, 3.0), (3.0, 4.0), (0.0, 0.0)] {
        assert_eq!(
            two_feature_poses(&f(r1), &l1, &f(r2), &l1),
            Err(IntersectionError::Concentric),
            "{r1} {r2}"
        );
    }
    // Just intersecting: 5.01 + 5 > 10 gives two candidates, 2·√(5.01² − a²) apart.
    let got = two_feature_poses(&f(5.01), &l1, &f(5.0), &l2).unwrap();
    assert_eq!(got.len(), 2);
    let [a, b] = [got.as_slice()[0].pose, got.as_slice()[1].pose];
    let a_ref = (100.0 + 5.01f64 * 5.01 - 25.0) / 20.0;
    let h_ref = (5.01f64 * 5.01 - a_ref * a_ref).sqrt();
    assert!((f64::from(a.x_m) - a_ref).abs() < 1e-5 && (f64::from(b.x_m) - a_ref).abs() < 1e-5);
    assert!(
        (f64::from(a.y_m) - h_ref).abs() < 1e-4,
        "{a:?} vs h {h_ref}"
    );
    assert!(
        (f64::from(b.y_m) + h_ref).abs() < 1e-4,
        "{b:?} vs h {h_ref}"
    );
}
