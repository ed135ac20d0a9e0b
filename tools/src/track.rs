//! `beamfield track`: Monte Carlo localization ([`beamfield::mcl`]) over a whole CARMEN log,
//! measured against the logged poses.
//!
//! The shared logs carry corrected poses and no raw odometry, so odometry is synthesized:
//! starting at the first logged pose, each step between consecutive logged poses (Thrun's
//! `(δrot1, δtrans, δrot2)`) is perturbed by the filter's own motion model
//! ([`OdometryNoise::sample`], AMCL's `odom_alpha1..4` variance convention) and chained. The
//! filter sees only these odometry poses and the scans; the logged poses are the truth it is
//! scored against.
//!
//! Random numbers, all [`SplitMix64`] (documented in `beamfield::mcl::rng`):
//! - odometry: seed `S ^ ODOMETRY_SEED_XOR`;
//! - the filter (initialization, motion samples, resampling, recovery): seed `S`;
//! - the kidnapping's wrong pose: seed `S ^ KIDNAP_SEED_XOR`.
//!
//! The FLASER pose is the laser's pose, so the filter estimates laser poses (centred mount).

use crate::carmen::{CarmenLog, LogError, ReadOptions};
use crate::field_cmd::render;
use crate::score_cmd::MAX_BEAMS;
use beamfield::field::{
    BlobError, FieldView, FreeSpace, FreeSpaceError, LikelihoodField, LikelihoodParams,
};
use beamfield::mcl::{
    Mcl, MclConfig, MclError, OdometryNoise, OdometryStep, Particles, SplitMix64,
};
use beamfield::{wrap_angle, BeamLayout, Pose, Reading, Scan, SensorMount, Tempered};
use clap::{Args, ValueEnum};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// Largest `--particles`.
pub const MAX_TRACK_PARTICLES: usize = 20_000;
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
    /// Number of particles.
    #[arg(long, default_value_t = 500)]
    pub particles: usize,
    /// Tempering κ (8.25 is the value `beamfield calibrate` finds on the Intel log).
    #[arg(long, default_value_t = 8.25)]
    pub kappa: f32,
    /// Score every S-th beam.
    #[arg(long, default_value_t = 1)]
    pub stride: usize,
    /// Odometry noise odom_alpha1..4 (variance coefficients, AMCL's convention), used both to
    /// synthesize the odometry and in the filter: "A" or "A1,A2,A3,A4".
    #[arg(long = "odom-noise", default_value = "0.005")]
    pub odom_noise: String,
    /// Seed of the run (see the module docs for the generators).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Run this many seeds (SEED, SEED+1, …) and report min / median / max.
    #[arg(long, default_value_t = 1)]
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

/// Everything a run needs, loaded once.
pub struct TrackInput {
    /// Blob bytes (and any free-space section after them).
    pub bytes: Vec<u8>,
    /// Likelihood-field parameters.
    pub params: LikelihoodParams,
    /// The log's beam layout (centred mount).
    pub layout: BeamLayout<MAX_BEAMS>,
    /// The scans.
    pub scans: Vec<Scan<MAX_BEAMS>>,
    /// The logged (corrected) laser poses: the truth.
    pub logged: Vec<Pose>,
}

impl TrackInput {
    /// The field view and the free space after it, if any.
    ///
    /// # Errors
    /// [`TrackError::Blob`], [`TrackError::FreeSpace`] (also when its grid is not the blob's).
    pub fn views(&self) -> Result<(FieldView<'_>, Option<FreeSpace<'_>>), TrackError> {
        let (view, rest) = FieldView::parse_prefix(&self.bytes).map_err(TrackError::Blob)?;
        if rest.is_empty() {
            return Ok((view, None));
        }
        let free = FreeSpace::parse(rest).map_err(TrackError::FreeSpace)?;
        if !free.matches(&view) {
            return Err(usage("the free-space section's grid is not the blob's"));
        }
        Ok((view, Some(free)))
    }
}

/// Loads the field and the log.
///
/// # Errors
/// [`TrackError`] for unreadable or malformed inputs.
pub fn load(
    field: &Path,
    log: &Path,
    z_hit: f32,
    z_rand: f32,
    sigma_hit: f32,
) -> Result<TrackInput, TrackError> {
    let bytes = std::fs::read(field).map_err(|e| TrackError::Io(field.to_path_buf(), e))?;
    let log = CarmenLog::read_path(log, ReadOptions::default()).map_err(TrackError::Log)?;
    let max_range = log
        .max_range
        .value_m()
        .ok_or_else(|| usage("the log's max-range value could not be detected"))?;
    let params = LikelihoodParams::new(z_hit, z_rand, sigma_hit, max_range)
        .map_err(|e| usage(format!("likelihood field parameters: {e}")))?;
    let layout = log
        .layout_with_mount(SensorMount::CENTERED)
        .map_err(|e| usage(format!("beam layout of the log: {e}")))?;
    let scans = log
        .scans
        .iter()
        .map(|s| s.to_scan())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| usage(format!("scan: {e}")))?;
    if scans.is_empty() {
        return Err(usage("no FLASER scans in the log"));
    }
    let logged = log.scans.iter().map(|s| s.pose).collect();
    let input = TrackInput {
        bytes,
        params,
        layout,
        scans,
        logged,
    };
    input.views()?;
    Ok(input)
}

/// The options of one run.
#[derive(Clone, Copy, Debug)]
pub struct RunOptions {
    /// Particles.
    pub particles: usize,
    /// κ.
    pub kappa: f32,
    /// Beam stride.
    pub stride: usize,
    /// odom_alpha1..4.
    pub alphas: [f32; 4],
    /// Seed.
    pub seed: u64,
    /// Initial cloud.
    pub init: Init,
    /// Scan at which the robot is kidnapped.
    pub kidnap: Option<usize>,
    /// Weighting.
    pub weighting: Weighting,
    /// (recovery_alpha_slow, recovery_alpha_fast).
    pub recovery: (f32, f32),
    /// ESS fraction below which the set is resampled.
    pub resample_ess: f32,
    /// Scans to run (at most the log's).
    pub scans: usize,
}

/// The outcome of one run.
#[derive(Clone, Debug)]
pub struct RunResult {
    /// The estimate after each scan.
    pub estimates: Vec<Pose>,
    /// Translation error per scan, metres.
    pub trans_err_m: Vec<f64>,
    /// Heading error per scan, degrees.
    pub heading_err_deg: Vec<f64>,
    /// Scans whose update was skipped (empty scan) or discarded (all particles impossible).
    pub skipped: usize,
    /// Resamplings.
    pub resamplings: usize,
    /// Random particles injected by recovery, in total.
    pub injected: u64,
}

/// Summary figures of a run.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Metrics {
    /// Translation RMSE over the scans, metres.
    pub trans_rmse_m: f64,
    /// Heading RMSE, degrees.
    pub heading_rmse_deg: f64,
    /// Largest translation error, metres.
    pub max_trans_m: f64,
    /// Fraction of scans within 10 cm and 2°.
    pub within_10cm_2deg: f64,
    /// The estimate was once more than 0.5 m off.
    pub lost: bool,
    /// First scan from which the estimate stays within 20 cm / 5° for 20 scans (counted from
    /// the start, or from the kidnapping).
    pub converged_after: Option<usize>,
}

impl RunResult {
    /// The summary, over scans `from..` (the RMSE and fractions over all scans; convergence
    /// counted from `from`).
    pub fn metrics(&self, from: usize) -> Metrics {
        let n = self.trans_err_m.len().max(1) as f64;
        let trans_rmse_m = (self.trans_err_m.iter().map(|e| e * e).sum::<f64>() / n).sqrt();
        let heading_rmse_deg = (self.heading_err_deg.iter().map(|e| e * e).sum::<f64>() / n).sqrt();
        let max_trans_m = self.trans_err_m.iter().copied().fold(0.0, f64::max);
        let ok: Vec<bool> = self
            .trans_err_m
            .iter()
            .zip(&self.heading_err_deg)
            .map(|(&t, &h)| t <= 0.10 && h <= 2.0)
            .collect();
        let within = ok.iter().filter(|&&b| b).count() as f64 / n;
        let close: Vec<bool> = self
            .trans_err_m
            .iter()
            .zip(&self.heading_err_deg)
            .map(|(&t, &h)| t <= CONVERGED_M && h <= CONVERGED_DEG)
            .collect();
        let mut converged_after = None;
        let mut streak = 0usize;
        for (k, &c) in close.iter().enumerate().skip(from) {
            streak = if c { streak + 1 } else { 0 };
            if streak == CONVERGED_SCANS {
                converged_after = Some(k + 1 - CONVERGED_SCANS - from);
                break;
            }
        }
        Metrics {
            trans_rmse_m,
            heading_rmse_deg,
            max_trans_m,
            within_10cm_2deg: within,
            lost: max_trans_m > LOST_M,
            converged_after,
        }
    }
}

/// AMCL's `likelihood_field` weight of `scan` at `pose`: `ln(1 + Σ p_k³)`.
fn amcl_cube(
    view: &FieldView<'_>,
    params: &LikelihoodParams,
    layout: &BeamLayout<MAX_BEAMS>,
    scan: &Scan<MAX_BEAMS>,
    stride: usize,
    pose: &Pose,
) -> f32 {
    let (s, c) = (pose.theta_rad.sin(), pose.theta_rad.cos());
    let denom = 2.0 * params.sigma_hit_m() * params.sigma_hit_m();
    let rand = params.z_rand() / params.max_range_m();
    let mut p = 1.0f32;
    for (beam, &r) in layout.beams().iter().zip(scan.ranges_m()).step_by(stride) {
        if !matches!(
            Reading::classify(r, params.max_range_m()),
            Reading::Range(_)
        ) {
            continue;
        }
        let (bx, by) = (beam.cos * c - beam.sin * s, beam.sin * c + beam.cos * s);
        let d = view.distance_m(pose.x_m + r * bx, pose.y_m + r * by);
        let pz = params.z_hit() * (-d * d / denom).exp() + rand;
        p += pz * pz * pz;
    }
    p.ln()
}

/// Runs the filter over the log once.
///
/// # Errors
/// [`TrackError::Usage`] for bad options (global initialization or recovery without free
/// space, too many particles), [`TrackError::Filter`].
pub fn run_once(input: &TrackInput, o: &RunOptions) -> Result<RunResult, TrackError> {
    let (view, free) = input.views()?;
    if o.particles == 0 || o.particles > MAX_TRACK_PARTICLES {
        return Err(usage(format!(
            "--particles {}: must be 1 ..= {MAX_TRACK_PARTICLES}",
            o.particles
        )));
    }
    if (o.init == Init::Global || o.kidnap.is_some()) && free.is_none() {
        return Err(usage(
            "--init global and --kidnap need a field built with --free-space",
        ));
    }
    let noise = OdometryNoise::new(o.alphas[0], o.alphas[1], o.alphas[2], o.alphas[3])
        .map_err(|e| usage(format!("--odom-noise: {e}")))?;
    let config = MclConfig::new(noise, o.resample_ess, o.recovery.0, o.recovery.1)
        .map_err(|e| usage(format!("--recovery / --resample-ess: {e}")))?;
    let lf = LikelihoodField::new(view, input.params);
    let model = Tempered::new(lf, o.kappa, o.stride)
        .map_err(|e| usage(format!("--kappa / --stride: {e}")))?;
    let mut store: Box<Particles<MAX_TRACK_PARTICLES>> = Box::default();
    let mut mcl = Mcl::new(&mut store, config).map_err(TrackError::Filter)?;
    let mut rng = SplitMix64::new(o.seed);
    let mut odom_rng = SplitMix64::new(o.seed ^ ODOMETRY_SEED_XOR);
    let mut kidnap_rng = SplitMix64::new(o.seed ^ KIDNAP_SEED_XOR);
    let first = input.logged.first().copied().unwrap_or_default();
    match (o.init, &free) {
        (Init::Global, Some(f)) => mcl.init_uniform(o.particles, f, &mut rng),
        _ => mcl.init_gaussian(
            o.particles,
            &first,
            INIT_SIGMA_XY_M,
            INIT_SIGMA_THETA_RAD,
            &mut rng,
        ),
    }
    .map_err(TrackError::Filter)?;
    let n = o.scans.min(input.scans.len());
    let mut out = RunResult {
        estimates: Vec::with_capacity(n),
        trans_err_m: Vec::with_capacity(n),
        heading_err_deg: Vec::with_capacity(n),
        skipped: 0,
        resamplings: 0,
        injected: 0,
    };
    let progress = std::io::stderr().is_terminal();
    let mut odom = first;
    for k in 0..n {
        let truth = input.logged[k];
        if k > 0 {
            let step = OdometryStep::between(&input.logged[k - 1], &truth)
                .map_err(|e| usage(format!("logged pose {k}: {e}")))?;
            let next = noise.sample(&odom, &step, &mut odom_rng);
            let seen = OdometryStep::between(&odom, &next)
                .map_err(|e| usage(format!("odometry {k}: {e}")))?;
            odom = next;
            mcl.predict(&seen, &mut rng);
        }
        if o.kidnap == Some(k) {
            if let Some(f) = &free {
                kidnap(&mut mcl, f, &truth, &mut kidnap_rng);
            }
        }
        let scan = &input.scans[k];
        let result = match o.weighting {
            Weighting::Product => {
                let prepared = model.prepare(&input.layout, scan);
                mcl.update_prepared(&prepared, free.as_ref(), &mut rng)
            }
            Weighting::AmclCube => {
                if scan.is_empty() {
                    Err(MclError::EmptyScan)
                } else {
                    mcl.update_with(
                        |p| amcl_cube(&view, &input.params, &input.layout, scan, o.stride, p),
                        free.as_ref(),
                        &mut rng,
                    )
                }
            }
        };
        let est = match result {
            Ok(u) => {
                out.resamplings += usize::from(u.resampled);
                out.injected += u64::from(u.injected);
                u.estimate.pose
            }
            Err(MclError::EmptyScan | MclError::AllImpossible) => {
                out.skipped += 1;
                mcl.estimate().pose
            }
            Err(e) => return Err(TrackError::Filter(e)),
        };
        let dx = f64::from(est.x_m - truth.x_m);
        let dy = f64::from(est.y_m - truth.y_m);
        out.estimates.push(est);
        out.trans_err_m.push(dx.hypot(dy));
        out.heading_err_deg.push(
            f64::from(wrap_angle(est.theta_rad - truth.theta_rad))
                .abs()
                .to_degrees(),
        );
        if progress && (k % 50 == 0 || k + 1 == n) {
            eprint!("\rseed {}: scan {}/{n}", o.seed, k + 1);
            if k + 1 == n {
                eprintln!();
            }
        }
    }
    Ok(out)
}

/// Moves the whole cloud rigidly so that the truth lands on a free pose at least
/// [`KIDNAP_MIN_M`] away: from the filter's side, the robot was carried off. The weights and
/// recovery averages are kept (only the poses move).
fn kidnap<const N: usize>(
    mcl: &mut Mcl<'_, N>,
    free: &FreeSpace<'_>,
    truth: &Pose,
    kidnap_rng: &mut SplitMix64,
) {
    let mut wrong = free.sample_pose(kidnap_rng);
    for _ in 0..10_000 {
        if (wrong.x_m - truth.x_m).hypot(wrong.y_m - truth.y_m) >= KIDNAP_MIN_M {
            break;
        }
        wrong = free.sample_pose(kidnap_rng);
    }
    // p' = wrong ⊕ (truth⁻¹ ⊕ p), in f64.
    let (tx, ty, tt) = (
        f64::from(truth.x_m),
        f64::from(truth.y_m),
        f64::from(truth.theta_rad),
    );
    let (wx, wy, wt) = (
        f64::from(wrong.x_m),
        f64::from(wrong.y_m),
        f64::from(wrong.theta_rad),
    );
    let turn = wt - tt;
    let (s, c) = turn.sin_cos();
    mcl.move_particles(|p| {
        let (dx, dy) = (f64::from(p.x_m) - tx, f64::from(p.y_m) - ty);
        Pose::new(
            (wx + c * dx - s * dy) as f32,
            (wy + s * dx + c * dy) as f32,
            (f64::from(p.theta_rad) + turn) as f32,
        )
    });
}

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
    if args.seeds == 0 {
        return Err(usage("--seeds must be at least 1"));
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
    for seed in args.seed..args.seed + args.seeds {
        let o = options(args, seed, input.scans.len())?;
        let r = run_once(&input, &o)?;
        if runs.is_empty() {
            if let Some(path) = &args.output {
                draw_track(path, &input, &r, o.scans)?;
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
    let conv: Vec<Option<usize>> = runs.iter().map(|(_, m, _)| m.converged_after).collect();
    let conv_ok: Vec<f64> = conv.iter().flatten().map(|&c| c as f64).collect();
    if json {
        let per: Vec<_> = runs
            .iter()
            .map(|(seed, m, r)| {
                serde_json::json!({ "seed": seed, "metrics": m, "skipped": r.skipped,
                    "resamplings": r.resamplings, "injected": r.injected })
            })
            .collect();
        return Ok(serde_json::json!({
            "scans": o.scans, "particles": o.particles, "kappa": o.kappa, "stride": o.stride,
            "odom_alphas": o.alphas, "init": format!("{:?}", o.init).to_lowercase(),
            "weighting": format!("{:?}", o.weighting), "recovery": [o.recovery.0, o.recovery.1],
            "kidnap": o.kidnap, "runs": per,
            "trans_rmse_cm_min_med_max": rmse, "heading_rmse_deg_min_med_max": head,
            "max_trans_m_min_med_max": maxe, "within_10cm_2deg_pct_min_med_max": within,
            "lost_runs": lost, "converged_runs": conv_ok.len(),
            "converged_after_min_med_max": if conv_ok.is_empty() { None } else { Some(min_med_max(conv_ok.clone())) },
        })
        .to_string());
    }
    let mut s = format!(
        "{} scans, {} particles, κ {}, stride {}, odom_alpha {:?}, init {:?}, weighting {:?}, \
         recovery {:?}{}\n",
        o.scans,
        o.particles,
        o.kappa,
        o.stride,
        o.alphas,
        o.init,
        o.weighting,
        o.recovery,
        o.kidnap
            .map(|k| format!(", kidnapped at scan {k}"))
            .unwrap_or_default()
    );
    for (seed, m, r) in &runs {
        s += &format!(
            "seed {seed}: trans RMSE {:.2} cm, heading RMSE {:.2}°, max {:.3} m, within 10 cm/2° \
             {:.1} %, {}{}; {} resamplings, {} injected, {} skipped\n",
            m.trans_rmse_m * 100.0,
            m.heading_rmse_deg,
            m.max_trans_m,
            m.within_10cm_2deg * 100.0,
            if m.lost { "LOST" } else { "not lost" },
            m.converged_after
                .map(|c| format!(", converged after {c} scans"))
                .unwrap_or_else(|| ", never converged".into()),
            r.resamplings,
            r.injected,
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
        let c = min_med_max(conv_ok);
        s += &format!(", after {:.0} / {:.0} / {:.0} scans", c[0], c[1], c[2]);
    }
    if let Some(p) = &args.output {
        s += &format!("\nwrote {}", p.display());
    }
    Ok(s)
}

/// Draws the logged (blue) and estimated (green) trajectories over the rendered field, one pixel
/// per cell, north up.
fn draw_track(
    path: &Path,
    input: &TrackInput,
    r: &RunResult,
    scans: usize,
) -> Result<(), TrackError> {
    let (view, _) = input.views()?;
    let base = render(&view);
    let scale = 1u32;
    let img = image::imageops::resize(
        &base,
        base.width() * scale,
        base.height() * scale,
        image::imageops::FilterType::Nearest,
    );
    let mut img = img;
    let h = view.header();
    let (w_px, h_px) = (img.width() as i64, img.height() as i64);
    let to_px = |p: &Pose| {
        let gx = (f64::from(p.x_m) - f64::from(h.origin_x_m)) / f64::from(h.cell_size_m);
        let gy = (f64::from(p.y_m) - f64::from(h.origin_y_m)) / f64::from(h.cell_size_m);
        (
            (gx * f64::from(scale)) as i64,
            h_px - 1 - (gy * f64::from(scale)) as i64,
        )
    };
    let mut line = |a: (i64, i64), b: (i64, i64), color: [u8; 3]| {
        let n = (b.0 - a.0).abs().max((b.1 - a.1).abs()).max(1);
        for i in 0..=n {
            let x = a.0 + (b.0 - a.0) * i / n;
            let y = a.1 + (b.1 - a.1) * i / n;
            for (ox, oy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let (px, py) = (x + ox, y + oy);
                if (0..w_px).contains(&px) && (0..h_px).contains(&py) {
                    img.put_pixel(px as u32, py as u32, image::Rgb(color));
                }
            }
        }
    };
    for pair in input.logged[..scans].windows(2) {
        line(to_px(&pair[0]), to_px(&pair[1]), [30, 80, 230]);
    }
    for pair in r.estimates.windows(2) {
        line(to_px(&pair[0]), to_px(&pair[1]), [0, 170, 0]);
    }
    img.save_with_format(path, image::ImageFormat::Png)
        .map_err(|e| TrackError::Png(path.to_path_buf(), e.to_string()))
}
