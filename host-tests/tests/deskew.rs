//! Motion de-skew ([`beamfield::lidar::deskew`]) on the Intel lab map the firmware links
//! (`firmware/assets/intel.bin`, 5 cm cells): synthetic LD06-like revolutions (360 points, 1°
//! apart, clockwise, 10 Hz) whose every point is ray-cast from the pose at its own time within
//! the 100 ms turn, along a trajectory at constant speed and turn rate. The odometry is the
//! trajectory itself sampled at 50 Hz and interpolated by the robot's
//! [`OdometryWindow`](beamfield::robot::OdometryWindow); the revolution's timing anchors are
//! what the assembler reports for the LD06 encoder's frames (0° at 0 ms, the last frame's 348°
//! at 97 ms) and its reference time is the robot's (48.5 ms, the middle of the two stamps).
//!
//! Endpoint misplacement of a reading is the distance between where the scan places its
//! endpoint (range along the bin's bearing, from the true pose at the reference time) and the
//! true endpoint of the point it came from.
//!
//! `cargo test -p host-tests --release --test deskew -- --ignored --nocapture` prints the table
//! of docs/robot.md ("De-skew"): endpoint misplacement and MCL tracking error without and with
//! de-skew, and for revolutions ray-cast from one pose (no skew at all).

use beamfield::field::{FieldView, LikelihoodField, LikelihoodParams};
use beamfield::lidar::assembler::full_turn_layout;
use beamfield::lidar::{Deskewer, Sweep};
use beamfield::mcl::{Mcl, MclConfig, OdometryNoise, OdometryStep, Particles, SplitMix64};
use beamfield::robot::{OdometryWindow, Sample};
use beamfield::tempered::Tempered;
use beamfield::{wrap_angle, BeamLayout, Pose, RayCaster, Scan, SensorMount};

const BEAMS: usize = 360;
const MAX_RANGE_M: f32 = 12.0;
const PARTICLES: usize = 500;
/// Revolution period, last stamp and reference time after the revolution's start, s.
const REV_S: f64 = 0.1;
const LAST_STAMP_S: f64 = 0.097;
const REF_S: f64 = 0.0485;
/// The last frame's first point, degrees clockwise.
const LAST_FRAME_DEG: f32 = 348.0;

fn blob() -> Vec<u8> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    std::fs::read(root.join("firmware/assets/intel.bin")).unwrap()
}

fn layout() -> BeamLayout<BEAMS> {
    full_turn_layout::<BEAMS>(BEAMS, MAX_RANGE_M, SensorMount::CENTERED).unwrap()
}

/// Constant forward speed (m/s) and turn rate (rad/s) from a start pose.
#[derive(Clone, Copy, Debug)]
struct Motion {
    v: f64,
    w: f64,
}

fn pose_at(p0: Pose, m: Motion, t: f64) -> Pose {
    let th0 = f64::from(p0.theta_rad);
    let th = th0 + m.w * t;
    let (dx, dy) = if m.w.abs() < 1e-12 {
        (m.v * t * th0.cos(), m.v * t * th0.sin())
    } else {
        let r = m.v / m.w;
        (r * (th.sin() - th0.sin()), -r * (th.cos() - th0.cos()))
    };
    Pose::new(
        (f64::from(p0.x_m) + dx) as f32,
        (f64::from(p0.y_m) + dy) as f32,
        wrap_angle(th as f32),
    )
}

/// Whether a point is inside the building: nearly every ray meets a wall within range.
fn inside(caster: &RayCaster<'_>, x: f32, y: f32) -> bool {
    (0..36)
        .filter(|k| caster.cast(x, y, *k as f32 * 10f32.to_radians(), MAX_RANGE_M) < MAX_RANGE_M)
        .count()
        >= 35
}

/// Start poses (spread over the map) from which `motion` stays at least 0.35 m from every wall
/// and inside the building for `duration` s.
fn starts(
    view: &FieldView<'_>,
    caster: &RayCaster<'_>,
    m: Motion,
    duration: f64,
    count: usize,
) -> Vec<Pose> {
    let h = view.header();
    let mut found = Vec::new();
    let step = 0.25f32;
    let nx = (h.width as f32 * h.cell_size_m / step) as usize;
    let ny = (h.height as f32 * h.cell_size_m / step) as usize;
    for iy in 1..ny {
        for ix in 1..nx {
            let (x, y) = (
                h.origin_x_m + ix as f32 * step,
                h.origin_y_m + iy as f32 * step,
            );
            if view.distance_m(x, y) < 0.6 || !inside(caster, x, y) {
                continue;
            }
            for k in 0..16 {
                let p0 = Pose::new(x, y, wrap_angle(k as f32 * 22.5f32.to_radians()));
                let steps = (duration / 0.05) as usize;
                let ok = (0..=steps).all(|s| {
                    let p = pose_at(p0, m, s as f64 * 0.05);
                    view.distance_m(p.x_m, p.y_m) >= 0.35
                }) && {
                    let e = pose_at(p0, m, duration);
                    inside(caster, e.x_m, e.y_m)
                };
                if ok {
                    found.push(p0);
                    break;
                }
            }
        }
    }
    assert!(
        found.len() >= count,
        "{} start poses for {m:?}",
        found.len()
    );
    (0..count)
        .map(|i| found[i * found.len() / count + found.len() / (2 * count)])
        .collect()
}

/// One synthetic revolution.
struct Revolution {
    /// Swept (every point from its own time), and cast from the reference pose alone.
    swept: Scan<BEAMS>,
    still: Scan<BEAMS>,
    /// True world endpoint of each bin's point of `swept` (NaN-free where the range is finite).
    endpoints: Vec<(f64, f64)>,
    /// True pose at the reference time.
    truth: Pose,
    /// The odometry (window-interpolated) at the anchors and the reference time.
    sweep: Sweep,
}

fn odometry(traj: &impl Fn(f64) -> Pose, t0: f64) -> OdometryWindow {
    let mut w = OdometryWindow::new();
    // 50 Hz samples on the device clock, covering the revolution.
    let first = ((t0 - 0.04) / 0.02).floor().max(0.0) as u64;
    for k in first..first + 10 {
        let t = k as f64 * 0.02;
        assert!(w.push(Sample {
            t_us: (t * 1e6).round() as u64,
            pose: traj(t),
        }));
    }
    w
}

fn at(w: &OdometryWindow, t: f64) -> Pose {
    let i = w.at((t * 1e6).round() as u64, 100_000).unwrap();
    assert!(!i.stale);
    i.pose
}

fn revolution(caster: &RayCaster<'_>, traj: &impl Fn(f64) -> Pose, t0: f64) -> Revolution {
    let truth = traj(t0 + REF_S);
    let mut swept = vec![f32::NAN; BEAMS];
    let mut still = vec![f32::NAN; BEAMS];
    let mut endpoints = vec![(f64::NAN, f64::NAN); BEAMS];
    let quantize = |r: f32| {
        if r < MAX_RANGE_M {
            (r * 1000.0).round() / 1000.0
        } else {
            f32::NAN
        }
    };
    for i in 0..BEAMS {
        // Point i at i° clockwise, measured i/3600 s into the turn; bin (360 − i) mod 360.
        let p = traj(t0 + i as f64 / 3600.0);
        let a = wrap_angle(p.theta_rad - (i as f32).to_radians());
        let r = quantize(caster.cast(p.x_m, p.y_m, a, MAX_RANGE_M));
        let j = (BEAMS - i) % BEAMS;
        swept[j] = r;
        let (s, c) = (f64::from(a)).sin_cos();
        endpoints[j] = (
            f64::from(p.x_m) + f64::from(r) * c,
            f64::from(p.y_m) + f64::from(r) * s,
        );
        let a_still = wrap_angle(truth.theta_rad - (i as f32).to_radians());
        still[j] = quantize(caster.cast(truth.x_m, truth.y_m, a_still, MAX_RANGE_M));
    }
    let w = odometry(traj, t0);
    Revolution {
        swept: Scan::from_ranges(&swept).unwrap(),
        still: Scan::from_ranges(&still).unwrap(),
        endpoints,
        truth,
        sweep: Sweep {
            start_deg: 0.0,
            end_deg: LAST_FRAME_DEG,
            start: at(&w, t0),
            end: at(&w, t0 + LAST_STAMP_S),
            reference: at(&w, t0 + REF_S),
        },
    }
}

fn place(p: &Pose, r: f32, bearing: f32) -> (f64, f64) {
    let a = f64::from(p.theta_rad) + f64::from(bearing);
    (
        f64::from(p.x_m) + f64::from(r) * a.cos(),
        f64::from(p.y_m) + f64::from(r) * a.sin(),
    )
}

fn dist(a: (f64, f64), b: (f64, f64)) -> f64 {
    ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt()
}

/// Per reading of one revolution: range, misplacement without de-skew, of the continuous
/// correction, and of the binned correction (`None` where the reading lost its bin).
struct Misplacement {
    range: Vec<f64>,
    raw: Vec<f64>,
    continuous: Vec<f64>,
    binned: Vec<Option<f64>>,
}

fn misplacement(rev: &Revolution, deskewed: &Scan<BEAMS>) -> Misplacement {
    let layout = layout();
    let d = Deskewer::new(&layout).unwrap();
    let mut m = Misplacement {
        range: Vec::new(),
        raw: Vec::new(),
        continuous: Vec::new(),
        binned: Vec::new(),
    };
    for (j, &r) in rev.swept.ranges_m().iter().enumerate() {
        if !r.is_finite() {
            continue;
        }
        let truth = rev.endpoints[j];
        let beam = layout.beams()[j];
        m.range.push(f64::from(r));
        m.raw
            .push(dist(place(&rev.truth, r, beam.bearing_rad), truth));
        let (r2, b2) = d.correct_beam(&layout, &rev.sweep, j, r).unwrap().unwrap();
        m.continuous.push(dist(place(&rev.truth, r2, b2), truth));
        // The bin it goes to (nearest, 1° beams) and whether it holds this very reading.
        let k = ((b2.to_degrees().rem_euclid(360.0)).round() as usize) % BEAMS;
        let out = deskewed.ranges_m()[k];
        m.binned.push(
            (out.to_bits() == r2.to_bits())
                .then(|| dist(place(&rev.truth, out, layout.beams()[k].bearing_rad), truth)),
        );
    }
    m
}

/// The binning bound of a reading: half a beam step sideways at its range, plus the timing
/// model's error (the anchor at 97 ms for 96.67: ≤ 0.34 ms of turn, 5.1e-4 rad at 1.5 rad/s),
/// plus 2 mm of rounding (f32 poses, mm ranges, the window's chords).
fn bound(range: f64) -> f64 {
    range * ((0.5f64).to_radians().sin() + 1e-3) + 0.002
}

fn deskew(rev: &Revolution) -> Scan<BEAMS> {
    let layout = layout();
    let mut out = Scan::default();
    Deskewer::new(&layout)
        .unwrap()
        .apply(&layout, &rev.swept, &rev.sweep, &mut out)
        .unwrap();
    out
}

#[test]
fn deskewed_endpoints_lie_within_the_bin_bound_and_raw_ones_do_not() {
    let blob = blob();
    let view = FieldView::parse(&blob).unwrap();
    let caster = RayCaster::new(view).unwrap();
    let m = Motion { v: 0.5, w: 1.5 };
    let p0 = starts(&view, &caster, m, 1.0, 1)[0];
    let traj = move |t: f64| pose_at(p0, m, t);
    let (mut raw_over, mut binned_over, mut cont_over, mut kept, mut n) = (0, 0, 0, 0, 0);
    let (mut raw_sum, mut binned_sum) = (0.0, 0.0);
    for k in 0..8 {
        let rev = revolution(&caster, &traj, k as f64 * REV_S);
        let out = deskew(&rev);
        let mis = misplacement(&rev, &out);
        for i in 0..mis.range.len() {
            let b = bound(mis.range[i]);
            n += 1;
            raw_over += usize::from(mis.raw[i] > b);
            raw_sum += mis.raw[i];
            cont_over += usize::from(mis.continuous[i] > 1e-3 * mis.range[i] + 0.002);
            if let Some(e) = mis.binned[i] {
                kept += 1;
                binned_sum += e;
                binned_over += usize::from(e > b);
            }
        }
    }
    let (raw_mean, binned_mean) = (raw_sum / n as f64, binned_sum / kept as f64);
    println!(
        "{n} readings, {kept} kept their bin; over the bound: raw {raw_over}, binned \
         {binned_over}, continuous {cont_over}; mean raw {raw_mean:.4} m, binned {binned_mean:.4} m"
    );
    assert!(n > 2000, "{n}");
    assert_eq!(cont_over, 0);
    assert_eq!(binned_over, 0);
    // Collisions lose a few readings to nearer ones in the same bin, not many.
    assert!(kept * 10 >= n * 8, "{kept} of {n}");
    // At 1.5 rad/s a reading more than 6 ms from the reference time is out by more than half
    // a beam step: most of them.
    assert!(raw_over * 2 > n, "{raw_over} of {n}");
    assert!(binned_mean * 3.0 < raw_mean);
}

#[test]
fn no_motion_leaves_the_revolution_bit_for_bit() {
    let blob = blob();
    let view = FieldView::parse(&blob).unwrap();
    let caster = RayCaster::new(view).unwrap();
    let m = Motion { v: 0.0, w: 0.0 };
    let p0 = starts(&view, &caster, m, 0.2, 1)[0];
    let rev = revolution(&caster, &move |t| pose_at(p0, m, t), 0.3);
    let out = deskew(&rev);
    assert!(
        rev.swept
            .ranges_m()
            .iter()
            .filter(|r| r.is_finite())
            .count()
            > 300
    );
    for (a, b) in out.ranges_m().iter().zip(rev.swept.ranges_m()) {
        assert_eq!(a.to_bits(), b.to_bits());
    }
}

/// Tracking with the robot's filter settings (500 particles, the likelihood field z_hit 0.95,
/// z_rand 0.05, σ 5 cm, κ 8.25, α 0.005, resampling below half): translation and heading
/// RMSE after the first `settle` revolutions, and the largest translation error.
#[derive(Clone, Copy, Debug, Default)]
struct Track {
    sq_xy: f64,
    sq_th: f64,
    n: usize,
    max_xy: f64,
}

fn track(
    field: &LikelihoodField<'_>,
    revs: &[Revolution],
    scans: &[Scan<BEAMS>],
    seed: u64,
    settle: usize,
) -> Track {
    let layout = layout();
    let model = Tempered::new(field.clone(), 8.25, 1).unwrap();
    let mut store = Particles::<PARTICLES>::new();
    let config = MclConfig::new(OdometryNoise::uniform(0.005).unwrap(), 0.5, 0.0, 0.0).unwrap();
    let mut mcl = Mcl::new(&mut store, config).unwrap();
    let mut rng = SplitMix64::new(seed);
    mcl.init_gaussian(PARTICLES, &revs[0].truth, 0.05, 0.02, &mut rng)
        .unwrap();
    let mut t = Track::default();
    let mut prev: Option<Pose> = None;
    for (k, (rev, scan)) in revs.iter().zip(scans).enumerate() {
        let odom = rev.sweep.reference;
        let step = match prev {
            Some(p) => OdometryStep::between(&p, &odom).unwrap(),
            None => OdometryStep::STILL,
        };
        prev = Some(odom);
        mcl.predict(&step, &mut rng);
        let prepared = model.prepare(&layout, scan);
        mcl.update_prepared(&prepared, None, &mut rng).unwrap();
        let e = mcl.estimate().pose;
        if k >= settle {
            let dxy = f64::from((e.x_m - rev.truth.x_m).hypot(e.y_m - rev.truth.y_m));
            let dth = f64::from(wrap_angle(e.theta_rad - rev.truth.theta_rad));
            t.sq_xy += dxy * dxy;
            t.sq_th += dth * dth;
            t.n += 1;
            t.max_xy = t.max_xy.max(dxy);
        }
    }
    t
}

fn add(a: &mut Track, b: Track) {
    a.sq_xy += b.sq_xy;
    a.sq_th += b.sq_th;
    a.n += b.n;
    a.max_xy = a.max_xy.max(b.max_xy);
}

fn row(t: &Track) -> String {
    format!(
        "{:>6.2} {:>6.2} {:>6.1}",
        100.0 * (t.sq_xy / t.n as f64).sqrt(),
        (t.sq_th / t.n as f64).sqrt().to_degrees(),
        100.0 * t.max_xy
    )
}

#[test]
#[ignore = "measurement: prints the table of docs/robot.md (De-skew); about 5 s in release"]
fn deskew_measurement_table() {
    const REVOLUTIONS: usize = 150;
    const SETTLE: usize = 10;
    const SEEDS: u64 = 5;
    let blob = blob();
    let view = FieldView::parse(&blob).unwrap();
    let caster = RayCaster::new(view).unwrap();
    let field = LikelihoodField::new(
        view,
        LikelihoodParams::new(0.95, 0.05, 0.05, MAX_RANGE_M).unwrap(),
    );
    let cases = [
        ("forward 0.5 m/s", Motion { v: 0.5, w: 0.0 }),
        ("turn 1.5 rad/s", Motion { v: 0.0, w: 1.5 }),
        ("both", Motion { v: 0.5, w: 1.5 }),
    ];
    println!(
        "{REVOLUTIONS} revolutions per run, {SEEDS} runs (seed s: the s-th start pose, filter seed s), \
         tracking error after the first {SETTLE}"
    );
    println!(
        "{:<16} | {:>28} | {:>20} | {:>20} | {:>20}",
        "motion", "misplacement mean/max cm", "track raw", "track de-skewed", "track one-pose cast"
    );
    println!(
        "{:<16} | {:>9} {:>9} {:>8} | {:>20} | {:>20} | {:>20}",
        "",
        "raw",
        "de-skewed",
        "contin.",
        "RMSE cm deg max cm",
        "RMSE cm deg max cm",
        "RMSE cm deg max cm"
    );
    for (name, m) in cases {
        let duration = REVOLUTIONS as f64 * REV_S;
        let poses = starts(&view, &caster, m, duration, SEEDS as usize);
        let (mut raw, mut des, mut still) = (Track::default(), Track::default(), Track::default());
        let (mut mr, mut mb, mut mc) = ((0.0, 0.0f64), (0.0, 0.0f64), (0.0, 0.0f64));
        let (mut nr, mut nb) = (0usize, 0usize);
        let (mut host_s, mut host_revs) = (0.0f64, 0usize);
        for (s, &p0) in poses.iter().enumerate() {
            let traj = move |t: f64| pose_at(p0, m, t);
            let revs: Vec<Revolution> = (0..REVOLUTIONS)
                .map(|k| revolution(&caster, &traj, k as f64 * REV_S))
                .collect();
            let swept: Vec<Scan<BEAMS>> = revs.iter().map(|r| r.swept.clone()).collect();
            let layout = layout();
            let d = Deskewer::new(&layout).unwrap();
            let mut deskewed = vec![Scan::<BEAMS>::default(); revs.len()];
            let clock = std::time::Instant::now();
            for (rev, out) in revs.iter().zip(deskewed.iter_mut()) {
                d.apply(&layout, &rev.swept, &rev.sweep, out).unwrap();
            }
            host_s += clock.elapsed().as_secs_f64();
            host_revs += revs.len();
            let one_pose: Vec<Scan<BEAMS>> = revs.iter().map(|r| r.still.clone()).collect();
            for (rev, out) in revs.iter().zip(&deskewed) {
                let mis = misplacement(rev, out);
                for i in 0..mis.raw.len() {
                    mr = (mr.0 + mis.raw[i], mr.1.max(mis.raw[i]));
                    mc = (mc.0 + mis.continuous[i], mc.1.max(mis.continuous[i]));
                    nr += 1;
                    if let Some(e) = mis.binned[i] {
                        mb = (mb.0 + e, mb.1.max(e));
                        nb += 1;
                    }
                }
            }
            let seed = s as u64 + 1;
            add(&mut raw, track(&field, &revs, &swept, seed, SETTLE));
            add(&mut des, track(&field, &revs, &deskewed, seed, SETTLE));
            add(&mut still, track(&field, &revs, &one_pose, seed, SETTLE));
        }
        println!(
            "{:<16} | {:>4.2}/{:<4.1} {:>4.2}/{:<4.1} {:>4.2}/{:<3.1} | {} | {} | {}",
            name,
            100.0 * mr.0 / nr as f64,
            100.0 * mr.1,
            100.0 * mb.0 / nb as f64,
            100.0 * mb.1,
            100.0 * mc.0 / nr as f64,
            100.0 * mc.1,
            row(&raw),
            row(&des),
            row(&still)
        );
        println!(
            "{:<16}   ({nr} readings, {nb} kept their bin after de-skew; de-skew on this host \
             {:.1} µs per revolution)",
            "",
            1e6 * host_s / host_revs as f64
        );
    }
}
