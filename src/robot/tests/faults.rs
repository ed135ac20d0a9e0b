//! A robot's bad day: valid-looking faults (stamps that jump, an odometry restart, a CRC-valid
//! LiDAR frame with a wrong stamp, a covariance the filter cannot use, a silent LiDAR) that the
//! application must survive: refused with an error report and counted, or absorbed, never
//! applied as motion or time.

use super::*;
use crate::link::WheelOdometry;

const COV: [[f32; 3]; 3] = [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.01]];

fn odo(t_us: u64, pose: Pose) -> Message {
    Message::WheelOdometry(WheelOdometry {
        timestamp_us: t_us,
        pose,
    })
}

fn initial(pose: Pose, covariance: [[f32; 3]; 3]) -> Message {
    Message::SetInitialPose(SetInitialPose {
        timestamp_us: 0,
        pose,
        covariance,
    })
}

fn errors(c: &Collect) -> Vec<ErrorReport> {
    c.frames
        .iter()
        .filter_map(|(m, _)| match m {
            Message::Error(r) => Some(*r),
            _ => None,
        })
        .collect()
}

/// The time an LD06 frame of [`lidar_stream`] has fully arrived: frame `j` of revolution `k`
/// (30 frames of 12 points per turn at 10 Hz) ends `(j + 1) · 100 / 30` ms after the turn starts.
fn frame_end_us(index: usize) -> u64 {
    let (k, j) = (index / 30, index % 30);
    k as u64 * 100_000 + (j as u64 + 1) * 100_000 / 30
}

/// Runs the application with the bytes arriving at their times, as on the device: each LD06
/// frame when its last byte is in, each link frame at its time; polls until idle after each.
fn run_paced(
    room: &Room,
    lidar: &[u8],
    link: &[(u64, Vec<u8>)],
    config: RobotConfig,
) -> (Collect, RobotCounters, u64) {
    let mut store = Particles::<CAP>::new();
    let view = FieldView::parse(&room.blob).unwrap();
    let free = FreeSpace::parse(&room.free).unwrap();
    let mut robot =
        Robot::<CAP, BEAMS>::new(&mut store, view, Some(free), layout(), config, None).unwrap();
    let mut sink = Collect::default();
    let mut arrivals: Vec<(u64, bool, &[u8])> = lidar
        .chunks(ld06::FRAME_LEN)
        .enumerate()
        .map(|(i, c)| (frame_end_us(i), true, c))
        .chain(link.iter().map(|(t, b)| (*t, false, b.as_slice())))
        .collect();
    // Stable: at equal times the LiDAR frame first.
    arrivals.sort_by_key(|&(t, is_lidar, _)| (t, !is_lidar));
    for (_, is_lidar, bytes) in arrivals {
        let (mut ls, mut ks) = if is_lidar {
            (SliceSource::new(bytes), SliceSource::new(&[]))
        } else {
            (SliceSource::new(&[]), SliceSource::new(bytes))
        };
        for _ in 0..1_000 {
            if robot.poll(&mut ls, &mut ks, &mut sink).is_idle() {
                break;
            }
        }
        assert!(ls.is_empty() && ks.is_empty(), "bytes left unread");
    }
    let now = robot.now_us();
    (sink, robot.counters(), now)
}

/// The link of [`link_stream`], each frame with its time, stamped by `stamp`.
fn paced_link(until_us: u64, stamp: impl Fn(u64) -> u64) -> Vec<(u64, Vec<u8>)> {
    let mut e = Encoder::new();
    let mut out = vec![(0, frame(&mut e, odo(stamp(0), truth(0))))];
    out.push((0, frame(&mut e, initial(truth(0), COV))));
    let mut t = 20_000;
    while t <= until_us {
        out.push((t, frame(&mut e, odo(stamp(t), truth(t)))));
        t += 20_000;
    }
    out
}

fn assert_tracks(est: &[link::Estimate], at: impl Fn(u64) -> Pose, tolerance_m: f32) {
    for e in est {
        let p = at(e.timestamp_us);
        let d = ((e.pose.x_m - p.x_m).powi(2) + (e.pose.y_m - p.y_m).powi(2)).sqrt();
        assert!(d < tolerance_m, "error {d} m at {} µs", e.timestamp_us);
    }
}

#[test]
fn odometry_stamped_zero_is_taken_on_arrival() {
    let room = room();
    let (lidar, _) = lidar_stream(10);
    let link = paced_link(960_000, |_| 0);
    let (out, counters, _) = run_paced(&room, &lidar, &link, config());
    assert_eq!(errors(&out), []);
    assert_eq!(counters.refused, 0);
    assert_eq!(counters.odometry, 49);
    let est = estimates(&out);
    assert_eq!(est.len(), 9);
    // Stamped on arrival, up to one LD06 frame (3.3 ms) before the pose was measured.
    assert_tracks(&est, truth, 0.05);
}

#[test]
fn odometry_on_the_device_clock_paced_as_on_the_device_tracks() {
    // The control of the previous test: the same run with the odometry stamped by its sender.
    let room = room();
    let (lidar, _) = lidar_stream(10);
    let link = paced_link(960_000, |t| t);
    let (out, counters, _) = run_paced(&room, &lidar, &link, config());
    assert_eq!(counters.refused, 0);
    assert_eq!(estimates(&out).len(), 9);
    assert_tracks(&estimates(&out), truth, 0.05);
}

#[test]
fn one_odometry_frame_stamped_far_ahead_poisons_nothing() {
    let room = room();
    let (lidar, _) = lidar_stream(20);
    // The clean run, with a second initial pose at 1.5 s.
    let build = |bad: bool| {
        let mut e = Encoder::new();
        let mut link = frame(&mut e, odo(0, truth(0)));
        link.extend(frame(&mut e, initial(truth(0), COV)));
        let mut t = 20_000;
        while t <= 2_100_000 {
            link.extend(frame(&mut e, odo(t, truth(t))));
            if t == 500_000 && bad {
                link.extend(frame(&mut e, odo(1_000_000_000_000, truth(t))));
            } else if t == 500_000 {
                // Keep the sequence numbers of both runs alike.
                e.encode(&odo(t, truth(t)), &mut [0u8; MAX_WIRE_LEN])
                    .unwrap();
            }
            if t == 1_500_000 {
                link.extend(frame(&mut e, initial(truth(t), COV)));
            }
            t += 20_000;
        }
        link
    };
    let (clean, _) = run(&room, &lidar, &build(false), 0, 0, None);
    for (link_chunk, lidar_chunk) in [(0, 0), (30, 141)] {
        let (out, counters) = run(&room, &lidar, &build(true), link_chunk, lidar_chunk, None);
        let errs = errors(&out);
        assert_eq!(errs.len(), 1, "{errs:?}");
        assert_eq!(errs[0].code, ErrorCode::ValueOutOfRange);
        assert_eq!(
            usize::from(errs[0].detail),
            link::layout::wheel_odometry::TIMESTAMP_US.start
        );
        assert_eq!(counters.refused, 1);
        assert_eq!(counters.odometry, 106);
        assert_eq!(estimates(&out), estimates(&clean));
    }
}

/// A path that stops at 1.0 s, stands still until 2.2 s and then drives on as [`truth`] did
/// from 1.0 s.
fn parked(t_us: u64) -> Pose {
    truth(match t_us {
        0..=1_000_000 => t_us,
        1_000_001..=2_200_000 => 1_000_000,
        _ => t_us - 1_200_000,
    })
}

/// `p` in the frame of `origin`.
fn relative(origin: &Pose, p: &Pose) -> Pose {
    let (s, c) = origin.theta_rad.sin_cos();
    let (dx, dy) = (p.x_m - origin.x_m, p.y_m - origin.y_m);
    Pose::new(
        c * dx + s * dy,
        -s * dx + c * dy,
        wrap_angle(p.theta_rad - origin.theta_rad),
    )
}

#[test]
fn wheel_odometry_restarting_at_zero_after_a_gap_is_not_motion() {
    let room = room();
    let (lidar, _) = lidar_stream_of(35, parked);
    // The base controller goes silent at 1.0 s and comes back at 2.2 s with its odometry
    // restarted at the origin: its poses are the path's, relative to where it restarted.
    // Before, its frame is the map's moved 10 m along x (where it was started).
    let before = |t: u64| {
        let p = parked(t);
        Pose::new(p.x_m + 10.0, p.y_m, p.theta_rad)
    };
    let origin = parked(2_200_000);
    let mut e = Encoder::new();
    let mut link = frame(&mut e, odo(0, before(0)));
    link.extend(frame(&mut e, initial(parked(0), COV)));
    let mut t = 20_000;
    while t <= 3_600_000 {
        if t <= 1_000_000 {
            link.extend(frame(&mut e, odo(t, before(t))));
        } else if t >= 2_200_000 {
            link.extend(frame(&mut e, odo(t, relative(&origin, &parked(t)))));
        }
        t += 20_000;
    }
    let (out, counters) = run_with(&room, &lidar, &link, config());
    assert_eq!(counters.odometry_restarts, 1, "{counters:?}");
    assert_eq!(counters.refused, 0, "{counters:?}");
    let est = estimates(&out);
    assert!(est.len() >= 33, "{counters:?}");
    assert_tracks(&est, parked, 0.1);
    // The estimates across the silence say the odometry could not be used.
    assert!(est
        .iter()
        .filter(|e| (1_020_000..2_200_000).contains(&e.timestamp_us))
        .all(|e| e.flags.contains(EstimateFlags::ODOMETRY_STALE)));
}

/// `lidar` with the timestamp of LD06 frame `index` moved `by_ms` ahead (and its CRC fixed).
fn wrong_stamp(lidar: &[u8], index: usize, by_ms: u16) -> Vec<u8> {
    let mut out = lidar.to_vec();
    let f = &mut out[index * ld06::FRAME_LEN..(index + 1) * ld06::FRAME_LEN];
    let ts = u16::from_le_bytes([f[44], f[45]]);
    let bad = ((u32::from(ts) + u32::from(by_ms)) % u32::from(TIMESTAMP_WRAP_MS)) as u16;
    f[44..46].copy_from_slice(&bad.to_le_bytes());
    f[46] = ld06::crc8(&f[..46]);
    out
}

#[test]
fn one_ld06_frame_with_a_wrong_stamp_does_not_move_the_clock() {
    let room = room();
    let (lidar, times) = lidar_stream(20);
    let link = link_stream(2_200_000);
    let (clean, _) = run(&room, &lidar, &link, 0, 0, None);
    // A frame in the middle of revolution 8, 27 s ahead.
    let bad = wrong_stamp(&lidar, 8 * 30 + 12, 27_000);
    let (out, counters) = run(&room, &bad, &link, 0, 0, None);
    let stamps = |c: &Collect| {
        estimates(c)
            .iter()
            .map(|e| e.timestamp_us)
            .collect::<Vec<_>>()
    };
    assert_eq!(stamps(&out), stamps(&clean));
    // The frame's 12 points are dropped: the estimates track as the clean run's do.
    assert_tracks(&estimates(&out), truth, 0.05);
    assert_eq!(counters.late_odometry, 0);
    // The first or the last frame of a revolution: that revolution's time comes from its
    // other stamps; every other estimate is stamped as in the clean run.
    for index in [9 * 30, 9 * 30 + 29] {
        let bad = wrong_stamp(&lidar, index, 27_000);
        let (out, counters) = run(&room, &bad, &link, 0, 0, None);
        let est = estimates(&out);
        assert_eq!(est.len(), 19, "{counters:?}");
        for (e, &t) in est.iter().zip(&times) {
            assert!(
                e.timestamp_us.abs_diff(t) <= 50_000,
                "{} vs {t}",
                e.timestamp_us
            );
        }
        assert_tracks(&est, truth, 0.05);
    }
    // The clock the device reports is the sensor's, not 27 s ahead.
    let (_, _, now) = run_paced(
        &room,
        &wrong_stamp(&lidar, 8 * 30 + 12, 27_000),
        &paced_link(2_000_000, |t| t),
        config(),
    );
    assert!(now < 2_100_000, "{now}");
}

#[test]
fn an_initial_pose_with_a_covariance_the_filter_cannot_use_is_refused() {
    let room = room();
    let (lidar, _) = lidar_stream(8);
    for v in [3e38f32, 1e30, 1e12] {
        let mut e = Encoder::new();
        let mut link = frame(&mut e, odo(0, truth(0)));
        let huge = [[v, 0.0, 0.0], [0.0, v, 0.0], [0.0, 0.0, 0.01]];
        link.extend(frame(&mut e, initial(truth(0), huge)));
        let mut t = 20_000;
        while t <= 900_000 {
            link.extend(frame(&mut e, odo(t, truth(t))));
            t += 20_000;
        }
        let (out, counters) = run(&room, &lidar, &link, 0, 0, None);
        let errs = errors(&out);
        assert_eq!(errs.len(), 1, "{v}: {errs:?}");
        assert_eq!(errs[0].code, ErrorCode::Refused);
        assert_eq!(errs[0].msg_type, MessageType::SetInitialPose as u8);
        assert_eq!(errs[0].seq, 1);
        assert_eq!(counters.refused, 1);
        // State unchanged: the filter still waits for an initial pose.
        assert!(estimates(&out).is_empty());
        assert_eq!(counters.encode_failures, 0);
    }
    // Within the bound: taken, every estimate encodable.
    let mut e = Encoder::new();
    let mut link = frame(&mut e, odo(0, truth(0)));
    let wide = [[25.0, 0.0, 0.0], [0.0, 25.0, 0.0], [0.0, 0.0, 1e30]];
    link.extend(frame(&mut e, initial(truth(0), wide)));
    let (out, counters) = run(&room, &lidar, &link, 0, 0, None);
    assert_eq!(errors(&out), []);
    assert!(!estimates(&out).is_empty());
    assert_eq!(counters.encode_failures, 0);
}

#[test]
fn the_link_is_read_while_the_lidar_is_silent() {
    let room = room();
    // An initial pose and 4 s of odometry, the LiDAR silent.
    let mut e = Encoder::new();
    let mut link = Vec::new();
    let mut t = 0;
    let mut samples = 0u32;
    while t <= 4_000_000 {
        link.extend(frame(&mut e, odo(t, truth(t))));
        samples += 1;
        if t == 0 {
            link.extend(frame(&mut e, initial(truth(t), COV)));
        }
        t += 20_000;
    }
    let mut store = Particles::<CAP>::new();
    let view = FieldView::parse(&room.blob).unwrap();
    let mut robot =
        Robot::<CAP, BEAMS>::new(&mut store, view, None, layout(), config(), None).unwrap();
    robot.set_lidar_silent(true);
    let mut sink = Collect::default();
    let mut ks = SliceSource::new(&link);
    for _ in 0..1_000 {
        if robot
            .poll(&mut SliceSource::new(&[]), &mut ks, &mut sink)
            .is_idle()
        {
            break;
        }
    }
    assert!(ks.is_empty(), "{} of {} bytes read", ks.taken(), link.len());
    let counters = robot.counters();
    assert_eq!(counters.odometry, samples, "{counters:?}");
    let dropped = samples - window::WINDOW as u32;
    assert_eq!(counters.odometry_dropped, dropped, "{counters:?}");
    assert_eq!(errors(&sink), []);
    // The dropped samples are in the heartbeat's drops.
    robot.send_heartbeat(&mut sink);
    let Some((Message::Heartbeat(h), _)) = sink.frames.last() else {
        panic!("no heartbeat");
    };
    assert_eq!(h.drops, dropped);
    // The LiDAR comes back: the initial pose sent during the silence is carried out.
    robot.set_lidar_silent(false);
    let (lidar, _) = lidar_stream_of(8, |_| truth(4_000_000));
    let mut ls = SliceSource::new(&lidar);
    for _ in 0..1_000 {
        if robot
            .poll(&mut ls, &mut SliceSource::new(&[]), &mut sink)
            .is_idle()
        {
            break;
        }
    }
    assert!(!estimates(&sink).is_empty());
    assert!(robot.is_initialized());
}

#[test]
fn a_seed_beyond_the_link_s_range_is_not_used() {
    // Found by the robot_poll fuzz target: a seed at −2.5·10³³ m gave an infinite covariance.
    let room = room();
    let (lidar, _) = lidar_stream(4);
    let link = paced_link(500_000, |t| t.max(1));
    let link: Vec<u8> = link.into_iter().skip(2).flat_map(|(_, b)| b).collect();
    for x in [-2.5e33f32, 1.0e6] {
        let seed = Seed {
            pose: Pose::new(x, x, 0.0),
            covariance: COV,
        };
        let (out, counters) = run(&room, &lidar, &link, 0, 0, Some(seed));
        assert!(estimates(&out).is_empty(), "{x}");
        assert_eq!(counters.updates, 0);
    }
}

/// `n` bytes of line noise, as a LiDAR at the wrong baud rate sends: pseudo-random, with no
/// LD06 header byte (0x54) in them, so that the decoder can only skip every one.
fn noise(n: usize, seed: u64) -> Vec<u8> {
    let mut state = seed;
    (0..n)
        .map(|_| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            match (state >> 56) as u8 {
                0x54 => 0x55,
                b => b,
            }
        })
        .collect()
}

/// Runs `robot` over `steps` (the board's time at the end of the step, µs, and the LiDAR and
/// link bytes that arrived during it) as the firmware's main loop does: polls until idle with
/// the step's bytes, then ticks the board's clock. Every byte must be read in the step it arrived
/// in (the link at its pace whatever the LiDAR does). Returns the heartbeats with the board time
/// each was sent at and the LiDAR bytes handed over by then, and the board times of the steps
/// after which the LiDAR was taken as silent.
fn run_clocked<const N: usize>(
    robot: &mut Robot<'_, N, BEAMS>,
    steps: impl IntoIterator<Item = (u64, Vec<u8>, Vec<u8>)>,
    sink: &mut Collect,
) -> (Vec<(u64, u64, Heartbeat)>, Vec<u64>) {
    let mut beats = Vec::new();
    let mut silent = Vec::new();
    let mut lidar_total = 0u64;
    for (now_us, lidar, link) in steps {
        let (mut ls, mut ks) = (SliceSource::new(&lidar), SliceSource::new(&link));
        for _ in 0..1_000 {
            if robot.poll(&mut ls, &mut ks, sink).is_idle() {
                break;
            }
        }
        assert!(
            ks.is_empty(),
            "at {now_us} µs: {} of {} link bytes read",
            ks.taken(),
            link.len()
        );
        assert!(ls.is_empty(), "at {now_us} µs: LiDAR bytes left");
        lidar_total += lidar.len() as u64;
        let before = sink.frames.len();
        let sent = robot.tick(now_us, sink);
        let new: Vec<Heartbeat> = sink.frames[before..]
            .iter()
            .filter_map(|(m, _)| match m {
                Message::Heartbeat(h) => Some(*h),
                _ => None,
            })
            .collect();
        assert_eq!(sent, !new.is_empty());
        beats.extend(new.into_iter().map(|h| (now_us, lidar_total, h)));
        if robot.is_lidar_silent() {
            silent.push(now_us);
        }
    }
    (beats, silent)
}

/// The LiDAR taken as silent at every step from 1 s (`lidar_silence_us`) after the first tick at
/// 10 ms to the end at `until_us`, steps of 10 ms.
fn assert_silent_after_1_s(silent: &[u64], until_us: u64) {
    let want: Vec<u64> = (1_010_000..=until_us).step_by(10_000).collect();
    assert!(
        silent == want,
        "silent from {:?} to {:?} µs, {} steps",
        silent.first(),
        silent.last(),
        silent.len()
    );
}

/// The LD06's line at 230,400 baud (8N1): bytes that arrive in 10 ms.
const LINE_BYTES_PER_10_MS: usize = 230;

/// Heartbeats at most 1.5 s apart over `until_us`, the first within 1.5 s of the start.
fn assert_periodic(beats: &[(u64, u64, Heartbeat)], until_us: u64) {
    let times: Vec<u64> = beats.iter().map(|b| b.0).collect();
    let mut last = 0;
    for &t in times.iter().chain([until_us].iter()) {
        assert!(t - last <= 1_500_000, "heartbeats at {times:?} µs");
        last = t;
    }
    for (t, _, h) in beats {
        assert_eq!(u64::from(h.uptime_ms), t / 1000);
    }
}

#[test]
fn heartbeats_keep_coming_while_the_lidar_sends_noise_and_count_its_bytes() {
    let room = room();
    let mut store = Particles::<CAP>::new();
    let view = FieldView::parse(&room.blob).unwrap();
    let mut robot =
        Robot::<CAP, BEAMS>::new(&mut store, view, None, layout(), config(), None).unwrap();
    let mut sink = Collect::default();
    // 8 s of noise at the line's rate.
    let steps =
        (1..=800u64).map(|k| (k * 10_000, noise(LINE_BYTES_PER_10_MS, k), Vec::<u8>::new()));
    let (beats, silent) = run_clocked(&mut robot, steps, &mut sink);
    assert_periodic(&beats, 8_000_000);
    assert!(beats.len() >= 7, "{}", beats.len());
    assert_silent_after_1_s(&silent, 8_000_000);
    // Every noise byte handed over by then is in the heartbeat's count of skipped bytes.
    for (t, fed, h) in &beats {
        assert_eq!(u64::from(h.lidar_skipped), *fed, "at {t} µs");
        assert_eq!(h.scans, 0);
    }
    // A second later, all 8 s of noise.
    assert!(robot.tick(9_000_000, &mut sink));
    let Some((Message::Heartbeat(h), _)) = sink.frames.last() else {
        panic!("no heartbeat");
    };
    assert_eq!(h.lidar_skipped as usize, 800 * LINE_BYTES_PER_10_MS);
    assert_eq!(h.lidar_skipped, robot.lidar_stats().bytes);
}

#[test]
fn heartbeats_keep_coming_while_the_lidar_is_silent() {
    let room = room();
    let mut store = Particles::<CAP>::new();
    let view = FieldView::parse(&room.blob).unwrap();
    let mut robot =
        Robot::<CAP, BEAMS>::new(&mut store, view, None, layout(), config(), None).unwrap();
    let mut sink = Collect::default();
    let steps = (1..=800u64).map(|k| (k * 10_000, Vec::new(), Vec::new()));
    let (beats, silent) = run_clocked(&mut robot, steps, &mut sink);
    assert_periodic(&beats, 8_000_000);
    assert!(beats.len() >= 7, "{}", beats.len());
    assert_silent_after_1_s(&silent, 8_000_000);
}

#[test]
fn heartbeats_keep_their_period_while_the_lidar_sends_good_data() {
    let room = room();
    let (lidar, _) = lidar_stream(40);
    let link = paced_link(4_100_000, |t| t);
    let mut store = Particles::<CAP>::new();
    let view = FieldView::parse(&room.blob).unwrap();
    let mut robot =
        Robot::<CAP, BEAMS>::new(&mut store, view, None, layout(), config(), None).unwrap();
    let mut sink = Collect::default();
    // Board time = LiDAR time here: each LD06 frame and link frame in the step it ends in.
    let frames: Vec<(u64, &[u8])> = lidar
        .chunks(ld06::FRAME_LEN)
        .enumerate()
        .map(|(i, c)| (frame_end_us(i), c))
        .collect();
    let steps = (1..=410u64).map(|k| {
        let window = (k - 1) * 10_000..k * 10_000;
        let lidar: Vec<u8> = frames
            .iter()
            .filter(|(t, _)| window.contains(t))
            .flat_map(|(_, c)| c.iter().copied())
            .collect();
        let link: Vec<u8> = link
            .iter()
            .filter(|(t, _)| window.contains(t))
            .flat_map(|(_, b)| b.iter().copied())
            .collect();
        (k * 10_000, lidar, link)
    });
    let (beats, silent) = run_clocked(&mut robot, steps, &mut sink);
    assert_periodic(&beats, 4_100_000);
    assert_eq!(beats.len(), 4);
    // Good frames all along: never silent (the last one ends at 4 s; 100 ms later is not 1 s).
    assert!(silent.is_empty(), "{silent:?}");
    assert_eq!(estimates(&sink).len(), 39);
    for (_, _, h) in &beats {
        assert_eq!(h.lidar_skipped, 0);
        assert!(h.scans > 0);
    }
}

/// The link of [`the_link_is_read_while_the_lidar_is_silent`] paced at 50 Hz: an initial pose
/// and 4 s of odometry, each frame with its time.
fn odometry_for_4_s() -> Vec<(u64, Vec<u8>)> {
    let mut e = Encoder::new();
    let mut out = Vec::new();
    let mut t = 0;
    while t <= 4_000_000 {
        let mut bytes = frame(&mut e, odo(t, truth(t)));
        if t == 0 {
            bytes.extend(frame(&mut e, initial(truth(t), COV)));
        }
        out.push((t, bytes));
        t += 20_000;
    }
    out
}

#[test]
fn the_link_is_read_at_its_pace_while_the_lidar_sends_noise_or_nothing() {
    let room = room();
    let link = odometry_for_4_s();
    for noisy in [false, true] {
        let mut store = Particles::<CAP>::new();
        let view = FieldView::parse(&room.blob).unwrap();
        let mut robot =
            Robot::<CAP, BEAMS>::new(&mut store, view, None, layout(), config(), None).unwrap();
        let mut sink = Collect::default();
        // No call of `set_lidar_silent`: the board's clock alone tells the silence.
        // Step k ends at k · 10 ms + 1 µs: the frames stamped after the previous step's end.
        let steps = (0..=400u64).map(|k| {
            let window = (k * 10_000).saturating_sub(9_999)..k * 10_000 + 1;
            let bytes: Vec<u8> = link
                .iter()
                .filter(|(t, _)| window.contains(t))
                .flat_map(|(_, b)| b.iter().copied())
                .collect();
            let lidar = if noisy {
                noise(LINE_BYTES_PER_10_MS, k)
            } else {
                Vec::new()
            };
            (k * 10_000 + 1, lidar, bytes)
        });
        // `run_clocked` checks that every link byte is read in the step it arrives in.
        let (beats, _) = run_clocked(&mut robot, steps, &mut sink);
        assert_periodic(&beats, 4_000_001);
        let counters = robot.counters();
        assert_eq!(counters.odometry, link.len() as u32, "{counters:?}");
        let dropped = link.len() as u32 - window::WINDOW as u32;
        assert_eq!(counters.odometry_dropped, dropped, "{counters:?}");
        assert_eq!(errors(&sink), []);
        assert_eq!(beats.last().map(|b| b.2.drops), Some(dropped));
        // The LiDAR comes back: the initial pose sent during the silence is carried out.
        let (lidar, _) = lidar_stream_of(8, |_| truth(4_000_000));
        let mut ls = SliceSource::new(&lidar);
        for _ in 0..1_000 {
            if robot
                .poll(&mut ls, &mut SliceSource::new(&[]), &mut sink)
                .is_idle()
            {
                break;
            }
        }
        assert!(robot.is_initialized(), "noisy {noisy}");
        assert!(!estimates(&sink).is_empty(), "noisy {noisy}");
        assert_eq!(robot.counters().commands, 1);
    }
}
