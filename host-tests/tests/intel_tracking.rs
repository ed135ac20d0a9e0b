//! Tracking acceptance of the Monte Carlo localizer on the whole Intel lab log (910 scans):
//! the map and its free space are built from the log's corrected poses (5 cm cells, as
//! `beamfield map from-log` + `beamfield field build --free-space`), the odometry is synthesized
//! from consecutive logged poses with the motion model's own noise (α = 0.005 each, seeded
//! SplitMix64; `beamfield_tools::track`), 500 particles, κ = 8.25 (the `beamfield calibrate`
//! value for this log), every beam, an update on every scan.
//!
//! Measured over 10 seeds (1–10) with `beamfield track --seeds 10` (docs/localization.md):
//! translation RMSE 3.96 / 4.19 / 4.66 cm (min / median / max), heading RMSE 0.64 / 0.87 /
//! 1.36°, within 10 cm / 2° 95.3 / 96.1 / 97.1 %, never lost. The bounds below sit just outside
//! the worst of those 10 seeds (RMSE 4.66 → 5 cm, heading 1.36 → 1.5°, 95.3 → 94 %), so a
//! seed that happens to be a little worse does not fail the test, while a real regression
//! (a biased cell convention costs about 2.5 cm in x and y; a broken resampler or motion model
//! loses the robot) does.

use beamfield::mcl::QualityThresholds;
use beamfield_tools::track::{run_once, Init, RunOptions, Weighting};
use host_tests::intel_input;

fn tracking_options(seed: u64, scans: usize) -> RunOptions {
    RunOptions {
        particles: 500,
        kappa: 8.25,
        stride: 1,
        alphas: [0.005; 4],
        seed,
        init: Init::Logged,
        kidnap: None,
        weighting: Weighting::Product,
        recovery: (0.0, 0.0),
        recovery_while_unsettled: false,
        retry: None,
        resample_ess: 0.5,
        scans,
        unexplained: None,
        resetting: false,
        adaptive_noise: None,
        kld: None,
        adaptive_sigma: None,
        kappa_uncertain: None,
        update_min: (0.0, 0.0),
        reset_per_update: 0,
        clutter_share: QualityThresholds::DEFAULT.clutter_share,
        lost_through: QualityThresholds::DEFAULT.lost_through,
    }
}

#[test]
fn tracks_the_whole_intel_log() {
    let input = intel_input();
    for seed in 1..=3 {
        let o = tracking_options(seed, input.scans.len());
        let m = run_once(&input, &o).unwrap().metrics(0);
        println!("seed {seed}: {m:?}");
        assert!(!m.lost, "seed {seed} lost the robot: {m:?}");
        assert!(m.trans_rmse_m <= 0.05, "seed {seed}: {m:?}");
        assert!(m.heading_rmse_deg <= 1.5, "seed {seed}: {m:?}");
        assert!(m.within_10cm_2deg >= 0.94, "seed {seed}: {m:?}");
    }
}

/// The retry at every update with half the step's spread (`--retry=-inf,0.5`), measured over
/// seeds 1–10 (docs/localization.md): translation RMSE 3.13 / 3.20 / 3.34 cm, heading 0.48 /
/// 0.59 / 1.05°, within 10 cm / 2° 98.2 / 99.1 / 99.5 %, never lost. The bounds sit just
/// outside the worst seed (3.34 → 3.7 cm, 1.05 → 1.4°, 98.2 → 98 %); the RMSE and fraction
/// bounds are beyond what the filter without the retry reaches on any of those seeds (best
/// 3.96 cm, 97.1 %), so a retry that does nothing fails.
#[test]
fn retry_sharpens_tracking() {
    let input = intel_input();
    for seed in 1..=3 {
        let o = RunOptions {
            retry: Some((f32::NEG_INFINITY, 0.5)),
            ..tracking_options(seed, input.scans.len())
        };
        let r = run_once(&input, &o).unwrap();
        let m = r.metrics(0);
        println!("seed {seed}: {m:?}, {} retries", r.retries);
        assert_eq!(r.retries, input.scans.len() - 1, "seed {seed}");
        assert!(!m.lost, "seed {seed} lost the robot: {m:?}");
        assert!(m.trans_rmse_m <= 0.037, "seed {seed}: {m:?}");
        assert!(m.heading_rmse_deg <= 1.4, "seed {seed}: {m:?}");
        assert!(m.within_10cm_2deg >= 0.98, "seed {seed}: {m:?}");
    }
}

/// Global localization with recovery only while the filter has not settled
/// (`--init global --particles 5000 --odom-noise 0.002 --recovery 0.001,0.1
/// --recovery-while-unsettled`, docs/localization.md): measured, all 10 seeds converge (within
/// 124 scans) and 8 of 10 are never more than 0.5 m off afterwards. The acceptance is the
/// target itself: at least 8 of 10 converge within 150 scans and are never lost afterwards.
#[test]
fn global_start_converges_and_stays() {
    let input = intel_input();
    let mut good = 0;
    for seed in 1..=10 {
        let o = RunOptions {
            particles: 5000,
            alphas: [0.002; 4],
            init: Init::Global,
            recovery: (0.001, 0.1),
            recovery_while_unsettled: true,
            ..tracking_options(seed, input.scans.len())
        };
        let m = run_once(&input, &o).unwrap().metrics(0);
        println!("seed {seed}: {m:?}");
        if m.converged_after.is_some_and(|c| c <= 150) && !m.lost_after_convergence {
            good += 1;
        }
    }
    assert!(good >= 8, "{good} of 10 converged and stayed");
}
