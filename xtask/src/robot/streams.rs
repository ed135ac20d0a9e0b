//! What the robot sends the device, built from the Intel lab log: the scans as an LD06 byte
//! stream at 10 Hz, the wheel encoders at 50 Hz and the commands of the plan, in time order.

use crate::error::{Error, Result};
use beamfield::lidar::ld06::{self, Ld06Sample};
use beamfield::link::{
    Encoder, Message, SetInitialPose, SetParameters, WheelOdometry, WheelTicks, MAX_WIRE_LEN,
};
use beamfield::{wrap_angle, Pose};
use beamfield_fixtures::robot_plan::{self, BEAMS, CAPACITY, PARTICLES};
use host_tests::wheel_odometry::{Encoders, Geometry, WheelErrors};
use std::path::Path;

/// LD06 points per revolution (one per degree) and the rotation speed written into the frames
/// (3,600 °/s: the LD06's nominal 10 Hz).
const SAMPLES: usize = 360;
const SPEED_DEG_PER_S: u16 = 3_600;
const INTENSITY: u8 = 200;
/// Revolution period and odometry period, µs.
pub const REVOLUTION_US: u64 = 100_000;
pub const ODOMETRY_US: u64 = 20_000;
/// Device time of revolution k: the middle of its first and last frames' stamps (0 and 97 ms
/// after its start, the encoder's timing at 3,600 °/s), µs after the stream's start.
pub fn revolution_time_us(k: usize) -> u64 {
    k as u64 * REVOLUTION_US + 48_500
}

/// One FLASER scan of the log.
pub struct LogScan {
    pub ranges_m: Vec<f32>,
    pub pose: Pose,
}

/// The log's FLASER scans (180 beams each) with their corrected poses.
pub fn read_log(path: &Path) -> Result<Vec<LogScan>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut scans = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let mut t = line.split_whitespace();
        if t.next() != Some("FLASER") {
            continue;
        }
        let bad = || {
            Error::Host(format!(
                "{}:{}: malformed FLASER line",
                path.display(),
                i + 1
            ))
        };
        let n: usize = t.next().and_then(|v| v.parse().ok()).ok_or_else(bad)?;
        let vals: Vec<f32> = t
            .take(n + 3)
            .map(|v| v.parse().unwrap_or(f32::NAN))
            .collect();
        if n != BEAMS || vals.len() != n + 3 || vals.iter().any(|v| !v.is_finite()) {
            return Err(bad());
        }
        scans.push(LogScan {
            ranges_m: vals[..n].to_vec(),
            pose: Pose::new(vals[n], vals[n + 1], wrap_angle(vals[n + 2])),
        });
    }
    if scans.len() < 2 {
        return Err(Error::Host(format!(
            "{}: fewer than two FLASER scans",
            path.display()
        )));
    }
    Ok(scans)
}

/// What the plan does at which revolution (indices into the log).
#[derive(Clone, Copy, Debug)]
pub struct Plan {
    /// Scans of the log used (from the first).
    pub scans: usize,
    /// Revolution before which the device is told to localize globally (with all its
    /// particles), `None` for no kidnap.
    pub global_at: Option<usize>,
    /// Revolutions after `global_at` at which the initial pose puts it right.
    pub recover_after: usize,
}

/// Bad input the link carries on purpose, and what the device must answer.
#[derive(Clone, Copy, Debug, Default)]
pub struct Injected {
    /// Frames refused after their CRC passed, by code: out of order, value out of range,
    /// refused.
    pub out_of_order: u32,
    pub out_of_range: u32,
    pub refused: u32,
    /// Frames broken before the CRC check (counted, not answered).
    pub bad_crc: u32,
    /// Garbage bytes between frames.
    pub garbage: usize,
}

/// The two byte streams and what they contain.
pub struct Streams {
    pub lidar: Vec<u8>,
    pub link: Vec<u8>,
    /// Revolutions written.
    pub revolutions: usize,
    /// Wheel-tick messages written.
    pub odometry: usize,
    /// Commands written (initial poses, parameters, global localization, no-motion update).
    pub commands: usize,
    pub injected: Injected,
    /// The logged pose at each revolution's time.
    pub truth: Vec<Pose>,
}

/// The Intel beam at clockwise angle `cw_deg`: beam `i` looks at −90° + i° counter-clockwise.
fn beam_at(cw_deg: usize) -> Option<usize> {
    let i = (90 + 360 - cw_deg) % 360;
    (i < BEAMS).then_some(i)
}

/// The pose of the trajectory at `t_us`: revolution k's logged pose at its time, linear in
/// between (heading along the shorter arc), the first pose before the first time.
fn truth_at(scans: &[LogScan], t_us: u64) -> Pose {
    pose_at(scans.len(), |k| scans[k].pose, t_us)
}

/// The pose at `t_us` of a series with one pose per revolution (`n` of them, `pose(k)` the
/// k-th), linear in between, the first before the first and the last after the last.
fn pose_at(n: usize, pose: impl Fn(usize) -> Pose, t_us: u64) -> Pose {
    let t0 = revolution_time_us(0);
    if t_us <= t0 {
        return pose(0);
    }
    let k = ((t_us - t0) / REVOLUTION_US) as usize;
    if k + 1 >= n {
        return pose(n - 1);
    }
    let f = ((t_us - revolution_time_us(k)) as f64 / REVOLUTION_US as f64) as f32;
    let (a, b) = (pose(k), pose(k + 1));
    Pose::new(
        a.x_m + f * (b.x_m - a.x_m),
        a.y_m + f * (b.y_m - a.y_m),
        wrap_angle(a.theta_rad + f * wrap_angle(b.theta_rad - a.theta_rad)),
    )
}

fn covariance(sigma_xy: f32, sigma_theta: f32) -> [[f32; 3]; 3] {
    [
        [sigma_xy * sigma_xy, 0.0, 0.0],
        [0.0, sigma_xy * sigma_xy, 0.0],
        [0.0, 0.0, sigma_theta * sigma_theta],
    ]
}

/// Builds both streams for `plan` from `log`, the wheels driven with `errors` (seeded by `seed`).
/// Where the odometry comes from.
#[derive(Clone, Copy)]
pub enum Odometry<'a> {
    /// Encoder ticks of a simulated base driven along the logged poses.
    Wheels { errors: WheelErrors, seed: u64 },
    /// Recorded odometry poses, one per scan (a bag's `/odom` at each scan's stamp), sent as
    /// `WheelOdometry` interpolated to each message's time.
    Recorded(&'a [Pose]),
}

pub fn build(log: &[LogScan], plan: &Plan, odometry_source: Odometry) -> Result<Streams> {
    let scans = &log[..plan.scans.min(log.len())];
    let mut lidar = Vec::new();
    let mut rev = vec![0u8; ld06::revolution_len(SAMPLES)];
    for (k, s) in scans.iter().enumerate() {
        let samples: Vec<Ld06Sample> = (0..SAMPLES)
            .map(|cw| match beam_at(cw).map(|i| s.ranges_m[i]) {
                Some(r) if r <= 65.535 => Ld06Sample::from_range_m(r, INTENSITY),
                _ => Ld06Sample::default(),
            })
            .collect();
        let start_ms =
            (k as u64 * REVOLUTION_US / 1000 % u64::from(ld06::TIMESTAMP_WRAP_MS)) as u16;
        let n = ld06::encode_revolution(&samples, SPEED_DEG_PER_S, start_ms, &mut rev)
            .map_err(|e| Error::Host(format!("LD06 encoder: {e}")))?;
        lidar.extend_from_slice(&rev[..n]);
    }
    // One more revolution's first frame closes the last one (the assembler emits a revolution
    // when the next begins): the next revolution, the log's last scan again.
    {
        let k = scans.len();
        let start_ms =
            (k as u64 * REVOLUTION_US / 1000 % u64::from(ld06::TIMESTAMP_WRAP_MS)) as u16;
        let n = ld06::encode_revolution(
            &[Ld06Sample::default(); SAMPLES],
            SPEED_DEG_PER_S,
            start_ms,
            &mut rev,
        )
        .map_err(|e| Error::Host(format!("LD06 encoder: {e}")))?;
        lidar.extend_from_slice(&rev[..n.min(ld06::FRAME_LEN)]);
    }

    let mut enc = Encoder::new();
    let mut link = Vec::new();
    let mut wire = [0u8; MAX_WIRE_LEN];
    let mut put = |enc: &mut Encoder, link: &mut Vec<u8>, m: Message| -> Result<Vec<u8>> {
        let n = enc
            .encode(&m, &mut wire)
            .map_err(|e| Error::Host(format!("link encoder: {e}")))?;
        link.extend_from_slice(&wire[..n]);
        Ok(wire[..n].to_vec())
    };
    let w = robot_plan::WHEELS;
    let geometry = Geometry {
        left_radius_m: f64::from(w.left_radius_m),
        right_radius_m: f64::from(w.right_radius_m),
        wheelbase_m: f64::from(w.wheelbase_m),
        ticks_per_rev: w.ticks_per_rev,
    };
    let (mut wheels, recorded) = match odometry_source {
        Odometry::Wheels { errors, seed } => (Some(Encoders::new(geometry, errors, seed)), None),
        Odometry::Recorded(poses) => {
            if poses.len() < scans.len() {
                return Err(Error::Host(format!(
                    "{} odometry poses for {} scans",
                    poses.len(),
                    scans.len()
                )));
            }
            (None, Some(poses))
        }
    };
    let mut injected = Injected::default();
    let (mut odometry, mut commands) = (0usize, 0usize);
    let end_us = revolution_time_us(scans.len()) + REVOLUTION_US;
    let global_us = plan
        .global_at
        .map(|k| revolution_time_us(k) - REVOLUTION_US / 2);
    let recover_us = plan
        .global_at
        .map(|k| revolution_time_us(k + plan.recover_after) - REVOLUTION_US / 2);
    // The bad input: times (µs) at which it goes in.
    let (garbage_us, replay_us, jump_us, refused_us, crc_us) =
        (10_020_000, 20_020_000, 30_020_000, 35_020_000, 38_020_000);
    let mut previous = scans[0].pose;
    let mut last_frame = Vec::new();
    let mut t = 0u64;
    while t <= end_us {
        let now = truth_at(scans, t);
        let (ticks, [left, right]) = match (&mut wheels, recorded) {
            (Some(wheels), _) => {
                let [left, right] = if t == 0 {
                    wheels.ticks()
                } else {
                    wheels.drive(&previous, &now)
                };
                let m = Message::WheelTicks(WheelTicks {
                    // 0 would mean "on arrival" (docs/link-protocol.md): the first reading at 1 µs.
                    timestamp_us: t.max(1),
                    left_ticks: left,
                    right_ticks: right,
                });
                (m, [left, right])
            }
            (None, Some(poses)) => {
                let m = Message::WheelOdometry(WheelOdometry {
                    timestamp_us: t.max(1),
                    pose: pose_at(scans.len(), |k| poses[k], t),
                });
                (m, [0, 0])
            }
            (None, None) => return Err(Error::Host("no odometry source".into())),
        };
        previous = now;
        if t == crc_us {
            // One bit flipped in the middle of the frame: the device counts a CRC failure.
            let mut f = put(&mut enc, &mut Vec::new(), ticks)?;
            let mid = f.len() / 2;
            f[mid] ^= 0x10;
            if f[mid] == 0 {
                f[mid] = 0x10;
            }
            link.extend_from_slice(&f);
            injected.bad_crc += 1;
        } else {
            last_frame = put(&mut enc, &mut link, ticks)?;
            odometry += 1;
        }
        if t == 0 {
            put(
                &mut enc,
                &mut link,
                Message::SetInitialPose(SetInitialPose {
                    timestamp_us: 0,
                    pose: scans[0].pose,
                    covariance: covariance(0.05, 0.035),
                }),
            )?;
            commands += 1;
        }
        if Some(t) == global_us.map(|g| g - g % ODOMETRY_US) {
            put(
                &mut enc,
                &mut link,
                Message::SetParameters(SetParameters {
                    particles: Some(CAPACITY as u16),
                    ..SetParameters::default()
                }),
            )?;
            put(&mut enc, &mut link, Message::StartGlobalLocalization)?;
            commands += 2;
        }
        if Some(t) == recover_us.map(|g| g - g % ODOMETRY_US) {
            put(
                &mut enc,
                &mut link,
                Message::SetParameters(SetParameters {
                    particles: Some(PARTICLES as u16),
                    ..SetParameters::default()
                }),
            )?;
            put(
                &mut enc,
                &mut link,
                Message::SetInitialPose(SetInitialPose {
                    timestamp_us: t,
                    pose: truth_at(scans, t),
                    covariance: covariance(0.1, 0.05),
                }),
            )?;
            put(&mut enc, &mut link, Message::RequestNoMotionUpdate)?;
            commands += 3;
        }
        if t == garbage_us {
            // Line noise without a delimiter, then one to put the receiver back in step.
            let noise = [
                0x5Au8, 0xC3, 0x11, 0x7E, 0x99, 0x42, 0xF0, 0x0F, 0x33, 0x01, 0x00,
            ];
            link.extend_from_slice(&noise);
            injected.garbage += noise.len();
        }
        if t == replay_us {
            // The same frame again: same timestamp, refused as out of order.
            link.extend_from_slice(&last_frame);
            injected.out_of_order += 1;
        }
        if t == jump_us {
            // An encoder glitch: a million ticks in 20 ms.
            let glitch = if let Some(poses) = recorded {
                // A kilometre in a microsecond: valid on the link, refused by the device's
                // speed limit, as the encoder glitch is.
                let p = pose_at(scans.len(), |k| poses[k], t);
                put(
                    &mut enc,
                    &mut Vec::new(),
                    Message::WheelOdometry(WheelOdometry {
                        timestamp_us: t + 1,
                        pose: Pose::new(p.x_m + 1000.0, p.y_m, p.theta_rad),
                    }),
                )?
            } else {
                put(
                    &mut enc,
                    &mut Vec::new(),
                    Message::WheelTicks(WheelTicks {
                        timestamp_us: t + 1,
                        left_ticks: left.wrapping_add(1_000_000),
                        right_ticks: right,
                    }),
                )?
            };
            link.extend_from_slice(&glitch);
            injected.out_of_range += 1;
        }
        if t == refused_us {
            put(
                &mut enc,
                &mut link,
                Message::SetParameters(SetParameters {
                    particles: Some(CAPACITY as u16 + 1),
                    ..SetParameters::default()
                }),
            )?;
            injected.refused += 1;
        }
        t += ODOMETRY_US;
    }
    let truth = (0..scans.len()).map(|k| scans[k].pose).collect::<Vec<_>>();
    Ok(Streams {
        lidar,
        link,
        revolutions: scans.len(),
        odometry,
        commands,
        injected,
        truth,
    })
}

/// A bag's scans as the replay's (ranges, and the reference pose at each scan's stamp) and its
/// odometry at the same stamps. The firmware's beam layout is the Intel log's (180 beams from
/// −90° in 1° steps, the laser at the base's centre): a bag with other scans is refused.
pub fn read_bag(b: &super::BagInput) -> Result<(Vec<LogScan>, Vec<Pose>)> {
    use beamfield_bag::{interpolate, Bag};
    if b.topics.reference.is_none() {
        return Err(Error::Requirement(
            "--bag needs --reference-topic: the estimates are compared with it".into(),
        ));
    }
    let bag = Bag::read(&b.path, &b.topics).map_err(|e| Error::Host(format!("--bag: {e}")))?;
    let first = bag
        .scans
        .first()
        .ok_or_else(|| Error::Host(format!("--bag: no usable scan on {}", b.topics.scan)))?;
    let want_min = -std::f32::consts::FRAC_PI_2;
    let want_step = std::f32::consts::PI / BEAMS as f32;
    let fits = |s: &beamfield_bag::LaserScan| {
        s.ranges.len() == BEAMS
            && (s.angle_min - want_min).abs() < 1e-5
            && (s.angle_increment - want_step).abs() < 1e-6
    };
    if !fits(&first.value) {
        return Err(Error::Requirement(format!(
            "--bag: the firmware is built for {BEAMS} beams from -90 deg in 1 deg steps; the bag's scans have {} beams from {:.3} deg in {:.4} deg steps",
            first.value.ranges.len(),
            first.value.angle_min.to_degrees(),
            first.value.angle_increment.to_degrees()
        )));
    }
    if let Some(m) = bag.frame_pose("base_link", &first.value.frame_id) {
        if m.x.abs() > 1e-6 || m.y.abs() > 1e-6 || m.theta.abs() > 1e-6 {
            return Err(Error::Requirement(format!(
                "--bag: the laser is mounted at ({}, {}, {} rad) on base_link; the firmware's layout has it at the centre",
                m.x, m.y, m.theta
            )));
        }
    }
    let to_pose = |p: beamfield_bag::Pose2| Pose::new(p.x as f32, p.y as f32, p.theta as f32);
    let (mut log, mut odom, mut skipped) = (Vec::new(), Vec::new(), 0usize);
    for s in &bag.scans {
        let (Some(o), Some(r)) = (
            interpolate(&bag.odometry, s.stamp_ns),
            interpolate(&bag.reference, s.stamp_ns),
        ) else {
            skipped += 1;
            continue;
        };
        if !fits(&s.value) {
            skipped += 1;
            continue;
        }
        let v = &s.value;
        let ranges_m = v
            .ranges
            .iter()
            .map(|&r| {
                if r.is_finite() && r >= v.range_min && r <= v.range_max {
                    r
                } else {
                    f32::INFINITY
                }
            })
            .collect();
        log.push(LogScan {
            ranges_m,
            pose: to_pose(r),
        });
        odom.push(to_pose(o));
    }
    if log.len() < 2 {
        return Err(Error::Host(format!(
            "--bag: {} scans have odometry and a reference at their stamp ({skipped} skipped)",
            log.len()
        )));
    }
    if skipped > 0 || !bag.skipped.is_empty() {
        println!(
            "robot: from the bag, {skipped} scans skipped (no odometry or reference at their stamp, or other angles); messages skipped: {:?}",
            bag.skipped
        );
    }
    Ok((log, odom))
}
