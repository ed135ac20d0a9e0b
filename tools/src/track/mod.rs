//! `beamfield track`: Monte Carlo localization ([`beamfield::mcl`]) over a whole CARMEN log,
//! measured against the logged poses.
//!
//! The shared logs carry corrected poses and no raw odometry, so odometry is synthesized:
//! starting at the first logged pose, each step between consecutive logged poses (Thrun's
//! `(δrot1, δtrans, δrot2)`) is perturbed by the filter's own motion model
//! (the variances of [`beamfield::mcl::OdometryNoise::sigmas`], AMCL's `odom_alpha1..4` convention, drawn with
//! Box–Muller normals by `odometry_sample`, not the filter's ziggurat) and chained. The
//! filter sees only these odometry poses and the scans; the logged poses are the truth it is
//! scored against.
//!
//! Random numbers, all [`SplitMix64`] (documented in `beamfield::mcl::rng`):
//! - odometry: seed `S ^ ODOMETRY_SEED_XOR`;
//! - the filter (initialization, motion samples, resampling, recovery): seed `S`;
//! - the kidnapping's wrong pose: seed `S ^ KIDNAP_SEED_XOR`.
//!
//! The FLASER pose is the laser's pose, so the filter estimates laser poses (centred mount).

use crate::input::carmen::LogError;
use beamfield::field::{BlobError, FreeSpaceError};
use beamfield::mcl::MclError;
use clap::{Args, ValueEnum};
use std::path::PathBuf;

/// Largest `--particles`.
pub const MAX_TRACK_PARTICLES: usize = 20_000;
/// Largest `--seeds`: 1,000 runs (each a whole pass over the log; the docs' studies use 20).
pub const MAX_TRACK_SEEDS: u64 = 1000;
/// XOR applied to the seed for the odometry generator.
pub const ODOMETRY_SEED_XOR: u64 = 0x6F64_6F6D_6574_7279;
/// XOR applied to the seed for the kidnapping's wrong pose.
pub const KIDNAP_SEED_XOR: u64 = 0x6B69_646E_6170_0000;
/// Spread of the initial cloud around the first logged pose (`--init logged`): σ metres.
pub const INIT_SIGMA_XY_M: f32 = 0.05;
/// Spread of the initial cloud around the first logged pose: σ radians (2°).
pub const INIT_SIGMA_THETA_RAD: f32 = 0.035;
/// A run is lost when the estimate is ever farther than this from the logged pose, metres.
pub const LOST_M: f64 = 0.5;
/// Converged (global localization, kidnapping): within this distance, metres …
pub const CONVERGED_M: f64 = 0.20;
/// … and this heading error, degrees …
pub const CONVERGED_DEG: f64 = 5.0;
/// … for this many consecutive scans.
pub const CONVERGED_SCANS: usize = 20;
/// The kidnapped robot is put at least this far from the truth, metres.
pub const KIDNAP_MIN_M: f32 = 3.0;

/// How the initial cloud is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Init {
    /// Gaussian around the first logged pose (σ 5 cm, 2°).
    Logged,
    /// Uniform over the free space appended to the field file (global localization).
    Global,
}

/// How particles are weighted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Weighting {
    /// The crate's likelihood field: Σ ln p(z_k | x, m) over every stride-th beam, divided by κ.
    Product,
    /// AMCL's `likelihood_field` weighting, as a baseline: weight 1 + Σ p_k³ with
    /// p_k = z_hit·exp(−d²/2σ²) + z_rand/z_max (unnormalized Gaussian), every stride-th beam.
    AmclCube,
}

/// `beamfield track`: run the localizer over a log.
#[derive(Args, Debug, Clone)]
pub struct TrackArgs {
    /// The distance-field blob (`beamfield field build`); `--init global` and recovery need it
    /// built with `--free-space`.
    #[arg(long)]
    pub field: PathBuf,
    /// The CARMEN log (FLASER lines with corrected poses).
    #[arg(long)]
    pub log: PathBuf,
    /// Number of particles (1 to 20,000).
    #[arg(long, default_value_t = 500,
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=MAX_TRACK_PARTICLES as u64))]
    pub particles: usize,
    /// Tempering κ (8.25 is the value `beamfield calibrate` finds on the Intel log).
    #[arg(long, default_value_t = 8.25)]
    pub kappa: f32,
    /// Score every S-th beam (1 to 1081, the most beams a scan has here).
    #[arg(long, default_value_t = 1,
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new()
              .range(1..=crate::cmd::scored_log::MAX_BEAMS as u64))]
    pub stride: usize,
    /// Odometry noise odom_alpha1..4 (variance coefficients, AMCL's convention), used both to
    /// synthesize the odometry and in the filter: "A" or "A1,A2,A3,A4".
    #[arg(long = "odom-noise", default_value = "0.005")]
    pub odom_noise: String,
    /// Seed of the run (see the module docs for the generators).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Run this many seeds (SEED, SEED+1, …; 1 to 1,000) and report min / median / max.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=MAX_TRACK_SEEDS))]
    pub seeds: u64,
    /// Initial cloud.
    #[arg(long, value_enum, default_value_t = Init::Logged)]
    pub init: Init,
    /// At this scan, move the filter's whole cloud rigidly to a random free pose at least
    /// 3 m from the truth (equivalent to kidnapping the robot), and count scans until it
    /// recovers.
    #[arg(long)]
    pub kidnap: Option<usize>,
    /// Particle weighting.
    #[arg(long, value_enum, default_value_t = Weighting::Product)]
    pub weighting: Weighting,
    /// Augmented-MCL recovery rates "SLOW,FAST" (recovery_alpha_slow/fast, e.g. "0.001,0.1";
    /// the default "0,0" turns it off, as AMCL's defaults do).
    #[arg(long, default_value = "0,0")]
    pub recovery: String,
    /// Inject recovery particles only while the filter has not settled; settled: its
    /// estimate's spread under 15 cm and 0.1 rad, and its moves matching the odometry's within
    /// 15 cm and 0.1 rad, for 20 scans in a row (the filter's own view, not the logged poses).
    /// A guard against recovery hijacking a tracked cloud.
    #[arg(long = "recovery-while-unsettled")]
    pub recovery_while_unsettled: bool,
    /// Retry "DROP,SCALE" (off by default; MclConfig::with_retry): when an update's average
    /// likelihood per beam falls more than DROP nats below its recent level, resample, move the
    /// set by SCALE times the odometry step's spread and weigh it again by the same scan. DROP
    /// "-inf" retries at every update (a second scoring pass each time), e.g. "--retry=-inf,0.5".
    #[arg(long, allow_hyphen_values = true)]
    pub retry: Option<String>,
    /// Resample when the effective sample size falls below this fraction of the particles.
    #[arg(long = "resample-ess", default_value_t = 0.5)]
    pub resample_ess: f32,
    /// σ_hit of the likelihood field, metres.
    #[arg(long = "sigma-hit", default_value_t = 0.05)]
    pub sigma_hit: f32,
    /// z_hit weight.
    #[arg(long = "z-hit", default_value_t = 0.95)]
    pub z_hit: f32,
    /// z_rand weight.
    #[arg(long = "z-rand", default_value_t = 0.05)]
    pub z_rand: f32,
    /// Stop after this many scans (default: the whole log).
    #[arg(long)]
    pub scans: Option<usize>,
    /// Draw the estimated (green) and logged (blue) trajectories over the map (first seed).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

/// Errors of `beamfield track`.
#[derive(Debug)]
#[non_exhaustive]
pub enum TrackError {
    /// A file could not be read or written.
    Io(PathBuf, std::io::Error),
    /// A file that is not a regular file or over its size limit (docs/resource-limits.md).
    Read(crate::input::limits::ReadError),
    /// The distance-field blob is malformed.
    Blob(BlobError),
    /// The free-space section after the blob is malformed.
    FreeSpace(FreeSpaceError),
    /// The log could not be read.
    Log(LogError),
    /// A bad option value.
    Usage(String),
    /// The filter refused its input.
    Filter(MclError),
    /// The picture could not be written.
    Png(PathBuf, String),
}

impl std::fmt::Display for TrackError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Io(p, e) => write!(f, "{}: {e}", p.display()),
            Self::Read(e) => write!(f, "{e}"),
            Self::Blob(e) => write!(f, "bad field blob: {e}"),
            Self::FreeSpace(e) => write!(f, "bad free-space section: {e}"),
            Self::Log(e) => write!(f, "{e}"),
            Self::Usage(m) => f.write_str(m),
            Self::Filter(e) => write!(f, "filter: {e}"),
            Self::Png(p, e) => write!(f, "{}: {e}", p.display()),
        }
    }
}

impl std::error::Error for TrackError {}

fn usage(m: impl Into<String>) -> TrackError {
    TrackError::Usage(m.into())
}

mod run;

pub use run::{load, run_once, synthesize_odometry, Metrics, RunOptions, RunResult, TrackInput};

fn parse_list(text: &str, what: &str, n: usize) -> Result<Vec<f32>, TrackError> {
    let v: Vec<f32> = text
        .split(',')
        .map(|t| t.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            usage(format!(
                "{what} {text:?}: expected numbers separated by commas"
            ))
        })?;
    match v.len() {
        1 if n == 4 => Ok(vec![v[0]; 4]),
        k if k == n => Ok(v),
        _ => Err(usage(format!("{what} {text:?}: expected {n} numbers"))),
    }
}

/// The options of `args` for seed `seed`.
///
/// # Errors
/// [`TrackError::Usage`] for malformed lists.
pub fn options(args: &TrackArgs, seed: u64, scans: usize) -> Result<RunOptions, TrackError> {
    let a = parse_list(&args.odom_noise, "--odom-noise", 4)?;
    let r = parse_list(&args.recovery, "--recovery", 2)?;
    let retry = match &args.retry {
        Some(text) => {
            let v = parse_list(text, "--retry", 2)?;
            Some((v[0], v[1]))
        }
        None => None,
    };
    Ok(RunOptions {
        particles: args.particles,
        kappa: args.kappa,
        stride: args.stride,
        alphas: [a[0], a[1], a[2], a[3]],
        seed,
        init: args.init,
        kidnap: args.kidnap,
        weighting: args.weighting,
        recovery: (r[0], r[1]),
        recovery_while_unsettled: args.recovery_while_unsettled,
        retry,
        resample_ess: args.resample_ess,
        scans: args.scans.unwrap_or(scans).min(scans),
    })
}

fn min_med_max(mut v: Vec<f64>) -> [f64; 3] {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return [f64::NAN; 3];
    }
    let mid = if v.len() % 2 == 1 {
        v[v.len() / 2]
    } else {
        0.5 * (v[v.len() / 2 - 1] + v[v.len() / 2])
    };
    [v[0], mid, v[v.len() - 1]]
}

/// Runs `beamfield track`; returns the text (or JSON) to print.
///
/// # Errors
/// [`TrackError`].
pub fn run(args: &TrackArgs, json: bool) -> Result<String, TrackError> {
    let input = load(
        &args.field,
        &args.log,
        args.z_hit,
        args.z_rand,
        args.sigma_hit,
    )?;
    if !(1..=MAX_TRACK_SEEDS).contains(&args.seeds) {
        return Err(usage(format!(
            "--seeds {}: must be 1 ..= {MAX_TRACK_SEEDS}",
            args.seeds
        )));
    }
    if let Some(k) = args.kidnap {
        if k == 0 || k >= input.scans.len() {
            return Err(usage(format!(
                "--kidnap {k}: must be a scan in 1..{}",
                input.scans.len()
            )));
        }
    }
    let from = args.kidnap.unwrap_or(0);
    let mut runs = Vec::new();
    // SEED, SEED+1, … wrapping past u64::MAX (the seed is only a generator's state).
    for seed in (0..args.seeds).map(|i| args.seed.wrapping_add(i)) {
        let o = options(args, seed, input.scans.len())?;
        let r = run_once(&input, &o)?;
        if runs.is_empty() {
            if let Some(path) = &args.output {
                crate::draw::tracks::draw_track(path, &input, &r, o.scans)?;
            }
        }
        runs.push((seed, r.metrics(from), r));
    }
    let o = options(args, args.seed, input.scans.len())?;
    let pick = |f: fn(&Metrics) -> f64| min_med_max(runs.iter().map(|(_, m, _)| f(m)).collect());
    let rmse = pick(|m| m.trans_rmse_m * 100.0);
    let head = pick(|m| m.heading_rmse_deg);
    let maxe = pick(|m| m.max_trans_m);
    let within = pick(|m| m.within_10cm_2deg * 100.0);
    let lost = runs.iter().filter(|(_, m, _)| m.lost).count();
    let lost_after = runs
        .iter()
        .filter(|(_, m, _)| m.lost_after_convergence)
        .count();
    let conv: Vec<Option<usize>> = runs.iter().map(|(_, m, _)| m.converged_after).collect();
    let conv_ok: Vec<f64> = conv.iter().flatten().map(|&c| c as f64).collect();
    if json {
        let per: Vec<_> = runs
            .iter()
            .map(|(seed, m, r)| {
                serde_json::json!({ "seed": seed, "metrics": m, "skipped": r.skipped,
                    "resamplings": r.resamplings, "injected": r.injected, "retries": r.retries })
            })
            .collect();
        return Ok(serde_json::json!({
            "scans": o.scans, "particles": o.particles, "kappa": o.kappa, "stride": o.stride,
            "odom_alphas": o.alphas, "init": format!("{:?}", o.init).to_lowercase(),
            "weighting": format!("{:?}", o.weighting), "recovery": [o.recovery.0, o.recovery.1],
"recovery_while_unsettled": o.recovery_while_unsettled,
            "retry": o.retry.map(|(d, k)| [d, k]), "kidnap": o.kidnap, "runs": per,
            "trans_rmse_cm_min_med_max": rmse, "heading_rmse_deg_min_med_max": head,
            "max_trans_m_min_med_max": maxe, "within_10cm_2deg_pct_min_med_max": within,
            "lost_runs": lost, "lost_after_convergence_runs": lost_after, "converged_runs": conv_ok.len(),
            "converged_after_min_med_max": if conv_ok.is_empty() { None } else { Some(min_med_max(conv_ok.clone())) },
        })
        .to_string());
    }
    let mut s = format!(
        "{} scans, {} particles, κ {}, stride {}, odom_alpha {:?}, init {:?}, weighting {:?}, \
         recovery {:?}{}{}{}\n",
        o.scans,
        o.particles,
        o.kappa,
        o.stride,
        o.alphas,
        o.init,
        o.weighting,
        o.recovery,
        if o.recovery_while_unsettled {
            " while unsettled"
        } else {
            ""
        },
        o.retry
            .map(|(d, k)| format!(", retry {d} nats below the level, {k}× the step's spread"))
            .unwrap_or_default(),
        o.kidnap
            .map(|k| format!(", kidnapped at scan {k}"))
            .unwrap_or_default()
    );
    for (seed, m, r) in &runs {
        s += &format!(
            "seed {seed}: trans RMSE {:.2} cm, heading RMSE {:.2}°, max {:.3} m, within 10 cm/2° \
             {:.1} %, {}{}{}; {} resamplings, {} injected, {} retries, {} skipped\n",
            m.trans_rmse_m * 100.0,
            m.heading_rmse_deg,
            m.max_trans_m,
            m.within_10cm_2deg * 100.0,
            if m.lost { "LOST" } else { "not lost" },
            m.converged_after
                .map(|c| format!(", converged after {c} scans"))
                .unwrap_or_else(|| ", never converged".into()),
            if m.lost_after_convergence {
                ", LOST after converging"
            } else {
                ""
            },
            r.resamplings,
            r.injected,
            r.retries,
            r.skipped,
        );
    }
    s += &format!(
        "over {} seeds (min / median / max): trans RMSE {:.2} / {:.2} / {:.2} cm; heading RMSE \
         {:.2} / {:.2} / {:.2}°; max error {:.3} / {:.3} / {:.3} m; within 10 cm/2° {:.1} / \
         {:.1} / {:.1} %; lost (> 0.5 m) in {lost} of {}; converged (20 cm/5° for 20 scans) in \
         {} of {}",
        runs.len(),
        rmse[0],
        rmse[1],
        rmse[2],
        head[0],
        head[1],
        head[2],
        maxe[0],
        maxe[1],
        maxe[2],
        within[0],
        within[1],
        within[2],
        runs.len(),
        conv_ok.len(),
        runs.len(),
    );
    if !conv_ok.is_empty() {
        let conv_ok_runs = conv_ok.len();
        let c = min_med_max(conv_ok);
        s += &format!(
            ", after {:.0} / {:.0} / {:.0} scans; lost after converging in {lost_after} of {}",
            c[0], c[1], c[2], conv_ok_runs
        );
    }
    if let Some(p) = &args.output {
        s += &format!("\nwrote {}", p.display());
    }
    Ok(s)
}
