//! `beamfield score` and `beamfield calibrate`: the likelihood field on the scans of a CARMEN
//! log, at one pose, over a local pose grid, and κ calibration (docs/models.md#tempering).
//!
//! The FLASER pose is the laser's pose, so scans are scored with a centred mount and poses are
//! laser poses (metres, radians in the map frame).

use crate::calibrate::{calibrate, Calibration};
use crate::draw::plot::{line_chart, LineChart, Series};
use crate::input::carmen::{CarmenLog, LogError, ReadOptions};
use crate::pose_grid::{argmax, posterior_sd, score_grid, GridSpec};
use beamfield::field::{LikelihoodField, LikelihoodParams};
use beamfield::{BeamLayout, Pose, Scan, SensorModel, SensorMount, Tempered};
use clap::Args;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Beam capacity of the scans these commands read (CARMEN FLASER scans have 180 or 361).
pub const MAX_BEAMS: usize = 1081;

/// Most scores `calibrate` keeps (scans × grid poses, one f64 each): 2²⁵, 256 MiB. The
/// default grid (41 × 41 × 41 poses) over the default 60 scans is 4.1 M.
pub const MAX_CALIBRATE_SCORES: u64 = 1 << 25;

/// Likelihood-field parameters shared by both commands.
#[derive(Args, Debug, Clone)]
pub struct ModelArgs {
    /// The distance-field blob (`beamfield field build`).
    #[arg(long)]
    pub field: PathBuf,
    /// The CARMEN log (FLASER lines with poses).
    #[arg(long)]
    pub log: PathBuf,
    /// σ_hit of the likelihood field, metres.
    #[arg(long = "sigma-hit", default_value_t = 0.05)]
    pub sigma_hit: f32,
    /// z_hit weight.
    #[arg(long = "z-hit", default_value_t = 0.95)]
    pub z_hit: f32,
    /// z_rand weight.
    #[arg(long = "z-rand", default_value_t = 0.05)]
    pub z_rand: f32,
    /// The sensor's max-range ("no return") value, metres (default: detected in the log, as
    /// `beamfield log info` reports it).
    #[arg(long = "max-range")]
    pub max_range: Option<f32>,
}

/// `beamfield score`: log-likelihood of one scan of a log at a pose.
#[derive(Args, Debug)]
pub struct ScoreArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Index of the scan in the log (0-based, FLASER lines in file order).
    #[arg(long)]
    scan: usize,
    /// Laser pose "X,Y,THETA" (metres, metres, radians); default: the logged pose.
    #[arg(long, allow_hyphen_values = true)]
    pose: Option<String>,
    /// Tempering κ (the log-likelihood is divided by it).
    #[arg(long, default_value_t = 1.0)]
    kappa: f32,
    /// Also score an x–y grid at the pose's θ and a θ profile, writing PREFIX.csv,
    /// PREFIX-xy.png and PREFIX-theta.png.
    #[arg(long, value_name = "PREFIX")]
    grid: Option<PathBuf>,
    /// Grid half-width in x and y, metres.
    #[arg(long = "grid-half", default_value_t = 0.2)]
    grid_half: f64,
    /// Grid step in x and y, metres.
    #[arg(long = "grid-step", default_value_t = 0.005)]
    grid_step: f64,
    /// θ profile half-width, degrees (step 0.25°).
    #[arg(long = "grid-half-deg", default_value_t = 10.0)]
    grid_half_deg: f64,
    /// Write a PNG of the scan's endpoints over the field around the pose: at the pose (blue)
    /// and at the best pose of the x–y–θ grid that --grid-half, --grid-step and
    /// --grid-half-deg span (θ in 0.25° steps; green), with the offset between them in the
    /// title. The best pose is also printed.
    #[arg(long, value_name = "PNG")]
    overlay: Option<PathBuf>,
    /// Half-width of the --overlay picture's window, metres.
    #[arg(long = "overlay-half", default_value_t = 6.0)]
    overlay_half: f64,
    /// Centre "X,Y" of the --overlay picture's window (metres, map frame); default: the pose.
    #[arg(
        long = "overlay-center",
        allow_hyphen_values = true,
        value_name = "X,Y"
    )]
    overlay_center: Option<String>,
}

/// `beamfield calibrate`: the smallest κ whose credible sets hold the logged poses.
#[derive(Args, Debug)]
pub struct CalibrateArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Requested coverage of the credible sets (their level).
    #[arg(long, default_value_t = 0.95)]
    coverage: f64,
    /// Number of scans, spread evenly over the log.
    #[arg(long, default_value_t = 60)]
    scans: usize,
    /// Grid half-width in x and y, metres.
    #[arg(long = "half-xy", default_value_t = 0.08)]
    half_xy: f64,
    /// Grid step in x and y, metres.
    #[arg(long = "step-xy", default_value_t = 0.004)]
    step_xy: f64,
    /// Grid half-width in θ, degrees.
    #[arg(long = "half-deg", default_value_t = 2.0)]
    half_deg: f64,
    /// Grid step in θ, degrees.
    #[arg(long = "step-deg", default_value_t = 0.1)]
    step_deg: f64,
    /// Write a PNG of coverage against κ.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

/// Errors of `score` and `calibrate`.
#[derive(Debug)]
#[non_exhaustive]
pub enum ScoreCmdError {
    /// The blob could not be read.
    Io(PathBuf, std::io::Error),
    /// A file that is not a regular file or over its size limit (docs/resource-limits.md).
    Read(crate::input::limits::ReadError),
    /// The blob is malformed.
    Blob(beamfield::field::BlobError),
    /// The log could not be read.
    Log(LogError),
    /// A bad option value.
    Usage(String),
    /// The plot could not be drawn.
    Plot(String),
}

impl std::fmt::Display for ScoreCmdError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Io(p, e) => write!(f, "{}: {e}", p.display()),
            Self::Read(e) => write!(f, "{e}"),
            Self::Blob(e) => write!(f, "bad field blob: {e}"),
            Self::Log(e) => write!(f, "{e}"),
            Self::Usage(m) => f.write_str(m),
            Self::Plot(m) => write!(f, "plot: {m}"),
        }
    }
}

impl std::error::Error for ScoreCmdError {}

fn usage(m: impl Into<String>) -> ScoreCmdError {
    ScoreCmdError::Usage(m.into())
}

struct Loaded {
    blob: Vec<u8>,
    log: CarmenLog,
    params: LikelihoodParams,
    layout: BeamLayout<MAX_BEAMS>,
}

fn load(m: &ModelArgs) -> Result<Loaded, ScoreCmdError> {
    let blob = crate::input::limits::read_regular_file(
        &m.field,
        crate::input::limits::MAX_FIELD_FILE_BYTES,
        "field file",
    )
    .map_err(ScoreCmdError::Read)?;
    crate::field_cmd::parse_field_file(&blob).map_err(ScoreCmdError::Blob)?;
    let options = ReadOptions {
        max_range_m: m.max_range,
        ..ReadOptions::default()
    };
    let log = CarmenLog::read_path(&m.log, options).map_err(ScoreCmdError::Log)?;
    if log.scans.is_empty() {
        return Err(usage(format!(
            "{}: no FLASER scans in the log",
            m.log.display()
        )));
    }
    let max_range = log.max_range.value_m().ok_or_else(|| {
        usage("the log's max-range value could not be detected: pass --max-range METRES")
    })?;
    let params = LikelihoodParams::new(m.z_hit, m.z_rand, m.sigma_hit, max_range)
        .map_err(|e| usage(format!("likelihood field parameters: {e}")))?;
    let layout = log
        .layout_with_mount(SensorMount::CENTERED)
        .map_err(|e| usage(format!("beam layout of the log: {e}")))?;
    Ok(Loaded {
        blob,
        log,
        params,
        layout,
    })
}

fn scan_of(log: &CarmenLog, i: usize) -> Result<(Scan<MAX_BEAMS>, Pose), ScoreCmdError> {
    let s = log
        .scans
        .get(i)
        .ok_or_else(|| usage(format!("scan {i}: the log has {} scans", log.scans.len())))?;
    let scan = s
        .to_scan()
        .map_err(|e| usage(format!("scan {i} (line {}): {e}", s.line)))?;
    Ok((scan, s.pose))
}

fn parse_pose(text: &str) -> Result<Pose, ScoreCmdError> {
    let v: Vec<f32> = text
        .split(',')
        .map(|t| t.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| usage(format!("--pose {text:?}: expected X,Y,THETA (numbers)")))?;
    match v.as_slice() {
        [x, y, t] if v.iter().all(|a| a.is_finite()) => Ok(Pose::new(*x, *y, *t)),
        _ => Err(usage(format!(
            "--pose {text:?}: expected three finite numbers"
        ))),
    }
}

/// Runs `beamfield score`; returns the text (or JSON) to print.
///
/// # Errors
/// [`ScoreCmdError`] for unreadable inputs, bad options or a failed plot.
pub fn run_score(a: &ScoreArgs, json: bool) -> Result<String, ScoreCmdError> {
    let l = load(&a.model)?;
    let lf = LikelihoodField::new(
        crate::field_cmd::parse_field_file(&l.blob).map_err(ScoreCmdError::Blob)?,
        l.params,
    );
    let model = Tempered::new(lf, a.kappa, 1).map_err(|e| usage(format!("--kappa: {e}")))?;
    let (scan, logged) = scan_of(&l.log, a.scan)?;
    let pose = match &a.pose {
        Some(t) => parse_pose(t)?,
        None => logged,
    };
    let s = model.score(&l.layout, &scan, &pose);
    let mut out = String::new();
    let mut files = Vec::new();
    if let Some(prefix) = &a.grid {
        files = write_grid(a, &model, &l.layout, &scan, &pose, prefix)?;
    }
    let mut best = None;
    if let Some(path) = &a.overlay {
        let center = overlay_center(a, &pose)?;
        let b = best_grid_pose(a, &model, &l.layout, &scan, &pose)?;
        write_overlay(a, &l, &scan, &pose, center, &b, path)?;
        files.push(path.display().to_string());
        best = Some(b);
    }
    if json {
        out = serde_json::json!({
            "scan": a.scan,
            "pose_m_m_rad": [pose.x_m, pose.y_m, pose.theta_rad],
            "logged_pose_m_m_rad": [logged.x_m, logged.y_m, logged.theta_rad],
            "kappa": a.kappa,
            "log_likelihood_nats": s.log_likelihood,
            "beams_scored": s.scored,
            "beams_skipped_max_range": s.max_range,
            "beams_skipped_invalid": s.invalid,
            "beams_unpaired": s.unpaired,
            "best_grid_pose": best.as_ref().map(|b| serde_json::json!({
                "pose_m_m_rad": [b.pose.x_m, b.pose.y_m, b.pose.theta_rad],
                "offset_m_m_rad": [b.offset.0, b.offset.1, b.offset.2],
                "log_likelihood_nats": b.log_likelihood,
                "grid_poses": b.poses,
            })),
            "files": files,
        })
        .to_string();
    } else {
        let _ = writeln!(
            out,
            "scan {} at ({:.3} m, {:.3} m, {:.4} rad), κ = {}: log-likelihood {:.3} nats",
            a.scan, pose.x_m, pose.y_m, pose.theta_rad, a.kappa, s.log_likelihood
        );
        let _ = write!(
            out,
            "beams: {} scored, {} max-range skipped, {} invalid, {} unpaired",
            s.scored, s.max_range, s.invalid, s.unpaired
        );
        if let Some(b) = &best {
            let (dx, dy, dt) = b.offset;
            let _ = write!(
                out,
                "\nbest of {} grid poses: ({:.3} m, {:.3} m, {:.4} rad), {:.1} cm ({:+.1}, {:+.1}) and {:+.2}° from the pose; log-likelihood {:.3} nats ({:+.3})",
                b.poses,
                b.pose.x_m,
                b.pose.y_m,
                b.pose.theta_rad,
                (dx * dx + dy * dy).sqrt() * 100.0,
                dx * 100.0,
                dy * 100.0,
                dt.to_degrees(),
                b.log_likelihood,
                b.log_likelihood - f64::from(s.log_likelihood)
            );
        }
        for f in &files {
            let _ = write!(out, "\nwrote {f}");
        }
    }
    Ok(out)
}

fn check_grid(a: &ScoreArgs) -> Result<(), ScoreCmdError> {
    if !(a.grid_step > 0.0 && a.grid_half >= a.grid_step && a.grid_half / a.grid_step <= 500.0) {
        return Err(usage(
            "--grid-step must be > 0 and at most --grid-half, with ≤ 500 steps per side",
        ));
    }
    if !(a.grid_half_deg > 0.0 && a.grid_half_deg <= 180.0) {
        return Err(usage("--grid-half-deg must be in (0, 180]"));
    }
    Ok(())
}

/// The best pose of the x–y–θ grid around the given pose (`--overlay`).
struct BestPose {
    pose: Pose,
    offset: (f64, f64, f64),
    log_likelihood: f64,
    poses: usize,
}

fn best_grid_pose<M: SensorModel<MAX_BEAMS>>(
    a: &ScoreArgs,
    model: &M,
    layout: &BeamLayout<MAX_BEAMS>,
    scan: &Scan<MAX_BEAMS>,
    pose: &Pose,
) -> Result<BestPose, ScoreCmdError> {
    check_grid(a)?;
    let spec = GridSpec {
        half_xy_m: a.grid_half,
        step_xy_m: a.grid_step,
        half_theta_rad: a.grid_half_deg.to_radians(),
        step_theta_rad: 0.25f64.to_radians(),
    };
    if spec.len() > 20_000_000 {
        return Err(usage(format!(
            "--overlay: the x–y–θ grid has {} poses (at most 20 million): use a coarser --grid-step or a smaller --grid-half or --grid-half-deg",
            spec.len()
        )));
    }
    crate::progress::note(&format!(
        "score: searching {} poses for the overlay's best pose",
        spec.len()
    ));
    let g = score_grid(model, layout, scan, pose, &spec);
    let i = argmax(&g.log_likelihood).ok_or_else(|| usage("the pose grid is empty"))?;
    Ok(BestPose {
        pose: spec.pose(pose, i),
        offset: spec.offset(i),
        log_likelihood: g.log_likelihood.get(i).copied().unwrap_or(f64::NAN),
        poses: spec.len(),
    })
}

/// The `--overlay` window's centre (metres), checking `--overlay-half` and `--overlay-center`.
fn overlay_center(a: &ScoreArgs, pose: &Pose) -> Result<(f64, f64), ScoreCmdError> {
    if !(a.overlay_half.is_finite() && a.overlay_half > 0.0 && a.overlay_half <= 1000.0) {
        return Err(usage("--overlay-half must be in (0, 1000] metres"));
    }
    Ok(match &a.overlay_center {
        None => (f64::from(pose.x_m), f64::from(pose.y_m)),
        Some(t) => {
            let v: Vec<f64> = t
                .split(',')
                .map(|p| p.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| usage(format!("--overlay-center {t:?}: expected X,Y (numbers)")))?;
            match v.as_slice() {
                [x, y] if x.is_finite() && y.is_finite() => (*x, *y),
                _ => {
                    return Err(usage(format!(
                        "--overlay-center {t:?}: expected two finite numbers"
                    )))
                }
            }
        }
    })
}

fn write_overlay(
    a: &ScoreArgs,
    l: &Loaded,
    scan: &Scan<MAX_BEAMS>,
    pose: &Pose,
    center: (f64, f64),
    best: &BestPose,
    path: &Path,
) -> Result<(), ScoreCmdError> {
    let bearings: Vec<f32> = l.layout.beams().iter().map(|b| b.bearing_rad).collect();
    let max_range = l.params.max_range_m();
    let at = |p: &Pose| (f64::from(p.x_m), f64::from(p.y_m), f64::from(p.theta_rad));
    let (dx, dy, dt) = best.offset;
    let title = format!(
        "scan {}: best grid pose {:.1} cm, {:.2}° from the given one",
        a.scan,
        (dx * dx + dy * dy).sqrt() * 100.0,
        dt.to_degrees()
    );
    let scans = vec![
        crate::draw::overlay::OverlayScan {
            name: "endpoints at the given pose".into(),
            color: plotters::style::RGBColor(20, 90, 230),
            pose: at(pose),
            points: crate::draw::overlay::endpoints(
                at(pose),
                &bearings,
                scan.ranges_m(),
                max_range,
            ),
        },
        crate::draw::overlay::OverlayScan {
            name: "endpoints at the grid's best pose".into(),
            color: plotters::style::RGBColor(0, 170, 60),
            pose: at(&best.pose),
            points: crate::draw::overlay::endpoints(
                at(&best.pose),
                &bearings,
                scan.ranges_m(),
                max_range,
            ),
        },
    ];
    let view = crate::field_cmd::parse_field_file(&l.blob).map_err(ScoreCmdError::Blob)?;
    crate::draw::overlay::draw_overlay(
        path,
        &view,
        &crate::draw::overlay::Overlay {
            title: &title,
            center,
            half_m: a.overlay_half,
            scans,
        },
    )
    .map_err(|e| ScoreCmdError::Plot(e.0))
}

/// The x–y surface at θ and the θ profile at (x, y): a CSV (`dx_m,dy_m,dtheta_rad,log_likelihood`)
/// and two PNGs.
fn write_grid<M: SensorModel<MAX_BEAMS>>(
    a: &ScoreArgs,
    model: &M,
    layout: &BeamLayout<MAX_BEAMS>,
    scan: &Scan<MAX_BEAMS>,
    pose: &Pose,
    prefix: &Path,
) -> Result<Vec<String>, ScoreCmdError> {
    check_grid(a)?;
    let xy = GridSpec {
        half_xy_m: a.grid_half,
        step_xy_m: a.grid_step,
        half_theta_rad: 0.0,
        step_theta_rad: 1.0,
    };
    let th = GridSpec {
        half_xy_m: 0.0,
        step_xy_m: 1.0,
        half_theta_rad: a.grid_half_deg.to_radians(),
        step_theta_rad: 0.25f64.to_radians(),
    };
    let gxy = score_grid(model, layout, scan, pose, &xy);
    let gth = score_grid(model, layout, scan, pose, &th);
    let mut csv = String::from("dx_m,dy_m,dtheta_rad,log_likelihood\n");
    for (spec, g) in [(&xy, &gxy), (&th, &gth)] {
        for (i, l) in g.log_likelihood.iter().enumerate() {
            let (dx, dy, dt) = spec.offset(i);
            let _ = writeln!(csv, "{dx:.4},{dy:.4},{dt:.5},{l:.4}");
        }
    }
    let name = |suffix: &str| {
        let mut s = prefix.as_os_str().to_owned();
        s.push(suffix);
        PathBuf::from(s)
    };
    let csv_path = name(".csv");
    std::fs::write(&csv_path, csv).map_err(|e| ScoreCmdError::Io(csv_path.clone(), e))?;
    let png_xy = name("-xy.png");
    crate::draw::heat_map::heat_map(
        &png_xy,
        &format!(
            "log-likelihood around ({:.2}, {:.2}) m at θ = {:.3} rad",
            pose.x_m, pose.y_m, pose.theta_rad
        ),
        xy.dims().0,
        a.grid_half,
        &gxy.log_likelihood,
    )
    .map_err(|e| ScoreCmdError::Plot(e.0))?;
    let png_th = name("-theta.png");
    let pts = gth
        .log_likelihood
        .iter()
        .enumerate()
        .map(|(i, l)| (th.offset(i).2.to_degrees(), *l))
        .collect();
    line_chart(
        &png_th,
        &LineChart {
            title: "log-likelihood against heading offset",
            x_label: "θ offset (degrees)",
            y_label: "log-likelihood (nats)",
            x_log: false,
            h_lines: vec![],
            v_lines: vec![(0.0, "given θ".into())],
            series: vec![Series {
                name: "scan".into(),
                points: pts,
            }],
        },
    )
    .map_err(|e| ScoreCmdError::Plot(e.0))?;
    Ok([csv_path, png_xy, png_th]
        .iter()
        .map(|p| p.display().to_string())
        .collect())
}

/// Runs `beamfield calibrate`; progress goes to stderr. Returns the text (or JSON) to print.
///
/// # Errors
/// [`ScoreCmdError`] for unreadable inputs, bad options or a failed plot.
pub fn run_calibrate(a: &CalibrateArgs, json: bool) -> Result<String, ScoreCmdError> {
    if !(a.coverage > 0.0 && a.coverage < 1.0) {
        return Err(usage("--coverage must be in (0, 1)"));
    }
    if a.scans == 0 {
        return Err(usage("--scans must be at least 1"));
    }
    let spec = GridSpec {
        half_xy_m: a.half_xy,
        step_xy_m: a.step_xy,
        half_theta_rad: a.half_deg.to_radians(),
        step_theta_rad: a.step_deg.to_radians(),
    };
    let ok = |h: f64, s: f64| s > 0.0 && h >= s && h / s <= 200.0;
    if !(ok(a.half_xy, a.step_xy) && ok(a.half_deg, a.step_deg)) {
        return Err(usage(
            "grid: steps must be > 0 and at most the half-widths, ≤ 200 steps per side",
        ));
    }
    let l = load(&a.model)?;
    let n = a.scans.min(l.log.scans.len());
    let scores = (n as u64).saturating_mul(spec.len() as u64);
    if scores > MAX_CALIBRATE_SCORES {
        return Err(usage(format!(
            "{n} scans of {} grid poses = {scores} scores, over the limit of \
             {MAX_CALIBRATE_SCORES} (fewer --scans or a coarser grid)",
            spec.len()
        )));
    }
    let lf = LikelihoodField::new(
        crate::field_cmd::parse_field_file(&l.blob).map_err(ScoreCmdError::Blob)?,
        l.params,
    );
    let total = l.log.scans.len();
    if total == 0 {
        return Err(usage("the log has no scans"));
    }
    let n = a.scans.min(total);
    let mut grids = Vec::with_capacity(n);
    let mut sd_sum = (0.0, 0.0, 0.0);
    let mut peak_err = Vec::with_capacity(n);
    let progress = crate::progress::Progress::new("calibrate: scan");
    for j in 0..n {
        let i = j * total / n;
        let (scan, pose) = scan_of(&l.log, i)?;
        let g = score_grid(&lf, &l.layout, &scan, &pose, &spec);
        let sd = posterior_sd(&g, &spec, 1.0);
        sd_sum = (sd_sum.0 + sd.0, sd_sum.1 + sd.1, sd_sum.2 + sd.2);
        if let Some(b) = argmax(&g.log_likelihood) {
            let (dx, dy, _) = spec.offset(b);
            peak_err.push((dx * dx + dy * dy).sqrt());
        }
        grids.push(g);
        progress.update(j + 1, n, &format!(" ({} poses each)", spec.len()));
    }
    let cal = calibrate(&grids, a.coverage);
    let nf = n as f64;
    let sd_k1 = (sd_sum.0 / nf, sd_sum.1 / nf, sd_sum.2 / nf);
    let sd_at = |k: f64| {
        let s = grids
            .iter()
            .map(|g| posterior_sd(g, &spec, k))
            .fold((0.0, 0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
        (s.0 / nf, s.1 / nf, s.2 / nf)
    };
    let sd_kappa = cal.kappa.map(sd_at);
    peak_err.sort_by(f64::total_cmp);
    let median_peak = peak_err.get(peak_err.len() / 2).copied().unwrap_or(0.0);
    if let Some(path) = &a.output {
        plot_curve(path, &cal)?;
    }
    if json {
        return Ok(serde_json::json!({
            "calibration": cal,
            "grid": spec,
            "mean_posterior_sd_at_kappa_1": [sd_k1.0, sd_k1.1, sd_k1.2],
            "mean_posterior_sd_at_kappa": sd_kappa.map(|s| [s.0, s.1, s.2]),
            "median_peak_distance_m": median_peak,
        })
        .to_string());
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{n} scans of {total}; grid ±{:.2} m / {:.3} m in x and y, ±{}° / {}° in θ ({} poses)",
        a.half_xy,
        a.step_xy,
        a.half_deg,
        a.step_deg,
        spec.len()
    );
    let _ = writeln!(
        out,
        "coverage of the {:.0} % credible set at κ = 1: {:.3}",
        a.coverage * 100.0,
        cal.coverage_at_1
    );
    match (cal.kappa, cal.coverage_at_kappa) {
        (Some(k), Some(c)) => {
            let _ = writeln!(
                out,
                "κ = {k:.3}: coverage {c:.3} over {n} scans (the smallest κ that reaches it is \
                 within {} % below)",
                cal.relative_precision * 100.0
            );
        }
        _ => {
            let _ = writeln!(
                out,
                "no κ ≤ {} reaches the requested coverage over {n} scans",
                crate::calibrate::KAPPA_MAX
            );
        }
    }
    let _ = write!(
        out,
        "mean posterior sd at κ = 1: x {:.1} mm, y {:.1} mm, θ {:.2}° ({:.1}, {:.1}, {:.1} grid cells)",
        sd_k1.0 * 1e3,
        sd_k1.1 * 1e3,
        sd_k1.2.to_degrees(),
        sd_k1.0 / a.step_xy,
        sd_k1.1 / a.step_xy,
        sd_k1.2.to_degrees() / a.step_deg
    );
    if let (Some(k), Some(s)) = (cal.kappa, sd_kappa) {
        let _ = write!(
            out,
            "\nmean posterior sd at κ = {k:.3}: x {:.1} mm, y {:.1} mm, θ {:.2}°",
            s.0 * 1e3,
            s.1 * 1e3,
            s.2.to_degrees()
        );
    }
    let _ = write!(
        out,
        "\nmedian distance of the grid's best pose from the logged one: {:.1} cm",
        median_peak * 100.0
    );
    if let Some(p) = &a.output {
        let _ = write!(out, "\nwrote {}", p.display());
    }
    Ok(out)
}

fn plot_curve(path: &Path, cal: &Calibration) -> Result<(), ScoreCmdError> {
    let mut v_lines = Vec::new();
    if let Some(k) = cal.kappa {
        v_lines.push((k, format!("κ = {k:.3}")));
    }
    line_chart(
        path,
        &LineChart {
            title: "coverage of the credible set against tempering κ",
            x_label: "κ",
            y_label: "fraction of logged poses inside",
            x_log: true,
            h_lines: vec![(cal.level, format!("requested {:.2}", cal.level))],
            v_lines,
            series: vec![Series {
                name: format!("{} scans", cal.scans),
                points: cal.curve.clone(),
            }],
        },
    )
    .map_err(|e| ScoreCmdError::Plot(e.0))
}
