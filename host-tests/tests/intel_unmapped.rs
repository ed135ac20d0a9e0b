//! Readings the map cannot explain, on the Intel lab log (910 scans): obstacles that are not in
//! the map (people as discs of 0.4 m, shelves as 1.5 m × 0.4 m boxes) are placed at fixed
//! world positions in free space near the logged trajectory and ray cast into every scan from
//! the logged pose (each beam that meets one is shortened to it, max-range readings included),
//! so they are consistent from scan to scan. The filter tracks the log with wheel odometry
//! (`host_tests::wheel_odometry`, [`WheelErrors::MILD`]), α 0.005, 500 particles, κ 8.25, every
//! beam, no recovery, with [`MclConfig::with_unexplained`] off and on.
//!
//! - `figures` (ignored): the table of docs/localization.md, "Readings the map cannot explain"
//!   (`cargo test -p host-tests --release --test intel_unmapped -- --ignored --nocapture`).
//! - `a_false_wall_drags_the_estimate_unless_removed`: a shelf wall along a corridor on a stretch
//!   of the log; the property asserted is that with the option the estimate stays close while
//!   without it the same run is dragged farther.

use beamfield::field::{FieldView, LikelihoodField};
use beamfield::mcl::{
    Mcl, MclConfig, MclError, OdometryNoise, OdometryStep, Particles, SplitMix64, Unexplained,
};
use beamfield::{wrap_angle, Pose, Scan, Tempered};
use beamfield_tools::cmd::scored_log::MAX_BEAMS;
use beamfield_tools::track::TrackInput;
use host_tests::intel_input;
use host_tests::splitmix::Draws;
use host_tests::wheel_odometry::{wheel_odometry, WheelErrors};

/// A run is lost when the estimate is this far off (metres) …
const LOST_M: f64 = 1.0;
/// … or this far in heading (degrees) …
const LOST_DEG: f64 = 30.0;
/// … for this many scans in a row (the definition of `intel_quality`).
const LOST_SCANS: usize = 10;
const PARTICLES: usize = 500;

/// An obstacle that is not in the map (world frame, metres).
#[derive(Clone, Copy, Debug)]
enum Obstacle {
    /// A disc: centre and radius.
    Disc { x: f64, y: f64, r: f64 },
    /// A rectangle: centre, half-lengths along its own axes, and the angle of its first axis.
    Box {
        x: f64,
        y: f64,
        hx: f64,
        hy: f64,
        angle: f64,
    },
}

impl Obstacle {
    /// Distance along the ray `(ox, oy) + t·(ux, uy)` (unit direction) to the obstacle's
    /// boundary, `t > 0`, if it meets it.
    fn hit(&self, ox: f64, oy: f64, ux: f64, uy: f64) -> Option<f64> {
        match *self {
            Obstacle::Disc { x, y, r } => {
                let (dx, dy) = (ox - x, oy - y);
                let b = dx * ux + dy * uy;
                let c = dx * dx + dy * dy - r * r;
                let disc = b * b - c;
                if disc < 0.0 {
                    return None;
                }
                let t = -b - disc.sqrt();
                (t > 0.0).then_some(t)
            }
            Obstacle::Box {
                x,
                y,
                hx,
                hy,
                angle,
            } => {
                // Slab test in the box's frame.
                let (s, c) = angle.sin_cos();
                let (dx, dy) = (ox - x, oy - y);
                let (px, py) = (c * dx + s * dy, -s * dx + c * dy);
                let (vx, vy) = (c * ux + s * uy, -s * ux + c * uy);
                let mut lo = f64::NEG_INFINITY;
                let mut hi = f64::INFINITY;
                for (p, v, h) in [(px, vx, hx), (py, vy, hy)] {
                    if v.abs() < 1e-12 {
                        if p.abs() > h {
                            return None;
                        }
                    } else {
                        let (a, b) = ((-h - p) / v, (h - p) / v);
                        lo = lo.max(a.min(b));
                        hi = hi.min(a.max(b));
                    }
                }
                (hi >= lo && lo > 0.0).then_some(lo)
            }
        }
    }

    fn centre(&self) -> (f64, f64) {
        match *self {
            Obstacle::Disc { x, y, .. } | Obstacle::Box { x, y, .. } => (x, y),
        }
    }

    /// Distance (metres) from `(px, py)` to the obstacle (0 inside).
    fn distance(&self, px: f64, py: f64) -> f64 {
        match *self {
            Obstacle::Disc { x, y, r } => ((px - x).hypot(py - y) - r).max(0.0),
            Obstacle::Box {
                x,
                y,
                hx,
                hy,
                angle,
            } => {
                let (s, c) = angle.sin_cos();
                let (dx, dy) = (px - x, py - y);
                let (u, v) = (c * dx + s * dy, -s * dx + c * dy);
                (u.abs() - hx).max(0.0).hypot((v.abs() - hy).max(0.0))
            }
        }
    }

    /// A radius that bounds the obstacle.
    fn bound(&self) -> f64 {
        match *self {
            Obstacle::Disc { r, .. } => r,
            Obstacle::Box { hx, hy, .. } => hx.hypot(hy),
        }
    }
}

/// The scans with `obstacles` ray cast into them from the logged poses; returns them and the
/// share of all readings that were shortened.
fn with_obstacles(input: &TrackInput, obstacles: &[Obstacle]) -> (Vec<Vec<f32>>, f64) {
    let max_r = f64::from(input.params.max_range_m());
    let (mut changed, mut total) = (0usize, 0usize);
    let scans = input
        .scans
        .iter()
        .zip(&input.logged)
        .map(|(ranges, pose)| {
            let (ox, oy) = (f64::from(pose.x_m), f64::from(pose.y_m));
            let near: Vec<&Obstacle> = obstacles
                .iter()
                .filter(|o| {
                    let (x, y) = o.centre();
                    (x - ox).hypot(y - oy) < max_r + o.bound()
                })
                .collect();
            ranges
                .iter()
                .zip(input.layout.beams())
                .map(|(&r, beam)| {
                    total += 1;
                    let a = f64::from(pose.theta_rad) + f64::from(beam.bearing_rad);
                    let (uy, ux) = a.sin_cos();
                    let seen = if r.is_finite() && r >= 0.0 {
                        f64::from(r).min(max_r)
                    } else {
                        max_r
                    };
                    let t = near
                        .iter()
                        .filter_map(|o| o.hit(ox, oy, ux, uy))
                        .fold(f64::INFINITY, f64::min);
                    if t < seen {
                        changed += 1;
                        t as f32
                    } else {
                        r
                    }
                })
                .collect()
        })
        .collect();
    (scans, changed as f64 / total.max(1) as f64)
}

/// Whether an obstacle may stand at its place: clear of the map's obstacles by `clearance` and
/// of every logged position by `path_clearance` (metres), so the robot never drives through it.
fn placeable(view: &FieldView<'_>, logged: &[Pose], o: &Obstacle, clearance: f64) -> bool {
    let (x, y) = o.centre();
    let map_d = f64::from(view.distance_m(x as f32, y as f32));
    map_d >= o.bound() + clearance && clear_of_path(logged, o)
}

/// True when no logged position comes within 0.35 m of the obstacle.
fn clear_of_path(logged: &[Pose], o: &Obstacle) -> bool {
    logged
        .iter()
        .all(|p| o.distance(f64::from(p.x_m), f64::from(p.y_m)) >= 0.35)
}

/// False walls (shelves in a row, 2 m × 0.2 m) along the corridors: at every 30th scan, 0.6 m
/// to the left or right (alternately) of the logged heading and 1 m ahead, kept when clear of
/// the logged path.
fn false_walls(input: &TrackInput) -> Vec<Obstacle> {
    (10..input.logged.len())
        .step_by(30)
        .enumerate()
        .map(|(i, k)| false_wall(input, k, if i % 2 == 0 { 0.6 } else { -0.6 }, 1.0, 1.0))
        .filter(|o| clear_of_path(&input.logged, o))
        .collect()
}

/// People (discs of 0.2 m radius) and, with `shelves`, shelves (1.5 m × 0.4 m, one candidate in
/// two): one candidate per `every` scans, `near`–2.5 m from the logged position at a random
/// bearing, kept if [`placeable`] and apart from those kept before (seeded, so the world is the
/// same in every run).
fn scattered(
    input: &TrackInput,
    every: usize,
    near: f64,
    shelves: bool,
    seed: u64,
) -> Vec<Obstacle> {
    let (view, _) = input.views().unwrap();
    let mut rng = SplitMix64::new(seed);
    let mut out: Vec<Obstacle> = Vec::new();
    for (k, p) in input.logged.iter().enumerate().step_by(every) {
        let (d, b) = (
            rng.range(near, 2.5),
            rng.range(-std::f64::consts::PI, std::f64::consts::PI),
        );
        let a = f64::from(p.theta_rad) + b;
        let (x, y) = (
            f64::from(p.x_m) + d * a.cos(),
            f64::from(p.y_m) + d * a.sin(),
        );
        let o = if shelves && k % (2 * every) == 0 {
            Obstacle::Box {
                x,
                y,
                hx: 0.75,
                hy: 0.2,
                angle: rng.range(0.0, std::f64::consts::PI),
            }
        } else {
            Obstacle::Disc { x, y, r: 0.2 }
        };
        let apart = out.iter().all(|q| {
            let (qx, qy) = q.centre();
            (qx - x).hypot(qy - y) > q.bound() + o.bound()
        });
        if apart && placeable(&view, &input.logged, &o, 0.1) {
            out.push(o);
        }
    }
    out
}

/// A crowd at the in-place turns: where the logged pose turns by more than 0.2 rad while moving
/// less than 0.1 m, up to eight people 0.7–1.2 m around the robot (turn places at least 2 m
/// apart).
fn crowd_at_turns(input: &TrackInput, seed: u64) -> Vec<Obstacle> {
    let (view, _) = input.views().unwrap();
    let mut rng = SplitMix64::new(seed);
    let mut out: Vec<Obstacle> = Vec::new();
    let mut places: Vec<(f64, f64)> = Vec::new();
    for w in input.logged.windows(2) {
        let (a, b) = (w[0], w[1]);
        let moved = f64::from(b.x_m - a.x_m).hypot(f64::from(b.y_m - a.y_m));
        let turned = f64::from(wrap_angle(b.theta_rad - a.theta_rad)).abs();
        let (x, y) = (f64::from(b.x_m), f64::from(b.y_m));
        if moved < 0.1
            && turned > 0.2
            && places.iter().all(|&(px, py)| (px - x).hypot(py - y) > 2.0)
        {
            places.push((x, y));
        }
    }
    for &(x, y) in &places {
        for _ in 0..8 {
            let (d, a) = (rng.range(0.7, 1.2), rng.range(0.0, std::f64::consts::TAU));
            let o = Obstacle::Disc {
                x: x + d * a.cos(),
                y: y + d * a.sin(),
                r: 0.2,
            };
            if placeable(&view, &input.logged, &o, 0.1) {
                out.push(o);
            }
        }
    }
    out
}

/// One run's errors.
struct Trace {
    err_m: Vec<f64>,
    err_deg: Vec<f64>,
    /// Beams removed per update.
    removed: Vec<u16>,
    scored: Vec<usize>,
}

impl Trace {
    fn lost(&self) -> bool {
        let mut streak = 0;
        for (m, d) in self.err_m.iter().zip(&self.err_deg) {
            streak = if *m > LOST_M || *d > LOST_DEG {
                streak + 1
            } else {
                0
            };
            if streak >= LOST_SCANS {
                return true;
            }
        }
        false
    }

    fn rmse_m(&self) -> f64 {
        (self.err_m.iter().map(|e| e * e).sum::<f64>() / self.err_m.len().max(1) as f64).sqrt()
    }

    fn max_m(&self) -> f64 {
        self.err_m.iter().copied().fold(0.0, f64::max)
    }

    fn removed_share(&self) -> f64 {
        let r: usize = self.removed.iter().map(|&r| usize::from(r)).sum();
        r as f64 / self.scored.iter().sum::<usize>().max(1) as f64
    }
}

/// Tracks scans `range` of `scans` from the logged pose at its start (σ 5 cm, 2°), wheel
/// odometry [`WheelErrors::MILD`] (seeded), α 0.005.
fn run(
    input: &TrackInput,
    scans: &[Vec<f32>],
    unexplained: Option<Unexplained>,
    seed: u64,
    range: std::ops::Range<usize>,
) -> Trace {
    let (view, free) = input.views().unwrap();
    let free = free.unwrap();
    let config = MclConfig::new(OdometryNoise::uniform(0.005).unwrap(), 0.5, 0.0, 0.0)
        .unwrap()
        .with_unexplained(unexplained)
        .unwrap();
    let model = Tempered::new(LikelihoodField::new(view, input.params), 8.25, 1).unwrap();
    let mut store: Box<Particles<PARTICLES>> = Box::default();
    let mut mcl = Mcl::new(&mut store, config).unwrap();
    let mut rng = SplitMix64::new(seed);
    mcl.init_gaussian(PARTICLES, &input.logged[range.start], 0.05, 0.035, &mut rng)
        .unwrap();
    let odom = wheel_odometry(&input.logged, &WheelErrors::MILD, seed ^ 0x77_6865_656c);
    let mut t = Trace {
        err_m: Vec::new(),
        err_deg: Vec::new(),
        removed: Vec::new(),
        scored: Vec::new(),
    };
    for k in range.clone() {
        let truth = input.logged[k];
        if k > range.start {
            let step = OdometryStep::between(&odom[k - 1], &odom[k]).unwrap();
            mcl.predict(&step, &mut rng);
        }
        let scan = Scan::<MAX_BEAMS>::from_ranges(&scans[k]).unwrap();
        let prepared = model.prepare(&input.layout, &scan);
        let (est, removed) = match mcl.update_prepared(&prepared, Some(&free), &mut rng) {
            Ok(u) => (u.estimate.pose, u.unexplained),
            Err(MclError::EmptyScan | MclError::AllImpossible) => (mcl.estimate().pose, 0),
            Err(e) => panic!("scan {k}: {e}"),
        };
        t.err_m
            .push(f64::from(est.x_m - truth.x_m).hypot(f64::from(est.y_m - truth.y_m)));
        t.err_deg.push(
            f64::from(wrap_angle(est.theta_rad - truth.theta_rad))
                .abs()
                .to_degrees(),
        );
        t.removed.push(removed);
        t.scored.push(prepared.prepared().len());
    }
    t
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn min_med_max(v: &[f64], scale: f64, digits: usize) -> String {
    let mut s: Vec<f64> = v.iter().map(|x| x * scale).collect();
    s.sort_by(f64::total_cmp);
    format!(
        "{:.d$} / {:.d$} / {:.d$}",
        s[0],
        median(s.clone()),
        s[s.len() - 1],
        d = digits
    )
}

/// The table of docs/localization.md: 10 seeds per row, the whole log.
#[test]
#[ignore = "long: 10 seeds × 6 scenes × 3 settings of the whole log; run with --release --ignored --nocapture"]
fn figures() {
    let input = intel_input();
    let n = input.scans.len();
    let scenes = [
        ("clean", Vec::new()),
        ("people", scattered(&input, 2, 0.8, false, 0x7065_6f70)),
        (
            "people and shelves",
            scattered(&input, 1, 0.5, true, 0x7368_656c),
        ),
        (
            "dense people",
            scattered(&input, 1, 0.6, false, 0x6465_6e73),
        ),
        (
            "crowd at in-place turns",
            crowd_at_turns(&input, 0x7475_726e),
        ),
        ("false walls", false_walls(&input)),
    ];
    let settings = [
        ("off", None),
        (
            "on, 0.25 m",
            Some(Unexplained {
                distance_m: 0.25,
                max_share: 0.5,
            }),
        ),
        (
            "on, 0.5 m",
            Some(Unexplained {
                distance_m: 0.5,
                max_share: 0.5,
            }),
        ),
    ];
    println!("| scene | obstacles | readings shortened | option | trans RMSE (cm) | largest error (m) | ever > 0.5 m | lost | beams removed |");
    println!("|---|---:|---:|---|---|---|---:|---:|---:|");
    for (name, obstacles) in &scenes {
        let (scans, share) = with_obstacles(&input, obstacles);
        for (label, u) in settings {
            let (mut rmse, mut largest, mut over, mut lost, mut removed) =
                (Vec::new(), Vec::new(), 0, 0, Vec::new());
            for seed in 1..=10u64 {
                let t = run(&input, &scans, u, seed, 0..n);
                rmse.push(t.rmse_m());
                largest.push(t.max_m());
                over += usize::from(t.max_m() > 0.5);
                lost += usize::from(t.lost());
                removed.push(t.removed_share());
            }
            println!(
                "| {name} | {} | {:.1} % | {label} | {} | {} | {over}/10 | {lost}/10 | {:.1} % |",
                obstacles.len(),
                100.0 * share,
                min_med_max(&rmse, 100.0, 2),
                min_med_max(&largest, 1.0, 3),
                100.0 * median(removed)
            );
        }
    }
}

/// A wall of shelves (a box `2·half_len` × 0.2 m) parallel to the logged heading at scan `at`,
/// `offset` metres to its left (negative: right), centred `ahead` metres ahead of it.
fn false_wall(input: &TrackInput, at: usize, offset: f64, ahead: f64, half_len: f64) -> Obstacle {
    let p = input.logged[at];
    let (s, c) = f64::from(p.theta_rad).sin_cos();
    Obstacle::Box {
        x: f64::from(p.x_m) + ahead * c - offset * s,
        y: f64::from(p.y_m) + ahead * s + offset * c,
        hx: half_len,
        hy: 0.1,
        angle: f64::from(p.theta_rad),
    }
}

/// One false wall on a 40-scan stretch, seeds 1–5, off and on: the largest errors (metres).
fn wall_case(input: &TrackInput, k0: usize, offset: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let wall = false_wall(input, k0 + 10, offset, 1.0, 2.0);
    let gap = input.logged[k0..k0 + 40]
        .iter()
        .map(|p| wall.distance(f64::from(p.x_m), f64::from(p.y_m)))
        .fold(f64::INFINITY, f64::min);
    assert!(
        gap >= 0.35,
        "stretch {k0}, offset {offset}: the path passes {gap:.2} m from the wall"
    );
    let (scans, _) = with_obstacles(input, &[wall]);
    let (mut off, mut on, mut removed) = (Vec::new(), Vec::new(), Vec::new());
    for seed in 1..=5 {
        off.push(run(input, &scans, None, seed, k0..k0 + 40).max_m());
        let t = run(input, &scans, Some(Unexplained::DEFAULT), seed, k0..k0 + 40);
        on.push(t.max_m());
        removed.push(t.removed_share());
    }
    (off, on, removed)
}

/// A shelf wall (4 m × 0.2 m) 0.6 m to the right of the logged heading at scan 640, 1 m ahead
/// of it, and the robot tracking scans 630–669 (the path passes 0.37 m from the wall). Without
/// the option one run of five (seed 3) is pulled away and ends 3.8 m off; with
/// [`Unexplained::DEFAULT`] the beams that hit the wall are left out and every run stays
/// within 0.26 m. Measured (largest error, seeds 1–5): off 0.20 / 0.20 / 3.84 / 0.19 / 0.23 m,
/// on 0.21 / 0.20 / 0.23 / 0.20 / 0.26 m. Asserted: the property (every run within 0.5 m with
/// the option, and the worst run better than the worst without), not these numbers. This is
/// one chosen case: over 80 walls on other stretches (`false_wall_cases`) the option changes
/// the count of runs beyond 0.5 m in 3 (docs/localization.md).
#[test]
fn a_false_wall_drags_the_estimate_unless_removed() {
    let input = intel_input();
    let (off, on, removed) = wall_case(&input, 630, -0.6);
    println!("largest error off {off:.3?} on {on:.3?}, beams removed {removed:.3?}");
    let worst = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    assert!(on.iter().all(|&e| e <= 0.5), "with the option: {on:?}");
    assert!(worst(&on) < worst(&off), "{on:?} vs {off:?}");
    assert!(removed.iter().all(|&r| r > 0.0), "{removed:?}");
}

/// The false-wall cases of docs/localization.md: one wall on a 40-scan stretch at several
/// offsets (where the option helps and where it hurts).
#[test]
#[ignore = "measurement; run with --release --ignored --nocapture"]
fn false_wall_cases() {
    let input = intel_input();
    println!("| stretch | wall offset (m) | largest error off, seeds 1–5 (m) | on (m) |");
    println!("|---|---:|---|---|");
    let (mut cases, mut helped, mut hurt) = (0, 0, 0);
    for k0 in (0..input.logged.len() - 40).step_by(20) {
        for offset in [-0.8, -0.6, -0.45, 0.45, 0.6, 0.8] {
            let wall = false_wall(&input, k0 + 10, offset, 1.0, 2.0);
            if !clear_of_path(&input.logged[k0..k0 + 40], &wall) {
                continue;
            }
            let (off, on, _) = wall_case(&input, k0, offset);
            let f = |v: &[f64]| {
                v.iter()
                    .map(|e| format!("{e:.2}"))
                    .collect::<Vec<_>>()
                    .join(" / ")
            };
            let over = |v: &[f64]| v.iter().filter(|&&e| e > 0.5).count();
            cases += 1;
            helped += usize::from(over(&on) < over(&off));
            hurt += usize::from(over(&on) > over(&off));
            if over(&on) != over(&off) {
                println!("| {k0}–{} | {offset} | {} | {} |", k0 + 39, f(&off), f(&on));
            }
        }
    }
    println!("{cases} walls clear of their stretch; fewer runs beyond 0.5 m with the option in {helped}, more in {hurt} (the others: rows not printed, the same count)");
}
