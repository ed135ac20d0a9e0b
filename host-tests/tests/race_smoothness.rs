//! Smoothness of the race (docs/race.md): the largest change of the log-likelihood between
//! neighbouring poses, beam model with ray casting (`BeamFieldModel`) against the likelihood
//! field, on the Intel lab map (the demo firmware's blob) with real scans at their logged poses.
//!
//! For every 10th scan of the log (91 scans) it walks lines of poses through the logged pose:
//! x and y offsets −20 … +20 cm in 1 cm steps, and heading offsets −10° … +10° in 1° steps, and
//! records, between each pair of neighbouring poses, the change of the whole-scan log-likelihood
//! and of each beam's term (nats). Both models use σ_hit 5.88 cm (EM-fitted on this log);
//! the beam model has the fitted weights, λ_short 0.07/m and z_max 81.83 m, the likelihood field
//! z_hit 0.95, z_rand 0.05.
//!
//! Run: `cargo test -p host-tests --release --test race_smoothness -- --nocapture` (prints the
//! table; docs/race.md quotes it).

use host_workloads::intel_race;

use beamfield::{BeamFieldModel, LikelihoodField, Pose, SensorModel, Stride};
use intel_race::{RaceData, N};

/// Half-width of the position walks, in 1 cm steps.
const XY_HALF_STEPS: i32 = 20;
/// Position step, metres.
const XY_STEP_M: f32 = 0.01;
/// Half-width of the heading walk, in 1° steps.
const TH_HALF_STEPS: i32 = 10;
/// Heading step, degrees.
const TH_STEP_DEG: f32 = 1.0;

/// One model's per-beam terms at a pose (0 for a beam the model does not score) and the total
/// the model itself reports.
trait Terms {
    fn terms(&self, data: &RaceData, k: usize, pose: &Pose, out: &mut [f32; N]) -> f32;
}

impl Terms for BeamFieldModel<'_> {
    fn terms(&self, data: &RaceData, k: usize, pose: &Pose, out: &mut [f32; N]) -> f32 {
        let (_, scan, _) = &data.scans[k];
        let mut z_star = [0.0f32; N];
        self.cast_layout(&data.layout, pose, Stride::ONE, &mut z_star);
        for ((o, &z), &zs) in out.iter_mut().zip(scan.ranges_m()).zip(&z_star) {
            *o = self.model().beam_log_likelihood(z, zs).unwrap_or(0.0);
        }
        self.score(&data.layout, scan, pose).log_likelihood
    }
}

impl Terms for LikelihoodField<'_> {
    fn terms(&self, data: &RaceData, k: usize, pose: &Pose, out: &mut [f32; N]) -> f32 {
        let (_, scan, _) = &data.scans[k];
        let mut d = [0.0f32; N];
        let score = self.score_into(&data.layout, scan, pose, &mut d);
        let step = self.view().step_m();
        for (o, &dist) in out.iter_mut().zip(&d) {
            *o = if dist.is_nan() {
                0.0
            } else {
                self.table()[(dist / step).round() as usize]
            };
        }
        score.log_likelihood
    }
}

/// What one model's walks along one axis gave.
#[derive(Default)]
struct Steps {
    /// |ΔLL| of the whole scan, every neighbouring pair of every scan.
    scan: Vec<f64>,
    /// Largest |ΔLL| per scan.
    per_scan_max: Vec<f64>,
    /// |Δ term| of every beam of every neighbouring pair.
    beam: Vec<f64>,
    /// Largest |Σ terms − reported total| seen, relative to the recursive-summation error bound
    /// of the model's f32 sum, `(n−1)·2⁻²⁴·Σ|terms|`: above 1 the terms are not what the model
    /// summed.
    sum_mismatch: f64,
}

fn walk<M: Terms>(m: &M, data: &RaceData, axis: usize) -> Steps {
    let mut st = Steps::default();
    let half = if axis == 2 {
        TH_HALF_STEPS
    } else {
        XY_HALF_STEPS
    };
    for (k, (_, _, p0)) in data.scans.iter().enumerate() {
        let mut prev: Option<(f32, [f32; N])> = None;
        let mut scan_max = 0.0f64;
        for i in -half..=half {
            let mut p = *p0;
            match axis {
                0 => p.x_m += i as f32 * XY_STEP_M,
                1 => p.y_m += i as f32 * XY_STEP_M,
                _ => p.theta_rad += (i as f32 * TH_STEP_DEG).to_radians(),
            }
            let mut t = [0.0f32; N];
            let total = m.terms(data, k, &p, &mut t);
            assert!(total.is_finite(), "scan {k} pose {p:?}: {total}");
            let sum: f64 = t.iter().map(|&x| f64::from(x)).sum();
            let abs: f64 = t.iter().map(|&x| f64::from(x).abs()).sum();
            assert!(t.iter().all(|x| x.is_finite()));
            let bound = (N - 1) as f64 * f64::from(f32::EPSILON) / 2.0 * abs;
            st.sum_mismatch = st.sum_mismatch.max((sum - f64::from(total)).abs() / bound);
            if let Some((pt, pterms)) = &prev {
                let d = f64::from((total - pt).abs());
                st.scan.push(d);
                scan_max = scan_max.max(d);
                for (a, b) in t.iter().zip(pterms) {
                    st.beam.push(f64::from((a - b).abs()));
                }
            }
            prev = Some((total, t));
        }
        st.per_scan_max.push(scan_max);
    }
    st
}

fn quantile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

#[derive(Clone)]
struct Row {
    max_scan: f64,
    median_scan_max: f64,
    mean_scan: f64,
    max_beam: f64,
    p99_beam: f64,
    frac_beam_over_1: f64,
}

fn row(mut s: Steps) -> Row {
    let mean_scan = s.scan.iter().sum::<f64>() / s.scan.len() as f64;
    let frac = s.beam.iter().filter(|&&d| d > 1.0).count() as f64 / s.beam.len() as f64;
    Row {
        max_scan: quantile(&mut s.scan, 1.0),
        median_scan_max: quantile(&mut s.per_scan_max, 0.5),
        mean_scan,
        max_beam: quantile(&mut s.beam, 1.0),
        p99_beam: quantile(&mut s.beam, 0.99),
        frac_beam_over_1: frac,
    }
}

/// The table for one parameter set; returns the rows `(walk, model, row)`.
fn table(
    data: &RaceData,
    title: &str,
    beam: &BeamFieldModel<'_>,
    field: &LikelihoodField<'_>,
) -> Vec<(usize, &'static str, Row)> {
    println!(
        "\n{title}: {} scans (every {}th of the log) x {N} beams; walks: x, y ±{} cm step 1 cm, θ ±{}° step 1°",
        data.scans.len(),
        intel_race::SCAN_EVERY,
        XY_HALF_STEPS,
        TH_HALF_STEPS
    );
    println!(
        "| model | walk | max |ΔLL| scan | median of per-scan max | mean |ΔLL| scan | max |Δ| beam | p99 |Δ| beam | beam steps > 1 nat |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let mut rows = Vec::new();
    for (axis, name) in ["x, 1 cm", "y, 1 cm", "θ, 1°"].into_iter().enumerate() {
        let b = walk(beam, data, axis);
        let f = walk(field, data, axis);
        // Cross-check of the per-beam terms against the models' own f32 totals: within the
        // summation error bound.
        assert!(
            b.sum_mismatch <= 1.0,
            "beam terms vs total: {}",
            b.sum_mismatch
        );
        assert!(
            f.sum_mismatch <= 1.0,
            "field terms vs total: {}",
            f.sum_mismatch
        );
        for (model, s) in [("beam model", b), ("likelihood field", f)] {
            let r = row(s);
            println!(
                "| {model} | {name} | {:.2} | {:.2} | {:.3} | {:.2} | {:.3} | {:.4} % |",
                r.max_scan,
                r.median_scan_max,
                r.mean_scan,
                r.max_beam,
                r.p99_beam,
                100.0 * r.frac_beam_over_1
            );
            assert!(r.max_scan.is_finite() && r.max_beam.is_finite());
            rows.push((axis, model, r));
        }
    }
    rows
}

#[test]
fn likelihood_steps_between_neighbouring_poses() {
    let data = intel_race::load();
    let (beam, field) = intel_race::models(&data);
    let fitted = table(&data, "σ_hit 5.88 cm (fitted)", &beam, &field);
    let (beam, field) = intel_race::models_amcl(&data);
    let amcl = table(&data, "σ_hit 20 cm (AMCL defaults)", &beam, &field);
    let pairs = |rows: &[(usize, &'static str, Row)]| -> Vec<(usize, Row, Row)> {
        let mut out = Vec::new();
        for axis in 0..3 {
            let get = |m: &str| rows.iter().position(|(a, mm, _)| *a == axis && *mm == m);
            let (b, f) = (get("beam model").unwrap(), get("likelihood field").unwrap());
            out.push((axis, rows[b].2.clone(), rows[f].2.clone()));
        }
        out
    };
    // The chapter's prediction (§6.4), at AMCL's σ_hit of 20 cm (four cells): the likelihood
    // field is smoother by every measure, on every walk.
    for (axis, b, f) in pairs(&amcl) {
        assert!(f.max_scan < b.max_scan, "walk {axis}: largest scan step");
        assert!(f.median_scan_max < b.median_scan_max, "walk {axis}");
        assert!(f.mean_scan < b.mean_scan, "walk {axis}: mean scan step");
        assert!(f.max_beam < b.max_beam, "walk {axis}: largest beam step");
        assert!(f.p99_beam < b.p99_beam, "walk {axis}: p99 beam step");
    }
    // At the fitted σ_hit of 5.88 cm (about one cell) the typical step is still smaller for the
    // likelihood field, but its *largest* whole-scan step in x and y is larger than the beam
    // model's (measured: 164 vs 98 nats in x, 135 vs 103 in y): the field is constant over each
    // 5 cm cell, so a 1 cm move that carries many end points across cell edges at once jumps,
    // and at σ ≈ one cell such a jump is worth ~1–3 nats per beam. Not asserted either way;
    // docs/race.md reports it.
    for (axis, b, f) in pairs(&fitted) {
        assert!(f.mean_scan < b.mean_scan, "walk {axis}: mean scan step");
        assert!(f.p99_beam < b.p99_beam, "walk {axis}: p99 beam step");
    }
}
