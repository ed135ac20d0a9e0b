//! `beamfield track`: Monte Carlo localization over a whole CARMEN log against its logged poses
//! (the runs themselves are [`crate::track`]): tracking error, global localization, kidnapping,
//! over one or more seeds; a PNG of the tracks over the map.

mod report;
pub use report::{SeedRun, TrackReport};

use crate::cmd::likelihood::LikelihoodArgs;
use crate::cmd::scored_log::MAX_BEAMS;
use crate::input::bag::{OdomFromTf, Topics};
use crate::track::{
    field_bytes, load_bag, load_with_max_range, read_odometry_file, read_reference_file, run_once,
    synthesize_odometry, usage, Init, Metrics, RunOptions, ScanLayout, TrackError, Weighting,
    WheelPreset, MAX_TRACK_PARTICLES, MAX_TRACK_SEEDS, WHEEL_SEED_XOR,
};
use beamfield::mcl::QualityThresholds;
use clap::Args;
use std::path::PathBuf;

/// The exit code of a `track --bag` run that was lost (its largest error against the reference
/// passed 0.5 m in at least one seed); the report is printed in full before it.
pub const EXIT_LOST: u8 = 3;

/// `beamfield track`: run the localizer over a log or a bag.
#[derive(Args, Debug, Clone)]
#[command(group(clap::ArgGroup::new("recording").required(true).args(["log", "bag"])))]
#[command(
    after_help = "Exit codes: 0 the runs ended (with --bag: none was lost); 1 an error \
    (the line on stderr says which); 3 with --bag, the report is printed but at least one run \
    was lost: its largest error against the reference topic passed 0.5 m (a line on stderr \
    says so). A lost run with --log is reported on stderr too, with exit code 0."
)]
pub struct TrackArgs {
    /// The distance-field blob (`beamfield field build`; `--init global` and recovery need it
    /// built with `--free-space`), or a nav2 map YAML, turned into a blob with its free space.
    #[arg(long)]
    pub field: PathBuf,
    /// The CARMEN log (FLASER lines with corrected poses, or odometry: --log-poses).
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// What the log's FLASER poses are: `truth` (corrected poses: the errors are measured
    /// against them and the odometry is synthesized or given), or `odometry` (the robot's own
    /// odometry, e.g. `data/laser_intel_lab_raw_odometry/intel-real-odom.clf`: the filter's
    /// odometry; needs --reference for the truth).
    #[arg(long, value_enum, default_value_t = LogPoses::Truth, requires = "log")]
    pub log_poses: LogPoses,
    /// Reference poses at some scans of the log (the truth there, in the map's frame): a
    /// table with a header naming `index` and `ref_x ref_y ref_theta` (or `x y theta`), as
    /// `anchors.tsv`, or lines `index x y θ`. The run starts at the first reference scan,
    /// around its pose, and errors, lost runs and the quality table are computed at the
    /// reference scans only.
    #[arg(long, value_name = "FILE", requires = "log")]
    pub reference: Option<PathBuf>,
    /// A ROS 2 bag: an .mcap file, a .db3 file (sqlite3, Humble's default storage), or a
    /// rosbag2 directory of either; scans, odometry and a reference pose by topic; the
    /// odometry is the bag's (needs --reference-topic).
    #[arg(long, conflicts_with = "odometry")]
    pub bag: Option<PathBuf>,
    /// The bag's sensor_msgs/LaserScan topic.
    #[arg(long, default_value = "/scan", requires = "bag")]
    pub scan_topic: String,
    /// The bag's nav_msgs/Odometry topic. A bag without it takes its odometry from /tf: the
    /// transforms ODOM_FRAME → BASE_FRAME.
    #[arg(long, default_value = "/odom", requires = "bag")]
    pub odom_topic: String,
    /// Bin every scan onto this layout: the first beam's bearing and the step in degrees
    /// (counter-clockwise in the laser's frame) and the beam count, e.g. "-180,1,360". Each
    /// reading goes to the beam nearest to its bearing within half a step (the nearest of
    /// several stays), as the device bins a LiDAR's revolution. Without it, scans whose angles
    /// change from one to the next (an LD06 driver's) are binned onto the layout covering
    /// them: the median first and last bearings at the largest step.
    #[arg(
        long,
        value_name = "MIN_DEG,STEP_DEG,BEAMS",
        allow_hyphen_values = true,
        requires = "bag"
    )]
    pub scan_layout: Option<String>,
    /// The odometry frame on /tf, for a bag with no odometry topic.
    #[arg(long, default_value = "odom", requires = "bag")]
    pub odom_frame: String,
    /// The bag's reference pose (PoseWithCovarianceStamped or PoseStamped: a recorded
    /// amcl_pose, ground truth) the errors are measured against.
    #[arg(long, requires = "bag")]
    pub reference_topic: Option<String>,
    /// The robot's frame: the laser's mount is BASE_FRAME → the scans' frame, composed through
    /// any chain of /tf_static transforms (e.g. base_footprint → base_link → laser); a scan
    /// frame not connected to it is refused.
    #[arg(long, default_value = "base_link", requires = "bag")]
    pub base_frame: String,
    /// Recorded odometry for the log instead of synthesized: lines `index x y θ` (m, m, rad;
    /// index 0 = the log's first scan; `#` comments). --odom-noise is then only the filter's
    /// motion model.
    #[arg(long, value_name = "FILE", requires = "log")]
    pub odometry: Option<PathBuf>,
    /// Odometry from a differential-drive wheel model instead of the filter's own noise model:
    /// the logged steps driven by wheels whose radii and wheelbase are not what the odometry
    /// believes, with slip (no Gaussian noise on the pose). Each seed S draws its slip from
    /// S ^ 0x776865656c. --odom-noise is then only the filter's motion model.
    #[arg(long, value_enum, value_name = "PRESET", requires = "log",
          conflicts_with_all = ["odometry", "bag"])]
    pub wheel_odometry: Option<WheelPreset>,
    /// Synthesize the odometry with this noise ("A" or "A1,A2,A3,A4", as --odom-noise) instead
    /// of --odom-noise, which is then only the filter's: odometry noisier (or quieter) than the
    /// filter assumes. The same generator and seeds as without it.
    #[arg(long, value_name = "ALPHAS", requires = "log",
          conflicts_with_all = ["odometry", "bag", "wheel_odometry"])]
    pub synthetic_odom_noise: Option<String>,
    /// The log's max-range ("no return") value in metres; readings at or above it are no
    /// return. Default: detected from the ranges (81.83 in the Intel log).
    #[arg(long, value_name = "M", requires = "log")]
    pub max_range: Option<f32>,
    /// Number of particles (1 to 20,000).
    #[arg(long, default_value_t = 500,
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=MAX_TRACK_PARTICLES as u64))]
    pub particles: usize,
    /// Tempering κ of the summed log-likelihood (dimensionless, > 0). 64 is chosen for a filter
    /// that applies every scan (docs/localization.md, "Tempering over time"); 8.25 is what
    /// `beamfield calibrate` finds for one scan on the Intel log, and what the crate used before.
    #[arg(long, default_value_t = 64.0)]
    pub kappa: f32,
    /// Score every S-th beam (1 to 1081, the most beams a scan has here).
    #[arg(long, default_value_t = 1,
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new()
              .range(1..=MAX_BEAMS as u64))]
    pub stride: usize,
    /// Odometry noise odom_alpha1..4 (variance coefficients, AMCL's convention), used both to
    /// synthesize the odometry and in the filter (only in the filter with --odometry, --bag or
    /// --wheel-odometry): "A" or "A1,A2,A3,A4".
    #[arg(long = "odom-noise", default_value = "0.02")]
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
    /// Leave out beams the map cannot explain, "DISTANCE,SHARE" (off by default;
    /// MclConfig::with_unexplained, product weighting only): at each update, a beam whose
    /// endpoint at the predicted estimate lies more than DISTANCE metres from every obstacle
    /// and whose ray reaches it without crossing a mapped wall (something unmapped in front)
    /// is left out for every particle; none when more than SHARE (0 to 1) of the beams would
    /// be. E.g. "--unexplained 0.25,0.5".
    #[arg(long)]
    pub unexplained: Option<String>,
    /// Recovery in fixed memory driven by the quality signal (off by default;
    /// MclConfig::with_resetting with Resetting::DEFAULT, docs/localization.md): when a scan's
    /// explained share is below 0.4 the cloud is widened in place (σ 0.1 m / 0.05 rad, doubling
    /// up to 8×); after 2 updates reported Lost the set is renewed from the best of 100 scored
    /// free-space candidates per particle; no augmented-MCL injection while tracking for 20
    /// updates. Needs a field built with --free-space.
    #[arg(long)]
    pub resetting: bool,
    /// The adaptive motion noise (off by default; MclConfig::with_adaptive_noise,
    /// docs/localization.md): the odometry variances scaled at every update so that the
    /// scan's correction of the predicted cloud matches its spread. "TARGET,RATE,MIN,MAX" (the
    /// squared Mahalanobis correction steered to, the rate, the variance scale's bounds), or no
    /// value for the defaults "1,0.3,0.25,4" (AdaptiveNoise::DEFAULT).
    #[arg(long, num_args = 0..=1, default_missing_value = "1,0.3,0.25,4", value_name = "T,R,MIN,MAX")]
    pub adaptive_noise: Option<String>,
    /// With --resetting: the most free-space candidates scored per update (0, the default:
    /// all 100 × particles at the update that starts the reset; N spreads them over updates,
    /// N each, Resetting::candidates_per_update).
    #[arg(long, default_value_t = 0, value_name = "N", requires = "resetting")]
    pub reset_per_update: u32,
    /// The quality signal's clutter allowance: up to this share of a scan's beams (0 to below 1)
    /// that end in front of a mapped wall the map does not explain are set aside before the
    /// explained share is judged (QualityThresholds::clutter_share; 0: off).
    #[arg(long, default_value_t = QualityThresholds::DEFAULT.clutter_share, value_name = "S")]
    pub clutter_share: f32,
    /// The quality signal's Lost on readings through mapped walls: an average share of beams
    /// (0 to 1) that cross a mapped wall to reach their endpoint above which the state is Lost
    /// (QualityThresholds::lost_through; 1: off).
    #[arg(long, default_value_t = QualityThresholds::DEFAULT.lost_through, value_name = "SHARE")]
    pub lost_through: f32,
    /// KLD sampling "MIN,MAX" (off by default; MclConfig::with_kld with nav2's pf_err 0.05,
    /// pf_z 0.99 and 0.5 m / 10° bins): the particles in use adapt at each resampling between
    /// MIN and MAX, starting from --particles.
    #[arg(long, value_name = "MIN,MAX")]
    pub kld: Option<String>,
    /// The likelihood's σ_hit follows the cloud's spread, "GAIN,MAX": before each update
    /// σ² = σ_hit² + GAIN · (var x + var y) / 2 of the predicted particles, at most MAX metres
    /// (off by default).
    #[arg(long, value_name = "GAIN,MAX", allow_hyphen_values = true)]
    pub adaptive_sigma: Option<String>,
    /// Tempering κ while the quality signal does not report Tracking (default: --kappa always).
    #[arg(long, value_name = "K")]
    pub kappa_uncertain: Option<f32>,
    /// Update the filter only once the odometry has moved D metres or turned A radians since
    /// the last update, "D,A" (AMCL's update_min_d and update_min_a; nav2's defaults are
    /// "0.25,0.2"); between updates the estimate is the last one carried by the odometry. The
    /// default "0,0" updates at every scan.
    #[arg(
        long,
        default_value = "0,0",
        value_name = "D,A",
        allow_hyphen_values = true
    )]
    pub update_min: String,
    /// Resample when the effective sample size falls below this fraction of the particles.
    #[arg(long = "resample-ess", default_value_t = 0.5)]
    pub resample_ess: f32,
    /// The likelihood field's mixture.
    #[command(flatten)]
    pub likelihood: LikelihoodArgs,
    /// Stop after this many scans (default: the whole log).
    #[arg(long)]
    pub scans: Option<usize>,
    /// Draw the estimated (green) and logged (blue) trajectories over the map (first seed).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

/// What a log's FLASER poses are (`--log-poses`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LogPoses {
    /// Corrected poses: the truth.
    Truth,
    /// The robot's odometry: the filter's input, not the truth (needs --reference).
    Odometry,
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

/// `--scan-layout MIN_DEG,STEP_DEG,BEAMS`.
fn scan_layout(text: &str) -> Result<ScanLayout, TrackError> {
    let v: Vec<f64> = text
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            usage(format!(
                "--scan-layout {text:?}: expected numbers separated by commas"
            ))
        })?;
    if v.len() != 3 {
        return Err(usage(format!("--scan-layout {text:?}: expected 3 numbers")));
    }
    let beams = v[2];
    let ok = v[0].is_finite()
        && v[1].is_finite()
        && v[1] > 0.0
        && beams >= 1.0
        && beams <= MAX_BEAMS as f64
        && beams.fract() == 0.0
        && v[1] * beams <= 360.0 + 1e-3;
    if !ok {
        return Err(usage(format!(
            "--scan-layout {text:?}: a first bearing (degrees), a step (degrees, > 0) and 1 to {MAX_BEAMS} beams spanning at most 360°"
        )));
    }
    Ok(ScanLayout {
        angle_min_rad: v[0].to_radians(),
        increment_rad: v[1].to_radians(),
        beams: beams as usize,
    })
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
    let unexplained = match &args.unexplained {
        Some(text) => {
            let v = parse_list(text, "--unexplained", 2)?;
            Some((v[0], v[1]))
        }
        None => None,
    };
    let adaptive_noise = match &args.adaptive_noise {
        Some(text) => {
            let v = parse_list(text, "--adaptive-noise", 4)?;
            Some([v[0], v[1], v[2], v[3]])
        }
        None => None,
    };
    let kld = match &args.kld {
        Some(text) => {
            let v = parse_list(text, "--kld", 2)?;
            let count = |x: f32| {
                (x >= 1.0 && x <= MAX_TRACK_PARTICLES as f32 && x.fract() == 0.0)
                    .then_some(x as u16)
                    .ok_or_else(|| {
                        usage(format!(
                            "--kld {text:?}: counts in 1..={MAX_TRACK_PARTICLES}"
                        ))
                    })
            };
            Some((count(v[0])?, count(v[1])?))
        }
        None => None,
    };
    let adaptive_sigma = match &args.adaptive_sigma {
        Some(text) => {
            let v = parse_list(text, "--adaptive-sigma", 2)?;
            if !(v[0].is_finite() && v[0] >= 0.0 && v[1].is_finite() && v[1] > 0.0) {
                return Err(usage(format!(
                    "--adaptive-sigma {text:?}: a gain ≥ 0 and a largest σ > 0 (m)"
                )));
            }
            Some((v[0], v[1]))
        }
        None => None,
    };
    let m = parse_list(&args.update_min, "--update-min", 2)?;
    if !m.iter().all(|x| x.is_finite() && *x >= 0.0) {
        return Err(usage(format!(
            "--update-min {:?}: a distance (m) and an angle (rad), each finite and at least 0",
            args.update_min
        )));
    }
    Ok(RunOptions {
        update_min: (m[0], m[1]),
        reset_per_update: args.reset_per_update,
        clutter_share: args.clutter_share,
        lost_through: args.lost_through,
        adaptive_noise,
        kld,
        adaptive_sigma,
        kappa_uncertain: match args.kappa_uncertain {
            Some(k) if !(k.is_finite() && k > 0.0) => {
                return Err(usage(format!(
                    "--kappa-uncertain {k}: a tempering κ, finite and > 0"
                )))
            }
            k => k,
        },
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
        unexplained,
        resetting: args.resetting,
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

/// Runs `beamfield track`.
///
/// # Errors
/// [`TrackError`].
pub fn run(args: &TrackArgs) -> Result<TrackReport, TrackError> {
    let lk = (
        args.likelihood.z_hit,
        args.likelihood.z_rand,
        args.likelihood.sigma_hit,
    );
    let (mut input, bag, odometry) = match (&args.log, &args.bag) {
        (Some(log), None) => {
            let mut input = load_with_max_range(&args.field, log, lk, args.max_range)?;
            if let Some(path) = &args.reference {
                input.reference = Some(read_reference_file(path, input.scans.len())?);
            }
            let from_log = args.log_poses == LogPoses::Odometry;
            if from_log {
                if args.reference.is_none() {
                    return Err(usage(
                        "--log-poses odometry: the log holds no truth; give --reference with poses at some scans",
                    ));
                }
                if args.odometry.is_some()
                    || args.wheel_odometry.is_some()
                    || args.synthetic_odom_noise.is_some()
                {
                    return Err(usage(
                        "--log-poses odometry: the log's poses are the odometry; --odometry, --wheel-odometry and --synthetic-odom-noise need a log of true poses",
                    ));
                }
                input.odometry = Some(input.logged.clone());
            }
            let source = match (&args.odometry, args.wheel_odometry) {
                (Some(_), Some(_)) => {
                    return Err(usage("give at most one of --odometry and --wheel-odometry"))
                }
                (None, Some(preset)) => {
                    let e = preset.errors();
                    format!(
                        "wheel model {} (left radius {:+.1} %, right radius {:+.1} %, wheelbase \
                         {:+.1} %, slip sigma {:.1} % per step{}; slip seed S ^ {WHEEL_SEED_XOR:#x})",
                        preset.name(),
                        (e.left_radius_scale - 1.0) * 100.0,
                        (e.right_radius_scale - 1.0) * 100.0,
                        (e.wheelbase_scale - 1.0) * 100.0,
                        e.slip_sigma * 100.0,
                        e.hard_slip.map_or(String::new(), |h| format!(
                            ", hard slip p {} losing {:.0} %",
                            h.p,
                            h.loss * 100.0
                        )),
                    )
                }
                (Some(path), None) => {
                    // Poses for the scans the run uses.
                    let used = args
                        .scans
                        .map_or(input.scans.len(), |n| n.min(input.scans.len()));
                    input.odometry = Some(read_odometry_file(path, used)?);
                    format!("recorded ({})", path.display())
                }
                (None, None) if from_log => {
                    format!("recorded (the log's poses, {})", log.display())
                }
                (None, None) => match &args.synthetic_odom_noise {
                    Some(text) => format!(
                        "synthesized from the logged poses with the motion model's noise at \
                         odom_alpha {:?} (the filter's: --odom-noise)",
                        parse_list(text, "--synthetic-odom-noise", 4)?
                    ),
                    None => {
                        "synthesized from the logged poses with the motion model's noise".into()
                    }
                },
            };
            (input, None, source)
        }
        (None, Some(path)) => {
            let bytes = field_bytes(&args.field)?;
            let topics = Topics {
                scan: args.scan_topic.clone(),
                odom: args.odom_topic.clone(),
                reference: args.reference_topic.clone(),
                odom_from_tf: Some(OdomFromTf {
                    topic: "/tf".into(),
                    odom_frame: args.odom_frame.clone(),
                    base_frame: args.base_frame.clone(),
                }),
                ..Topics::default()
            };
            let layout = match &args.scan_layout {
                Some(text) => Some(scan_layout(text)?),
                None => None,
            };
            let (input, summary) = load_bag(bytes, path, &topics, &args.base_frame, lk, layout)?;
            let source = if summary.odometry_from_tf {
                // Said where a user sees it even with --json: a mistyped --odom-topic lands here.
                eprintln!(
                    "beamfield track: the bag has no {} topic: odometry from /tf ({} → {})",
                    args.odom_topic, args.odom_frame, args.base_frame
                );
                format!(
                    "recorded (/tf: {} → {}; the bag has no {})",
                    args.odom_frame, args.base_frame, args.odom_topic
                )
            } else {
                format!("recorded ({})", args.odom_topic)
            };
            (input, Some(summary), source)
        }
        _ => return Err(usage("give one of --log and --bag")),
    };
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
        if let Some(preset) = args.wheel_odometry {
            // This seed's wheels, for the scans the run uses.
            let used = input.logged.get(..o.scans).unwrap_or(&input.logged);
            input.odometry = Some(preset.odometry(used, seed));
        } else if let Some(text) = &args.synthetic_odom_noise {
            let a = parse_list(text, "--synthetic-odom-noise", 4)?;
            let noise = beamfield::mcl::OdometryNoise::new(a[0], a[1], a[2], a[3])
                .map_err(|e| usage(format!("--synthetic-odom-noise {text:?}: {e}")))?;
            let used = input.logged.get(..o.scans).unwrap_or(&input.logged);
            input.odometry = Some(synthesize_odometry(&noise, used, seed)?);
        }
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
    let per = runs
        .iter()
        .map(|(seed, m, r)| SeedRun {
            seed: *seed,
            metrics: *m,
            skipped: r.skipped,
            resamplings: r.resamplings,
            injected: r.injected,
            retries: r.retries,
            particles_mean_max: [
                r.particles_in_use.iter().sum::<usize>() as f32
                    / r.particles_in_use.len().max(1) as f32,
                r.particles_in_use.iter().copied().max().unwrap_or(0) as f32,
            ],
            noise_scale_mean_max: [
                r.noise_scales.iter().sum::<f32>() / r.noise_scales.len().max(1) as f32,
                r.noise_scales.iter().copied().fold(0.0, f32::max),
            ],
            resets: r.resets,
            per_scan: r.per_scan.clone(),
        })
        .collect();
    Ok(TrackReport {
        scans: o.scans,
        particles: o.particles,
        kappa: o.kappa,
        stride: o.stride,
        odom_alphas: o.alphas,
        init: format!("{:?}", o.init).to_lowercase(),
        weighting: format!("{:?}", o.weighting),
        recovery: [o.recovery.0, o.recovery.1],
        recovery_while_unsettled: o.recovery_while_unsettled,
        resetting: o.resetting,
        retry: o.retry.map(|(d, k)| [d, k]),
        kidnap: o.kidnap,
        adaptive_noise: o.adaptive_noise,
        kld: o.kld.map(|(a, b)| [a, b]),
        adaptive_sigma: o.adaptive_sigma.map(|(g, m)| [g, m]),
        kappa_uncertain: o.kappa_uncertain,
        update_min: [o.update_min.0, o.update_min.1],
        runs: per,
        trans_rmse_cm_min_med_max: rmse,
        heading_rmse_deg_min_med_max: head,
        max_trans_m_min_med_max: maxe,
        within_10cm_2deg_pct_min_med_max: within,
        lost_runs: lost,
        lost_after_convergence_runs: lost_after,
        converged_runs: conv_ok.len(),
        converged_after_min_med_max: if conv_ok.is_empty() {
            None
        } else {
            Some(min_med_max(conv_ok))
        },
        options: o,
        output: args.output.as_ref().map(|p| p.display().to_string()),
        odometry,
        scored: if args.reference.is_some() {
            "reference".into()
        } else {
            "every scan".into()
        },
        odometry_model: match (&args.bag, &args.odometry, args.wheel_odometry) {
            (Some(_), _, _) | (_, Some(_), _) => "recorded".into(),
            _ if args.log_poses == LogPoses::Odometry => "recorded".into(),
            (_, _, Some(p)) => format!("wheels-{}", p.name()),
            _ => "synthetic".into(),
        },
        bag,
    })
}
