//! The application over a synthetic room: an LD06 stream ray-cast from a known path and 50 Hz
//! odometry along it, through the same byte interface as the device.

use super::*;
use crate::field::free_space::{emit_free_space, free_space_len, FreeSpaceGrid};
use crate::field::{emit_blob, FieldHeader};
use crate::lidar::assembler::{full_turn_layout, sample_revolution};
use crate::lidar::ld06::{self, Ld06Sample};
use crate::link::{Encoder, SetInitialPose, WheelOdometry};
use crate::pose::SensorMount;

const CELL: f32 = 0.05;
const W: usize = 120;
const H: usize = 80;
const BEAMS: usize = 360;
const CAP: usize = 300;

fn occupied(ix: usize, iy: usize) -> bool {
    ix == 0
        || iy == 0
        || ix == W - 1
        || iy == H - 1
        || ((70..78).contains(&ix) && (20..34).contains(&iy))
}

struct Room {
    blob: Vec<u8>,
    free: Vec<u8>,
}

fn room() -> Room {
    let walls: Vec<(f32, f32)> = (0..W * H)
        .filter(|&i| occupied(i % W, i / W))
        .map(|i| ((i % W) as f32, (i / W) as f32))
        .collect();
    let header = FieldHeader::new(W as u32, H as u32, CELL, 0.0, 0.0);
    let codes: Vec<u8> = (0..W * H)
        .map(|i| {
            let (x, y) = ((i % W) as f32, (i / W) as f32);
            let d = walls
                .iter()
                .map(|&(a, b)| ((a - x) * (a - x) + (b - y) * (b - y)).sqrt())
                .fold(f32::INFINITY, f32::min)
                * CELL;
            (d.min(header.max_dist_m) / header.max_dist_m * 255.0).round() as u8
        })
        .collect();
    let mut blob = vec![0u8; 64 + W * H];
    let n = emit_blob(&header, &codes, &mut blob).unwrap();
    blob.truncate(n);
    let view = FieldView::parse(&blob).unwrap();
    let grid = FreeSpaceGrid::of_view(&view);
    let free_cells: Vec<bool> = (0..W * H).map(|i| !occupied(i % W, i / W)).collect();
    let mut free = vec![0u8; free_space_len(&grid, &free_cells).unwrap()];
    emit_free_space(&grid, &free_cells, &mut free).unwrap();
    Room { blob, free }
}

fn range(p: &Pose, a: f32) -> f32 {
    let (c, s) = ((p.theta_rad + a).cos(), (p.theta_rad + a).sin());
    let mut r = 0.0f32;
    while r < 8.0 {
        r += 0.002;
        let (x, y) = (p.x_m + r * c, p.y_m + r * s);
        let (ix, iy) = ((x / CELL).floor(), (y / CELL).floor());
        if ix < 0.0 || iy < 0.0 || occupied(ix as usize, iy as usize) {
            return r;
        }
    }
    f32::NAN
}

/// The path: 0.3 m/s along x while turning at 0.2 rad/s, from (1.2, 1.5, 0).
fn truth(t_us: u64) -> Pose {
    let t = t_us as f32 * 1e-6;
    Pose::new(1.2 + 0.3 * t, 1.5 + 0.05 * t, wrap_angle(0.2 * t))
}

fn layout() -> BeamLayout<BEAMS> {
    full_turn_layout::<BEAMS>(BEAMS, 8.0, SensorMount::CENTERED).unwrap()
}

/// `revolutions` LD06 revolutions at 10 Hz, each ray-cast from the truth at its middle time.
fn lidar_stream(revolutions: usize) -> (Vec<u8>, Vec<u64>) {
    lidar_stream_of(revolutions, truth)
}

/// [`lidar_stream`] along the path `pose_at`.
fn lidar_stream_of(revolutions: usize, pose_at: impl Fn(u64) -> Pose) -> (Vec<u8>, Vec<u64>) {
    let layout = layout();
    let mut bytes = Vec::new();
    let mut times = Vec::new();
    let mut rev = vec![0u8; ld06::revolution_len(BEAMS)];
    for k in 0..revolutions {
        let start_ms = (k * 100) as u64;
        // Frames at start + 0, 3.33, …, 96.67 ms: the assembler's time is the middle of the
        // first and last frames' (rounded) stamps.
        let last_ms = start_ms + (34_800 * 10 + 1800) / 3600;
        let mid_us = start_ms * 1000 + (last_ms - start_ms) * 1000 / 2;
        let pose = pose_at(mid_us);
        let ranges: Vec<f32> = (0..BEAMS)
            .map(|i| range(&pose, layout.beams()[i].bearing_rad))
            .collect();
        let scan = Scan::<BEAMS>::from_ranges(&ranges).unwrap();
        let mut cw = vec![0.0f32; BEAMS];
        sample_revolution(&layout, &scan, &mut cw).unwrap();
        let samples: Vec<Ld06Sample> = cw
            .iter()
            .map(|&r| Ld06Sample::from_range_m(r, 200))
            .collect();
        let n =
            ld06::encode_revolution(&samples, 3600, (start_ms % 30_000) as u16, &mut rev).unwrap();
        bytes.extend_from_slice(&rev[..n]);
        times.push(mid_us);
    }
    (bytes, times)
}

fn frame(encoder: &mut Encoder, m: Message) -> Vec<u8> {
    let mut wire = [0u8; MAX_WIRE_LEN];
    let n = encoder.encode(&m, &mut wire).unwrap();
    wire[..n].to_vec()
}

/// An initial pose at the truth, then odometry every 20 ms (the truth itself) up to `until_us`.
fn link_stream(until_us: u64) -> Vec<u8> {
    let mut e = Encoder::new();
    let mut out = Vec::new();
    out.extend(frame(
        &mut e,
        Message::WheelOdometry(WheelOdometry {
            timestamp_us: 0,
            pose: truth(0),
        }),
    ));
    let cov = [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.01]];
    out.extend(frame(
        &mut e,
        Message::SetInitialPose(SetInitialPose {
            timestamp_us: 0,
            pose: truth(0),
            covariance: cov,
        }),
    ));
    let mut t = 20_000;
    while t <= until_us {
        out.extend(frame(
            &mut e,
            Message::WheelOdometry(WheelOdometry {
                timestamp_us: t,
                pose: truth(t),
            }),
        ));
        t += 20_000;
    }
    out
}

#[derive(Default)]
struct Collect {
    frames: Vec<(Message, Vec<u8>)>,
    saved: Option<Seed>,
}

impl Sink for Collect {
    fn send(&mut self, message: &Message, wire: &[u8]) {
        self.frames.push((*message, wire.to_vec()));
    }
    fn save(&mut self, seed: &Seed) {
        self.saved = Some(*seed);
    }
}

fn config() -> RobotConfig {
    let mut c = RobotConfig::new(8.0).unwrap();
    c.particles = 200;
    c
}

/// Runs the application over both streams, handing the link out `link_chunk` bytes and the
/// LiDAR `lidar_chunk` bytes per poll (0: everything at once).
fn run(
    room: &Room,
    lidar: &[u8],
    link: &[u8],
    link_chunk: usize,
    lidar_chunk: usize,
    seed: Option<Seed>,
) -> (Collect, RobotCounters) {
    let mut store = Particles::<CAP>::new();
    let view = FieldView::parse(&room.blob).unwrap();
    let free = FreeSpace::parse(&room.free).unwrap();
    let mut robot =
        Robot::<CAP, BEAMS>::new(&mut store, view, Some(free), layout(), config(), seed).unwrap();
    let mut sink = Collect::default();
    let (mut li, mut ki) = (0usize, 0usize);
    for _ in 0..1_000_000 {
        let lidar_end = if lidar_chunk == 0 {
            lidar.len()
        } else {
            (li + lidar_chunk).min(lidar.len())
        };
        let link_end = if link_chunk == 0 {
            link.len()
        } else {
            (ki + link_chunk).min(link.len())
        };
        let mut ls = SliceSource::new(&lidar[li..lidar_end]);
        let mut ks = SliceSource::new(&link[ki..link_end]);
        let p = robot.poll(&mut ls, &mut ks, &mut sink);
        li += ls.taken();
        ki += ks.taken();
        if p.is_idle() && li == lidar.len() && ki == link.len() {
            break;
        }
    }
    (sink, robot.counters())
}

fn estimates(c: &Collect) -> Vec<link::Estimate> {
    c.frames
        .iter()
        .filter_map(|(m, _)| match m {
            Message::Estimate(e) => Some(*e),
            _ => None,
        })
        .collect()
}

#[test]
fn tracks_the_path_and_sends_one_estimate_per_revolution() {
    let room = room();
    let (lidar, times) = lidar_stream(30);
    let link = link_stream(3_200_000);
    let (out, counters) = run(&room, &lidar, &link, 0, 0, None);
    let est = estimates(&out);
    // The last revolution is closed only by a following one.
    assert_eq!(counters.revolutions, 29);
    assert_eq!(est.len(), 29);
    assert_eq!(counters.late_odometry, 0);
    for (e, &t) in est.iter().zip(&times) {
        assert_eq!(e.timestamp_us, t);
        let p = truth(t);
        let d = ((e.pose.x_m - p.x_m).powi(2) + (e.pose.y_m - p.y_m).powi(2)).sqrt();
        assert!(d < 0.05, "error {d} m at {t} µs");
        assert!(wrap_angle(e.pose.theta_rad - p.theta_rad).abs() < 0.03);
        assert!(e.flags.contains(EstimateFlags::INITIALIZED));
        assert!(!e.flags.contains(EstimateFlags::ODOMETRY_STALE));
        // The localizer's own assessment, not "not assessed".
        assert_ne!(e.quality.state, link::QualityState::Unknown);
        assert!(
            e.quality.score > 0.0 && e.quality.score <= 1.0,
            "{:?}",
            e.quality
        );
    }
    // Tracking a clean synthetic room: the signal says so once the averages have settled.
    let tracking = est
        .iter()
        .filter(|e| e.quality.state == link::QualityState::Tracking)
        .count();
    assert!(
        tracking * 10 >= est.len() * 8,
        "{tracking} of {}",
        est.len()
    );
    // Heartbeats follow the board's clock (`Robot::tick`), which this run does not give.
    let heartbeats = out
        .frames
        .iter()
        .filter(|(m, _)| matches!(m, Message::Heartbeat(_)))
        .count();
    assert_eq!(heartbeats, 0);
    assert!(out.saved.is_some());
}

/// What follows from the byte streams alone: every estimate bit for bit, every error report,
/// and the heartbeats' time, scans and updates (their link counters count what was read ahead).
fn deterministic(c: &Collect) -> Vec<String> {
    c.frames
        .iter()
        .map(|(m, _)| match m {
            Message::Estimate(e) => format!(
                "estimate {} {:08x} {:08x} {:08x} {:08x} {:?} {:x?}",
                e.timestamp_us,
                e.pose.x_m.to_bits(),
                e.pose.y_m.to_bits(),
                e.pose.theta_rad.to_bits(),
                e.ess.to_bits(),
                e.flags,
                e.covariance.map(|r| r.map(f32::to_bits)),
            ),
            Message::Heartbeat(h) => {
                format!("heartbeat {} {} {}", h.timestamp_us, h.scans, h.updates)
            }
            other => format!("{other:?}"),
        })
        .collect()
}

#[test]
fn the_output_does_not_depend_on_how_the_bytes_are_split() {
    // Any split in which the odometry keeps up with the LiDAR (the module's one condition; a
    // link starved for a whole revolution is late, see the next test).
    let room = room();
    let (lidar, _) = lidar_stream(12);
    let link = link_stream(1_400_000);
    let (whole, _) = run(&room, &lidar, &link, 0, 0, None);
    assert_eq!(estimates(&whole).len(), 11);
    for (link_chunk, lidar_chunk) in [(1, 1), (7, 47), (64, 1000), (5, 20)] {
        let (split, c) = run(&room, &lidar, &link, link_chunk, lidar_chunk, None);
        assert_eq!(
            deterministic(&whole),
            deterministic(&split),
            "chunks {link_chunk}/{lidar_chunk}, counters {c:?}"
        );
    }
}

#[test]
fn odometry_that_never_comes_is_late_and_flagged() {
    let room = room();
    let (lidar, _) = lidar_stream(6);
    let mut e = Encoder::new();
    let link = frame(
        &mut e,
        Message::SetInitialPose(SetInitialPose {
            timestamp_us: 0,
            pose: truth(0),
            covariance: [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.01]],
        }),
    );
    let (out, counters) = run(&room, &lidar, &link, 0, 0, None);
    let est = estimates(&out);
    // Every revolution but the last waits for the next one, then goes on without odometry.
    assert_eq!(counters.late_odometry, 4);
    assert_eq!(est.len(), 4);
    assert!(est
        .iter()
        .all(|e| e.flags.contains(EstimateFlags::ODOMETRY_STALE)));
}

#[test]
fn bad_messages_are_refused_with_a_typed_error_and_change_nothing() {
    let room = room();
    let (lidar, _) = lidar_stream(8);
    let good = link_stream(900_000);
    let mut e = Encoder::new();
    // Sequence numbers of the bad frames follow the good ones'.
    for _ in 0..good.iter().filter(|&&b| b == 0).count() {
        frame(&mut e, Message::RequestNoMotionUpdate);
    }
    let mut link = good.clone();
    let odo = |t, x| {
        Message::WheelOdometry(WheelOdometry {
            timestamp_us: t,
            pose: Pose::new(x, 1.5, 0.0),
        })
    };
    link.extend(frame(&mut e, odo(100_000, 1.0))); // time went backwards
    link.extend(frame(&mut e, odo(920_000, 50.0))); // 50 m in 20 ms
    link.extend(frame(
        &mut e,
        Message::SetParameters(SetParameters {
            particles: Some(CAP as u16 + 1),
            ..SetParameters::default()
        }),
    ));
    link.extend([0x13, 0x37, 0x00, 0xFF, 0x01, 0x00]); // garbage
    let (out, counters) = run(&room, &lidar, &link, 0, 0, None);
    let errors: Vec<ErrorCode> = out
        .frames
        .iter()
        .filter_map(|(m, _)| match m {
            Message::Error(r) => Some(r.code),
            _ => None,
        })
        .collect();
    assert_eq!(
        errors,
        [
            ErrorCode::OutOfOrder,
            ErrorCode::ValueOutOfRange,
            ErrorCode::Refused
        ]
    );
    assert_eq!(counters.refused, 3);
    // The good run's estimates, unchanged.
    let (clean, _) = run(&room, &lidar, &good, 0, 0, None);
    assert_eq!(estimates(&out), estimates(&clean));
    for e in estimates(&out) {
        assert!(e.pose.is_finite());
    }
}

#[test]
fn no_motion_update_before_initialization_is_refused() {
    let room = room();
    let mut e = Encoder::new();
    let link = frame(&mut e, Message::RequestNoMotionUpdate);
    let (out, counters) = run(&room, &[], &link, 0, 0, None);
    assert_eq!(counters.refused, 1);
    assert!(matches!(
        out.frames.first().map(|f| f.0),
        Some(Message::Error(ErrorReport {
            code: ErrorCode::NotInitialized,
            ..
        }))
    ));
}

#[test]
fn a_saved_estimate_seeds_the_next_start() {
    let room = room();
    let (lidar, times) = lidar_stream(6);
    // Odometry only: no initial pose on the link.
    let mut e = Encoder::new();
    let mut link = Vec::new();
    let mut t = 0;
    while t <= 700_000 {
        link.extend(frame(
            &mut e,
            Message::WheelOdometry(WheelOdometry {
                timestamp_us: t,
                pose: truth(t),
            }),
        ));
        t += 20_000;
    }
    let (unseeded, c) = run(&room, &lidar, &link, 0, 0, None);
    assert!(estimates(&unseeded).is_empty());
    assert_eq!(c.skipped, 5);
    let seed = Seed {
        pose: truth(0),
        covariance: [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.01]],
    };
    let (seeded, _) = run(&room, &lidar, &link, 0, 0, Some(seed));
    let est = estimates(&seeded);
    assert_eq!(est.len(), 5);
    let p = truth(times[4]);
    assert!((est[4].pose.x_m - p.x_m).abs() < 0.05);
}

#[test]
fn global_localization_spreads_the_cloud_and_an_initial_pose_puts_it_right() {
    let room = room();
    let (lidar, times) = lidar_stream(20);
    let mut e = Encoder::new();
    let mut link = Vec::new();
    let mut t = 0;
    while t <= 2_100_000 {
        link.extend(frame(
            &mut e,
            Message::WheelOdometry(WheelOdometry {
                timestamp_us: t,
                pose: truth(t),
            }),
        ));
        if t == 0 {
            link.extend(frame(&mut e, Message::StartGlobalLocalization));
        }
        if t == 1_000_000 {
            link.extend(frame(
                &mut e,
                Message::SetInitialPose(SetInitialPose {
                    timestamp_us: t,
                    pose: truth(t),
                    covariance: [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.01]],
                }),
            ));
        }
        t += 20_000;
    }
    let (out, _) = run(&room, &lidar, &link, 0, 0, None);
    let est = estimates(&out);
    assert_eq!(est.len(), 19);
    assert!(est[0].flags.contains(EstimateFlags::GLOBAL_LOCALIZATION));
    // After the initial pose (at 1.0 s): tracking.
    for (e, &t) in est.iter().zip(&times).filter(|(_, &t)| t > 1_000_000) {
        assert!(!e.flags.contains(EstimateFlags::GLOBAL_LOCALIZATION));
        let p = truth(t);
        assert!(((e.pose.x_m - p.x_m).powi(2) + (e.pose.y_m - p.y_m).powi(2)).sqrt() < 0.05);
    }
}

/// `revolutions` LD06 revolutions at 10 Hz, each point ray-cast from `pose_at` at its own time
/// within the turn (point `k`, at `k°` clockwise, is measured `k / 3600` s after the start).
fn swept_lidar_stream(revolutions: usize, pose_at: impl Fn(u64) -> Pose) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut rev = vec![0u8; ld06::revolution_len(BEAMS)];
    for k in 0..revolutions {
        let start_us = (k * 100_000) as u64;
        let samples: Vec<Ld06Sample> = (0..BEAMS)
            .map(|i| {
                let t = start_us + (i as u64 * 100_000) / BEAMS as u64;
                let r = range(&pose_at(t), -(i as f32).to_radians());
                Ld06Sample::from_range_m(r, 200)
            })
            .collect();
        let n =
            ld06::encode_revolution(&samples, 3600, ((k * 100) % 30_000) as u16, &mut rev).unwrap();
        bytes.extend_from_slice(&rev[..n]);
    }
    bytes
}

/// An initial pose at `pose_at(0)`, then odometry every 20 ms from `pose_at` up to `until_us`.
fn swept_link_stream(until_us: u64, pose_at: impl Fn(u64) -> Pose) -> Vec<u8> {
    let mut e = Encoder::new();
    let mut out = frame(
        &mut e,
        Message::WheelOdometry(WheelOdometry {
            timestamp_us: 0,
            pose: pose_at(0),
        }),
    );
    let cov = [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.01]];
    out.extend(frame(
        &mut e,
        Message::SetInitialPose(SetInitialPose {
            timestamp_us: 0,
            pose: pose_at(0),
            covariance: cov,
        }),
    ));
    let mut t = 20_000;
    while t <= until_us {
        out.extend(frame(
            &mut e,
            Message::WheelOdometry(WheelOdometry {
                timestamp_us: t,
                pose: pose_at(t),
            }),
        ));
        t += 20_000;
    }
    out
}

fn run_with(
    room: &Room,
    lidar: &[u8],
    link: &[u8],
    config: RobotConfig,
) -> (Collect, RobotCounters) {
    let mut store = Particles::<CAP>::new();
    let view = FieldView::parse(&room.blob).unwrap();
    let free = FreeSpace::parse(&room.free).unwrap();
    let mut robot =
        Robot::<CAP, BEAMS>::new(&mut store, view, Some(free), layout(), config, None).unwrap();
    let mut sink = Collect::default();
    let (mut ls, mut ks) = (SliceSource::new(lidar), SliceSource::new(link));
    for _ in 0..1_000_000 {
        if robot.poll(&mut ls, &mut ks, &mut sink).is_idle() {
            break;
        }
    }
    (sink, robot.counters())
}

#[test]
fn deskew_of_a_robot_standing_still_changes_no_estimate() {
    let room = room();
    let still = |_t: u64| Pose::new(2.0, 1.6, 0.4);
    let lidar = swept_lidar_stream(12, still);
    let link = swept_link_stream(1_300_000, still);
    let (off, c_off) = run_with(&room, &lidar, &link, config());
    let mut on_config = config();
    on_config.deskew = true;
    let (on, c_on) = run_with(&room, &lidar, &link, on_config);
    assert_eq!(c_off.deskewed, 0);
    assert!(c_on.updates >= 10, "{c_on:?}");
    assert_eq!(c_on.deskewed, c_on.updates, "{c_on:?}");
    assert_eq!(c_on.deskew_skipped, 0, "{c_on:?}");
    assert_eq!(estimates(&off), estimates(&on));
}

#[test]
fn deskew_of_a_turning_robot_runs_on_every_update_and_tracks() {
    let room = room();
    // 0.5 m/s forward while turning at 1.5 rad/s: a circle of 1/3 m radius around (3, 2).
    let pose_at = |t_us: u64| {
        let t = t_us as f32 * 1e-6;
        let th = 1.5 * t;
        Pose::new(3.0 + th.sin() / 3.0, 2.0 - th.cos() / 3.0, wrap_angle(th))
    };
    let lidar = swept_lidar_stream(20, pose_at);
    let link = swept_link_stream(2_100_000, pose_at);
    let mut c = config();
    c.deskew = true;
    let (on, counters) = run_with(&room, &lidar, &link, c);
    let est = estimates(&on);
    assert!(est.len() >= 18, "{counters:?}");
    assert_eq!(counters.deskewed, counters.updates, "{counters:?}");
    assert_eq!(counters.late_odometry, 0, "{counters:?}");
    for e in &est {
        let p = pose_at(e.timestamp_us);
        let d = ((e.pose.x_m - p.x_m).powi(2) + (e.pose.y_m - p.y_m).powi(2)).sqrt();
        assert!(d < 0.1, "{e:?} vs {p:?}");
        assert!(
            wrap_angle(e.pose.theta_rad - p.theta_rad).abs() < 0.05,
            "{e:?}"
        );
    }
}

mod faults;
