//! The model cases the second on-target program runs (`firmware/src/bin/models.rs`): the
//! tempered likelihood field over a blob linked into the firmware, weight normalization and the
//! lag-1 diagnostic, landmark log-likelihoods (Table 6.4) and a crosstalk-aware sonar scan.
//!
//! The inputs are fixed here; the expected values are what the crate computes on the host, so
//! the firmware checks that the emulated Cortex-M4F gives the host's numbers (within 1e-5
//! relative). `host-tests/tests/target_models.rs` ties the host's numbers to the independent
//! f64 references and fails when the generated file `firmware/src/model_cases.rs` is stale
//! (`cargo xtask modelcases` rewrites it).

use crate::field_reference::{self, Grid};
use crate::landmark_correlation_cases::{correlation_case, SAMPLER_INPUT, SAMPLER_WORDS};
use beamfield::landmark::sample_pose;
use beamfield::landmark::{log_likelihood, Feature, FeatureNoise, Landmark};
use beamfield::sonar::{CrosstalkModel, Ring, Schedule, SonarModel};
use beamfield::{
    edt_scratch_len, emit_blob_from_squared_cells, normalize_log_weights, squared_edt,
    BeamIntrinsics, BeamLayout, EdtScratch, FieldHeader, FieldView, Lag1, LikelihoodField,
    LikelihoodParams, Pose, Scan, SensorModel, SensorMount, Tempered, EDT_INFINITY,
};
use beamfield::{emit_blob, MapCorrelation};
use std::fmt::Write as _;

/// Path of the generated file, relative to the repository root.
pub const GENERATED_PATH: &str = "firmware/src/model_cases.rs";

/// Room: 60 × 50 cells of 5 cm, origin (−1.0, −0.5) m.
pub const ROOM_W: usize = 60;
/// Room height, cells.
pub const ROOM_H: usize = 50;
/// Cell size, metres.
pub const ROOM_RES: f32 = 0.05;
/// Room origin, metres.
pub const ROOM_ORIGIN: (f32, f32) = (-1.0, -0.5);
/// Beams of the room scan (10° apart, full circle).
pub const ROOM_BEAMS: usize = 36;
/// Range limit of the room scan, metres.
pub const ROOM_MAX_RANGE_M: f32 = 8.0;
/// Likelihood-field parameters `(z_hit, z_rand, sigma_hit_m)`.
pub const LF_PARAMS: (f32, f32, f32) = (0.9, 0.1, 0.1);
/// Tempering κ.
pub const KAPPA: f32 = 4.0;
/// The true pose of the room scan.
pub const TRUE_POSE: [f32; 3] = [0.55, 0.7, 0.3];
/// Pose hypotheses scored (the truth first).
pub const POSES: [[f32; 3]; 5] = [
    TRUE_POSE,
    [0.60, 0.7, 0.3],
    [0.55, 0.62, 0.3],
    [0.55, 0.7, 0.35],
    [0.45, 0.8, 0.2],
];

/// The room's occupancy: border walls, a pillar, and an inner wall.
pub fn room_grid() -> Grid {
    let mut occ = vec![false; ROOM_W * ROOM_H];
    for iy in 0..ROOM_H {
        for ix in 0..ROOM_W {
            let border = ix == 0 || iy == 0 || ix == ROOM_W - 1 || iy == ROOM_H - 1;
            let pillar = (20..24).contains(&ix) && (20..24).contains(&iy);
            let inner = iy == 35 && (30..50).contains(&ix);
            occ[iy * ROOM_W + ix] = border || pillar || inner;
        }
    }
    Grid {
        width: ROOM_W,
        height: ROOM_H,
        res: f64::from(ROOM_RES),
        origin: (f64::from(ROOM_ORIGIN.0), f64::from(ROOM_ORIGIN.1)),
        occupied: occ,
    }
}

/// The room's distance-field blob (d_max 1 m), built with the crate's exact transform.
pub fn room_blob() -> Vec<u8> {
    let g = room_grid();
    let mut sq: Vec<u32> = g
        .occupied
        .iter()
        .map(|&o| if o { 0 } else { EDT_INFINITY })
        .collect();
    let n = edt_scratch_len(ROOM_W, ROOM_H);
    let (mut a, mut b, mut c) = (vec![0u32; n], vec![0i64; n], vec![0u32; n]);
    squared_edt(
        &mut sq,
        ROOM_W,
        ROOM_H,
        EdtScratch {
            sites: &mut a,
            bounds: &mut b,
            heights: &mut c,
        },
    )
    .expect("room transform");
    let mut h = FieldHeader::new(
        ROOM_W as u32,
        ROOM_H as u32,
        ROOM_RES,
        ROOM_ORIGIN.0,
        ROOM_ORIGIN.1,
    );
    h.max_dist_m = 1.0;
    let mut out = vec![0u8; h.required_len().expect("room header")];
    emit_blob_from_squared_cells(&h, &sq, &mut out).expect("room blob");
    out
}

/// The room scan: an f64 ray cast from the true pose plus a fixed pattern of 1.1–1.7 cm offsets;
/// beam 5 reads +∞ (no return) and beam 17 NaN (a driver glitch).
///
/// The ray cast stops on a cell boundary, so an unperturbed endpoint lies exactly between two
/// cells and f32 and f64 may pick different ones; every offset is at least 0.22 cell.
pub fn room_scan() -> Vec<f32> {
    let g = room_grid();
    (0..ROOM_BEAMS)
        .map(|k| {
            if k == 5 {
                return f32::INFINITY;
            }
            if k == 17 {
                return f32::NAN;
            }
            let a = f64::from(TRUE_POSE[2]) + (k as f64) * 10f64.to_radians();
            let r = field_reference::ray_cast(
                &g,
                f64::from(TRUE_POSE[0]),
                f64::from(TRUE_POSE[1]),
                a,
                8.0,
            )
            .unwrap_or(8.0);
            const OFFSETS_M: [f64; 5] = [0.012, -0.013, 0.017, -0.011, 0.014];
            (r + OFFSETS_M[(k * 7) % 5]) as f32
        })
        .collect()
}

/// The room layout.
pub fn room_layout() -> BeamLayout<ROOM_BEAMS> {
    BeamLayout::uniform(
        0.0,
        10f32.to_radians(),
        ROOM_BEAMS,
        ROOM_MAX_RANGE_M,
        SensorMount::CENTERED,
    )
    .expect("room layout")
}

/// One landmark case: `(feature [r, φ, s], landmark [x, y, s], pose [x, y, θ], noise [σr, σφ, σs])`.
pub type LandmarkCase = ([f32; 3], [f32; 3], [f32; 3], [f32; 3]);

/// The landmark cases.
pub const LANDMARK_CASES: [LandmarkCase; 5] = [
    (
        [4.0, 0.7, 3.0],
        [3.0, 4.0, 3.0],
        [0.5, 0.9, 0.2],
        [0.15, 0.05, 0.5],
    ),
    // Bearing residual across ±π: 179° observed, −179° predicted.
    (
        [2.0, 3.124_139_4, 1.0],
        [-2.0, -0.034_905_3, 1.0],
        [0.0, 0.0, 0.0],
        [0.1, 0.05, 0.5],
    ),
    (
        [10.0, -2.0, 7.0],
        [-5.0, 8.0, 6.0],
        [1.0, -1.0, 3.0],
        [0.3, 0.1, 1.0],
    ),
    (
        [0.5, 0.0, 0.0],
        [0.5, 0.0, 0.0],
        [0.0, 0.0, 0.0],
        [0.01, 0.01, 0.01],
    ),
    (
        [3.0, 1.0, 2.0],
        [0.0, 3.0, 2.0],
        [0.0, 0.0, 0.0],
        [0.2, 0.02, 0.3],
    ),
];

/// The sonar case of `host-tests/tests/sonar_score.rs`: ranges and ray-cast ranges.
pub const SONAR_RANGES_M: [f32; 24] = [
    1.20,
    1.31,
    5.0,
    2.05,
    0.40,
    2.90,
    3.10,
    f32::INFINITY,
    2.2,
    1.9,
    1.75,
    0.2,
    1.1,
    1.15,
    4.2,
    0.8,
    0.75,
    0.74,
    f32::NAN,
    0.9,
    1.0,
    1.3,
    1.25,
    1.22,
];
/// Ray-cast ranges of the sonar case.
pub const SONAR_Z_STAR_M: [f32; 24] = [
    1.21, 1.30, 3.9, 2.0, 2.4, 2.95, 3.05, 4.5, 2.25, 1.95, 1.70, 1.6, 1.12, 1.18, 1.5, 0.82, 0.74,
    0.73, 0.8, 0.88, 1.02, 1.28, 1.26, 1.2,
];

/// The sonar model of the case (SCITOS-like ring, groups of 3 spread 120°, 12 ms apart).
pub fn sonar_score() -> f32 {
    let ring: Ring<24> = Ring::uniform(
        24,
        0.0,
        -15f32.to_radians(),
        0.25,
        12.5f32.to_radians(),
        5.0,
    )
    .expect("ring");
    let groups: Vec<Vec<usize>> = (0..8).map(|g| vec![g, g + 8, g + 16]).collect();
    let slices: Vec<&[usize]> = groups.iter().map(|g| g.as_slice()).collect();
    let sched = Schedule::<24, 8>::new(&ring, &slices, 0.012, 343.0).expect("schedule");
    let base = BeamIntrinsics::new(0.8, 0.08, 0.07, 0.05, 0.08, 2.0, 5.0).expect("base");
    let model = CrosstalkModel::gaussian(0.3, 45f32.to_radians()).expect("crosstalk");
    let sonar = SonarModel::new(&ring, &sched, &base, &model).expect("sonar model");
    let scan = Scan::<24>::from_ranges(&SONAR_RANGES_M).expect("scan");
    sonar
        .scan_log_likelihood(&scan, &SONAR_Z_STAR_M)
        .log_likelihood
}

/// `landmark_correlation_cases`' correlation case as a blob: `#` cells are occupied (code 0), others
/// code 40.
pub fn correlation_blob() -> Vec<u8> {
    let c = correlation_case();
    let codes: Vec<u8> = c
        .map
        .iter()
        .flat_map(|row| row.bytes().map(|b| if b == b'#' { 0 } else { 40 }))
        .collect();
    let h = FieldHeader::new(8, 6, c.cell_m, c.origin_m.0, c.origin_m.1);
    let mut blob = vec![0u8; h.required_len().expect("correlation header")];
    emit_blob(&h, &codes, &mut blob).expect("correlation blob");
    blob
}

/// Replays a fixed list of words as a `rand_core` generator (the sampler case).
pub struct Replay<'a>(pub &'a [u32]);

impl rand_core::TryRng for Replay<'_> {
    type Error = core::convert::Infallible;
    fn try_next_u32(&mut self) -> Result<u32, core::convert::Infallible> {
        let (first, rest) = self.0.split_first().unwrap_or((&0, &[]));
        self.0 = rest;
        Ok(*first)
    }
    fn try_next_u64(&mut self) -> Result<u64, core::convert::Infallible> {
        let lo = u64::from(self.try_next_u32()?);
        Ok(lo | (u64::from(self.try_next_u32()?) << 32))
    }
    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), core::convert::Infallible> {
        for b in dst {
            *b = self.try_next_u32()? as u8;
        }
        Ok(())
    }
}

fn correlation_rho() -> f32 {
    let c = correlation_case();
    let blob = correlation_blob();
    let view = FieldView::parse(&blob).expect("correlation blob parses");
    let mut buf = vec![0u8; (c.window.0 * c.window.1) as usize];
    let model = MapCorrelation::new(view, c.window.0, c.window.1, &mut buf).expect("window");
    let layout = BeamLayout::<8>::uniform(
        c.bearings.0,
        c.bearings.1,
        8,
        c.bearings.2,
        SensorMount::CENTERED,
    )
    .expect("layout");
    let scan = Scan::<8>::from_ranges(&c.ranges_m).expect("scan");
    model
        .correlate(&layout, &scan, &Pose::new(c.pose[0], c.pose[1], c.pose[2]))
        .rho
}

fn sampled_poses() -> Vec<[f32; 3]> {
    let (fi, li, _, ni) = SAMPLER_INPUT;
    let f = Feature::new(fi[0], fi[1], fi[2]).expect("feature");
    let l = Landmark::new(li[0], li[1], li[2]).expect("landmark");
    let n = FeatureNoise::new(ni[0], ni[1], ni[2]).expect("noise");
    let mut rng = Replay(&SAMPLER_WORDS);
    (0..3)
        .map(|_| {
            let p = sample_pose(&f, &l, &n, &mut rng);
            [p.x_m, p.y_m, p.theta_rad]
        })
        .collect()
}

/// The host's results for every case.
#[derive(Clone, Debug)]
pub struct Expected {
    /// Tempered (κ) likelihood-field scores of [`POSES`], every beam.
    pub tempered: Vec<f32>,
    /// Tempered scores with a stride of 3 beams.
    pub tempered_stride3: Vec<f32>,
    /// Normalized weights of the tempered scores.
    pub weights: Vec<f32>,
    /// Effective sample size of those weights.
    pub ess: f32,
    /// Index of the best pose.
    pub best: usize,
    /// Lag-1 correlation of the endpoint distances at the true pose.
    pub lag1: f32,
    /// Landmark log-likelihoods.
    pub landmark: Vec<f32>,
    /// Sonar scan log-likelihood.
    pub sonar: f32,
    /// ρ of the correlation case.
    pub rho: f32,
    /// The sampler's first three poses from the fixed words.
    pub sampled: Vec<[f32; 3]>,
}

/// Evaluates every case with the crate on the host.
pub fn expected() -> Expected {
    let blob = room_blob();
    let view = FieldView::parse(&blob).expect("room blob parses");
    let (zh, zr, s) = LF_PARAMS;
    let params = LikelihoodParams::new(zh, zr, s, ROOM_MAX_RANGE_M).expect("lf params");
    let lf = LikelihoodField::new(view, params);
    let layout = room_layout();
    let scan = Scan::<ROOM_BEAMS>::from_ranges(&room_scan()).expect("room scan");
    let t1 = Tempered::new(lf.clone(), KAPPA, 1).expect("tempered");
    let t3 = Tempered::new(lf.clone(), KAPPA, 3).expect("tempered");
    let pose = |p: &[f32; 3]| Pose::new(p[0], p[1], p[2]);
    let tempered: Vec<f32> = POSES
        .iter()
        .map(|p| t1.score(&layout, &scan, &pose(p)).log_likelihood)
        .collect();
    let tempered_stride3: Vec<f32> = POSES
        .iter()
        .map(|p| t3.score(&layout, &scan, &pose(p)).log_likelihood)
        .collect();
    let mut weights = tempered.clone();
    let n = normalize_log_weights(&mut weights).expect("normalize");
    let mut lag = Lag1::new();
    lf.score_with(&layout, &scan, &pose(&TRUE_POSE), |_, d| lag.push(d));
    let landmark = LANDMARK_CASES
        .iter()
        .map(|(f, l, p, q)| {
            let f = Feature::new(f[0], f[1], f[2]).expect("feature");
            let l = Landmark::new(l[0], l[1], l[2]).expect("landmark");
            let q = FeatureNoise::new(q[0], q[1], q[2]).expect("noise");
            log_likelihood(&f, &l, &pose(p), &q)
        })
        .collect();
    Expected {
        tempered,
        tempered_stride3,
        weights,
        ess: n.ess,
        best: n.best,
        lag1: lag.correlation().unwrap_or(f32::NAN),
        landmark,
        sonar: sonar_score(),
        rho: correlation_rho(),
        sampled: sampled_poses(),
    }
}

fn list(v: &[f32]) -> String {
    v.iter()
        .map(|x| format!("{x:?}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The generated file's text.
pub fn render() -> String {
    let e = expected();
    let blob = room_blob();
    let scan = room_scan();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "// Generated by `cargo xtask modelcases` from host-tests/src/firmware_models.rs: the crate's\n\
         // results on the host for the inputs below. Do not edit; host-tests/tests/target_models.rs\n\
         // fails when this file is stale.\n"
    );
    let _ = writeln!(
        s,
        "/// The room's distance-field blob ({} bytes).",
        blob.len()
    );
    let _ = write!(s, "pub static ROOM_BLOB: [u8; {}] = [", blob.len());
    for (i, b) in blob.iter().enumerate() {
        if i % 24 == 0 {
            s.push_str("\n    ");
        }
        let _ = write!(s, "{b},");
    }
    s.push_str("\n];\n");
    let _ = writeln!(s, "/// Room scan ranges, metres (beam k at 10°·k).\npub const ROOM_SCAN: [f32; {ROOM_BEAMS}] = [{}];", list(&scan).replace("inf", "f32::INFINITY").replace("NaN", "f32::NAN"));
    let _ = writeln!(
        s,
        "/// Likelihood-field parameters (z_hit, z_rand, sigma_hit_m), range limit, kappa."
    );
    let _ = writeln!(
        s,
        "pub const LF: [f32; 5] = [{:?}, {:?}, {:?}, {:?}, {:?}];",
        LF_PARAMS.0, LF_PARAMS.1, LF_PARAMS.2, ROOM_MAX_RANGE_M, KAPPA
    );
    let poses: Vec<String> = POSES.iter().map(|p| format!("[{}]", list(p))).collect();
    let _ = writeln!(s, "/// Pose hypotheses (x m, y m, θ rad); the first is the truth.\npub const POSES: [[f32; 3]; {}] = [{}];", POSES.len(), poses.join(", "));
    let _ = writeln!(
        s,
        "/// Host: tempered scores.\npub const TEMPERED: [f32; {}] = [{}];",
        e.tempered.len(),
        list(&e.tempered)
    );
    let _ = writeln!(
        s,
        "/// Host: tempered scores, stride 3.\npub const TEMPERED_STRIDE3: [f32; {}] = [{}];",
        e.tempered_stride3.len(),
        list(&e.tempered_stride3)
    );
    let _ = writeln!(
        s,
        "/// Host: normalized weights.\npub const WEIGHTS: [f32; {}] = [{}];",
        e.weights.len(),
        list(&e.weights)
    );
    let _ = writeln!(s, "/// Host: effective sample size, best index, lag-1 at the truth.\npub const ESS: f32 = {:?};\npub const BEST: usize = {};\npub const LAG1: f32 = {:?};", e.ess, e.best, e.lag1);
    let cases: Vec<String> = LANDMARK_CASES
        .iter()
        .map(|(f, l, p, q)| {
            format!(
                "([{}], [{}], [{}], [{}])",
                list(f),
                list(l),
                list(p),
                list(q)
            )
        })
        .collect();
    let _ = writeln!(s, "/// Landmark cases (feature, landmark, pose, noise).\npub const LANDMARK_CASES: [([f32; 3], [f32; 3], [f32; 3], [f32; 3]); {}] = [\n    {}\n];", cases.len(), cases.join(",\n    "));
    let _ = writeln!(
        s,
        "/// Host: landmark log-likelihoods.\npub const LANDMARK: [f32; {}] = [{}];",
        e.landmark.len(),
        list(&e.landmark)
    );
    let _ = writeln!(s, "/// Sonar ranges and ray-cast ranges, metres.\npub const SONAR_RANGES_M: [f32; 24] = [{}];", list(&SONAR_RANGES_M).replace("inf", "f32::INFINITY").replace("NaN", "f32::NAN"));
    let _ = writeln!(
        s,
        "/// Sonar ray-cast ranges, metres.\npub const SONAR_Z_STAR_M: [f32; 24] = [{}];",
        list(&SONAR_Z_STAR_M)
    );
    let _ = writeln!(
        s,
        "/// Host: sonar scan log-likelihood.\npub const SONAR: f32 = {:?};",
        e.sonar
    );
    let c = correlation_case();
    let cb = correlation_blob();
    let _ = writeln!(
        s,
        "/// The correlation case's 8 × 6 blob.\npub static CORR_BLOB: [u8; {}] = {:?};",
        cb.len(),
        cb
    );
    let _ = writeln!(s, "/// Correlation window (cells), bearings (first, step rad, max range m), pose.\npub const CORR_WINDOW: (u32, u32) = {:?};\npub const CORR_BEARINGS: [f32; 3] = [{}];\npub const CORR_POSE: [f32; 3] = [{}];", c.window, list(&[c.bearings.0, c.bearings.1, c.bearings.2]), list(&c.pose));
    let _ = writeln!(
        s,
        "/// Correlation ranges, metres.\npub const CORR_RANGES: [f32; 8] = [{}];",
        list(&c.ranges_m)
            .replace("NaN", "f32::NAN")
            .replace("inf", "f32::INFINITY")
    );
    let _ = writeln!(s, "/// Host: ρ.\npub const CORR_RHO: f32 = {:?};", e.rho);
    let (fi, li, _, ni) = SAMPLER_INPUT;
    let _ = writeln!(s, "/// Sampler: feature, landmark, noise, words.\npub const SAMPLER_FEATURE: [f32; 3] = [{}];\npub const SAMPLER_LANDMARK: [f32; 3] = [{}];\npub const SAMPLER_NOISE: [f32; 3] = [{}];\npub const SAMPLER_WORDS: [u32; {}] = {:?};", list(&fi), list(&li), list(&ni), SAMPLER_WORDS.len(), SAMPLER_WORDS);
    let poses: Vec<String> = e.sampled.iter().map(|p| format!("[{}]", list(p))).collect();
    let _ = writeln!(
        s,
        "/// Host: the sampler's first three poses.\npub const SAMPLED: [[f32; 3]; 3] = [{}];",
        poses.join(", ")
    );
    s
}
