//! `cargo xtask robot`: the host plays the robot around the firmware `robot`
//! (`firmware/src/bin/robot.rs`) on QEMU's `netduinoplus2` (STM32F405) or `b-l475e-iot01a`
//! (STM32L475, `--board`).
//!
//! 1. The Intel lab log becomes what a robot sends ([`streams`]): every scan as an LD06
//!    revolution at 10 Hz into USART1, and into USART2 the wheel encoders at 50 Hz of a
//!    differential-drive base driven along the logged trajectory with wheels that are not the
//!    ones the device believes in, plus slip (`host_tests::wheel_odometry`), the commands of the plan (an initial
//!    pose; a global localization with all the particles, then an initial pose that puts it
//!    right) and bad input on purpose (garbage, a replayed frame, an encoder glitch, a refused
//!    parameter, a broken CRC).
//! 2. The device's answers on USART3 are decoded, and the whole run is recomputed on the host
//!    with the same crate over the same bytes: every estimate must be bit for bit the host's,
//!    every error report the same. Heartbeats follow the device's clock (the host's replay
//!    sends none): they must count up, come at most [`MAX_HEARTBEAT_GAP_MS`] apart, and the
//!    last one's counters must be the host's at the end.
//! 3. The estimates are compared with the logged poses, and (feature `count`) the instruction
//!    counts of every stage give the time budget of a revolution.

pub mod bridge;
pub mod streams;

use crate::cross::build_program;
use crate::error::{Error, Result};
use crate::insncount::{qemu_args, Regions};
use crate::qemu::{ensure_qemu, run_robot, Board};
use beamfield::field::FreeSpace;
use beamfield::link::{self, ErrorCode, EstimateFlags, Message};
use beamfield::robot::{Robot, RobotCounters, Sink, SliceSource};
use beamfield::{wrap_angle, FieldView, Pose};
use beamfield_fixtures::regions::robot as regions;
use beamfield_fixtures::robot_plan::{self, baud, ring, BEAMS, CAPACITY};
use host_tests::wheel_odometry::WheelErrors;
use std::fs;
use streams::{revolution_time_us, Plan, Streams};

const BIN: &str = "robot";
const READY: &str = "robot: ready";
/// Seed of the simulated wheels' slip.
const WHEEL_SEED: u64 = 0x0d0_e7e7;
/// The kidnap: a global localization commanded before this revolution, and the initial pose
/// that puts it right this many revolutions later.
const GLOBAL_AT: usize = 400;
const RECOVER_AFTER: usize = 30;
/// Revolutions after the initial pose left out of the tracking figures while the cloud
/// settles.
const SETTLE: usize = 10;
/// QEMU's limit for the whole run, seconds (a watchdog on the emulator's wall time, not a
/// check: the results are compared bit for bit whatever the run took). On the `netduinoplus2`
/// a run takes about a minute; on QEMU 10.0.2's `b-l475e-iot01a` the firmware takes the LiDAR's
/// bytes at 1.5 to 7 KB/s, so the same run takes 3 to 15 minutes of wall time
/// (docs/robot.md, "Boards and clocks").
const TIMEOUT_S: u64 = 2700;
/// The longest gap between two of the device's heartbeats on its own clock, ms: the period
/// (`RobotConfig::heartbeat_period_us`, 1 s) with room for a busy emulator's host (QEMU's
/// guest clock follows the host's; the device's own tests hold the period to 1.5 s).
const MAX_HEARTBEAT_GAP_MS: u32 = 5_000;

/// A ROS 2 bag to send instead of the Intel log.
#[derive(Clone, Debug)]
pub struct BagInput {
    pub path: std::path::PathBuf,
    pub topics: beamfield_bag::Topics,
}

/// What `cargo xtask robot` is asked to do.
#[derive(Clone, Debug)]
pub struct Options {
    /// Scans of the log to send (all by default).
    pub scans: Option<usize>,
    /// No kidnap (no global localization, no second initial pose).
    pub no_kidnap: bool,
    /// Count instructions per stage (the time budget).
    pub count: bool,
    /// Count the receive interrupt handlers instead.
    pub isr: bool,
    /// Only the host's run (no QEMU): the streams, the recomputation and the accuracy.
    pub host_only: bool,
    /// Offer the device's link to a bridge (`bridge`): the listening socket is the second
    /// argument of [`robot`].
    pub bridge: bool,
    /// A bag's scans, odometry and reference instead of the Intel log and simulated wheels.
    pub bag: Option<BagInput>,
    /// The board (QEMU machine, memory layout, the firmware's board module).
    pub board: Board,
}

/// Frames sent by the application, in order.
#[derive(Default)]
struct Collect(Vec<Message>);

impl Sink for Collect {
    fn send(&mut self, message: &Message, _wire: &[u8]) {
        self.0.push(*message);
    }
}

fn assets() -> Result<(Vec<u8>, Vec<u8>)> {
    let dir = crate::process::repo_root().join("firmware/assets");
    let read = |name: &str| {
        let p = dir.join(name);
        fs::read(&p).map_err(|e| Error::io(&p, e))
    };
    // The blob the firmware links (feature `tiled`, see `features`).
    Ok((read("intel-tiled.bin")?, read("intel-free-space.bin")?))
}

/// The application on the host over the whole streams, as the device runs it: its frames, its
/// counters and the heartbeat it would send at the end.
fn replay(
    streams: &Streams,
    blob: &[u8],
    free: &[u8],
) -> Result<(Vec<Message>, RobotCounters, link::Heartbeat)> {
    let view = FieldView::parse(blob).map_err(|e| Error::Host(format!("intel-tiled.bin: {e}")))?;
    let free =
        FreeSpace::parse(free).map_err(|e| Error::Host(format!("intel-free-space.bin: {e}")))?;
    let layout = robot_plan::layout().map_err(|e| Error::Host(e.into()))?;
    let config = robot_plan::config().map_err(|e| Error::Host(e.to_string()))?;
    let mut store = Box::new(beamfield::mcl::Particles::<CAPACITY>::new());
    let mut robot =
        Robot::<CAPACITY, BEAMS>::new(&mut store, view, Some(free), layout, config, None)
            .map_err(|e| Error::Host(format!("robot setup: {e}")))?;
    let mut sink = Collect::default();
    let (mut lidar, mut link) = (
        SliceSource::new(&streams.lidar),
        SliceSource::new(&streams.link),
    );
    loop {
        let p = robot.poll(&mut lidar, &mut link, &mut sink);
        if p.is_idle() && lidar.is_empty() && link.is_empty() {
            break;
        }
    }
    Ok((sink.0, robot.counters(), robot.heartbeat()))
}

/// What follows from the byte streams alone, one line per frame (estimates as bit patterns).
fn deterministic(m: &Message) -> String {
    match m {
        Message::Estimate(e) => format!(
            "estimate t={} x={:08x} y={:08x} th={:08x} ess={:08x} flags={:04x} cov={:08x?} odom={:08x}/{:08x}/{:08x} quality={:?}/{:08x}",
            e.timestamp_us,
            e.pose.x_m.to_bits(),
            e.pose.y_m.to_bits(),
            e.pose.theta_rad.to_bits(),
            e.ess.to_bits(),
            e.flags.bits(),
            e.covariance.map(|r| r.map(f32::to_bits)),
            e.odometry.x_m.to_bits(),
            e.odometry.y_m.to_bits(),
            e.odometry.theta_rad.to_bits(),
            e.quality.state,
            e.quality.score.to_bits(),
        ),
        other => format!("{other:?}"),
    }
}

/// The device's frames from USART3's bytes.
fn decode_device(bytes: &[u8]) -> Result<Vec<Message>> {
    let mut d = link::Decoder::new();
    let mut out = Vec::new();
    let mut bad = Vec::new();
    d.feed(bytes, |f| match f {
        Ok(f) => out.push(f.message),
        Err(e) => bad.push(e),
    });
    if let Some(e) = bad.first() {
        return Err(Error::Mismatch(format!(
            "USART3 carried {} frames the host's decoder refuses (first: {e})",
            bad.len()
        )));
    }
    Ok(out)
}

fn errors_of(frames: &[Message]) -> Vec<ErrorCode> {
    frames
        .iter()
        .filter_map(|m| match m {
            Message::Error(r) => Some(r.code),
            _ => None,
        })
        .collect()
}

struct Accuracy {
    scored: usize,
    rmse_m: f64,
    rmse_deg: f64,
    within: f64,
    max_m: f64,
    lost_at: Option<usize>,
    /// During the kidnap: the error at the last revolution before the initial pose, m, and
    /// whether that estimate was still flagged as a global localization; and the error at the
    /// first revolution after it, m.
    kidnap: Option<(f64, bool, f64)>,
}

/// Tracking error of the estimates against the logged poses, leaving out the revolutions of
/// the kidnap (from the global localization to `SETTLE` after the initial pose).
fn accuracy(frames: &[Message], s: &Streams, plan: &Plan) -> Accuracy {
    let skip = |k: usize| {
        plan.global_at
            .is_some_and(|g| k >= g && k < g + plan.recover_after + SETTLE)
    };
    let (mut se_t, mut se_h, mut n, mut within, mut max_m) = (0.0, 0.0, 0usize, 0usize, 0.0f64);
    let mut lost_at = None;
    let (mut before, mut after) = (None, None);
    for m in frames {
        let Message::Estimate(e) = m else { continue };
        let k = ((e.timestamp_us - revolution_time_us(0)) / streams::REVOLUTION_US) as usize;
        if let (Some(g), Some(p)) = (plan.global_at, s.truth.get(k)) {
            let d = f64::from(e.pose.x_m - p.x_m).hypot(f64::from(e.pose.y_m - p.y_m));
            if k + 1 == g + plan.recover_after {
                before = Some((d, e.flags.contains(EstimateFlags::GLOBAL_LOCALIZATION)));
            }
            if k == g + plan.recover_after {
                after = Some(d);
            }
        }
        if skip(k) || k >= s.truth.len() {
            continue;
        }
        let p: Pose = s.truth[k];
        let d = f64::from(e.pose.x_m - p.x_m).hypot(f64::from(e.pose.y_m - p.y_m));
        let h = f64::from(wrap_angle(e.pose.theta_rad - p.theta_rad))
            .abs()
            .to_degrees();
        se_t += d * d;
        se_h += h * h;
        n += 1;
        within += usize::from(d <= 0.10 && h <= 2.0);
        max_m = max_m.max(d);
        if d > 1.0 && lost_at.is_none() {
            lost_at = Some(k);
        }
    }
    let nn = n.max(1) as f64;
    Accuracy {
        scored: n,
        rmse_m: (se_t / nn).sqrt(),
        rmse_deg: (se_h / nn).sqrt(),
        within: within as f64 / nn,
        max_m,
        lost_at,
        kidnap: before.zip(after).map(|((b, f), a)| (b, f, a)),
    }
}

/// Runs the task; with `opts.bridge`, the bridge connects to `listener`.
pub fn robot(opts: Options, listener: Option<&std::net::TcpListener>) -> Result {
    let (log, recorded) = match &opts.bag {
        Some(b) => {
            let (log, odom) = streams::read_bag(b)?;
            (log, Some(odom))
        }
        None => {
            let log_path = host_tests::data_dir().join("laser_intel_lab/intel-corrected.log");
            (streams::read_log(&log_path)?, None)
        }
    };
    let scans = opts.scans.unwrap_or(log.len()).clamp(2, log.len());
    let kidnap = !opts.no_kidnap && scans > GLOBAL_AT + RECOVER_AFTER + SETTLE;
    let plan = Plan {
        scans,
        global_at: kidnap.then_some(GLOBAL_AT),
        recover_after: RECOVER_AFTER,
    };
    let source = match &recorded {
        Some(poses) => streams::Odometry::Recorded(poses),
        None => streams::Odometry::Wheels {
            errors: WheelErrors::TYPICAL,
            seed: WHEEL_SEED,
        },
    };
    let mut s = streams::build(&log, &plan, source)?;
    let w = WheelErrors::TYPICAL;
    if let Some(b) = &opts.bag {
        println!(
            "robot: {} scans of {} (reference {}) as {} LD06 revolutions at 10 Hz ({} bytes into USART1); its {} as {} WheelOdometry messages at 50 Hz, {} commands, and bad input ({} garbage bytes, {} replayed frame, {} odometry jump, {} refused parameter, {} broken CRC): {} bytes into USART2",
            scans,
            b.path.display(),
            b.topics.reference.as_deref().unwrap_or("?"),
            s.revolutions,
            s.lidar.len(),
            b.topics.odom,
            s.odometry,
            s.commands,
            s.injected.garbage,
            s.injected.out_of_order,
            s.injected.out_of_range,
            s.injected.refused,
            s.injected.bad_crc,
            s.link.len()
        );
    } else {
        println!(
        "robot: {} Intel scans as {} LD06 revolutions at 10 Hz ({} bytes into USART1); {} wheel-tick messages at 50 Hz from a differential drive with left/right radii x{}/x{}, wheelbase x{} of what the device believes, {} % slip per step and a {} % slip one step in {}, {} commands{}, and bad input ({} garbage bytes, {} replayed frame, {} encoder glitch, {} refused parameter, {} broken CRC): {} bytes into USART2",
        scans,
        s.revolutions,
        s.lidar.len(),
        s.odometry,
        w.left_radius_scale,
        w.right_radius_scale,
        w.wheelbase_scale,
        w.slip_sigma * 100.0,
        w.hard_slip.map_or(0.0, |h| h.loss * 100.0),
        w.hard_slip.map_or(0.0, |h| (1.0 / h.p).round()),
        s.commands,
        match plan.global_at {
            Some(g) => format!(
                " (initial pose; global localization with {CAPACITY} particles at revolution {g}, the initial pose that puts it right {RECOVER_AFTER} later)"
            ),
            None => " (initial pose)".into(),
        },
        s.injected.garbage,
        s.injected.out_of_order,
        s.injected.out_of_range,
        s.injected.refused,
        s.injected.bad_crc,
        s.link.len()
    );
    }
    let (blob, free) = assets()?;
    // With a bridge, the device runs first: what reaches USART2 is known only afterwards, and
    // the host replays exactly that.
    let mut device = None;
    let mut bridged_from_us = None;
    if let (true, Some(listener)) = (opts.bridge, listener) {
        // Built before the bridge is waited for: then the run starts as soon as it connects.
        build_program(opts.board, BIN, &features(&opts))?;
        let conn = bridge::accept(listener)?;
        let (d, written) = run_device(&opts, &s, Some(conn))?;
        println!(
            "bridge: {} frames from the bridge went into USART2 ({} bytes in all){}",
            written.bridge_frames,
            written.bytes.len(),
            match written.first_bridge_at_us {
                Some(t) => format!(
                    ", the first at the replay's {:.3} s: estimates from then on are not scored",
                    t as f64 * 1e-6
                ),
                None => String::new(),
            }
        );
        bridged_from_us = written.first_bridge_at_us;
        s.link = written.bytes;
        device = Some(d);
    }
    let (host, host_counters, host_heartbeat) = replay(&s, &blob, &free)?;
    let host_estimates = host
        .iter()
        .filter(|m| matches!(m, Message::Estimate(_)))
        .count();
    let want_errors: Vec<ErrorCode> = std::iter::empty()
        .chain(std::iter::repeat_n(
            ErrorCode::OutOfOrder,
            s.injected.out_of_order as usize,
        ))
        .chain(std::iter::repeat_n(
            ErrorCode::ValueOutOfRange,
            s.injected.out_of_range as usize,
        ))
        .chain(std::iter::repeat_n(
            ErrorCode::Refused,
            s.injected.refused as usize,
        ))
        .collect();
    if !opts.bridge && errors_of(&host) != want_errors {
        let got: Vec<&Message> = host
            .iter()
            .filter(|m| matches!(m, Message::Error(_)))
            .collect();
        return Err(Error::Requirement(format!(
            "the plan's bad input must be answered {want_errors:?}; the application answered {} error reports (first ten: {:?})",
            got.len(),
            &got[..got.len().min(10)]
        )));
    }
    if host_counters.late_odometry != 0 {
        return Err(Error::Requirement(format!(
            "the host's replay had {} revolutions with late odometry: the streams are out of step",
            host_counters.late_odometry
        )));
    }
    println!(
        "host replay: {} revolutions, {} updates ({} skipped), {} estimates, {} error reports ({:?}), odometry {} accepted",
        host_counters.revolutions,
        host_counters.updates,
        host_counters.skipped,
        host_estimates,
        want_errors.len(),
        want_errors,
        host_counters.odometry,
    );

    let frames = if opts.host_only {
        host.clone()
    } else {
        let device = match device {
            Some(d) => d,
            None => run_device(&opts, &s, None)?.0,
        };
        compare(&host, &device, opts.bridge)?;
        heartbeats(&device, &host_heartbeat)?;
        device
    };
    // Estimates after the bridge's first command answer that command, not the plan.
    let scored: Vec<Message> = frames
        .iter()
        .filter(|m| match (m, bridged_from_us) {
            (Message::Estimate(e), Some(t)) => e.timestamp_us < t,
            _ => true,
        })
        .copied()
        .collect();
    let a = accuracy(&scored, &s, &plan);
    let flagged_global = frames
        .iter()
        .filter(|m| matches!(m, Message::Estimate(e) if e.flags.contains(EstimateFlags::GLOBAL_LOCALIZATION)))
        .count();
    println!(
        "accuracy against the logged poses ({} estimates{}): RMSE {:.2} cm, {:.3} deg; within 10 cm and 2 deg {:.1} %; largest error {:.3} m; {}",
        a.scored,
        if kidnap {
            format!(
                ", leaving out the {} revolutions from the global localization to {SETTLE} after the initial pose; {flagged_global} estimates flagged global localization",
                RECOVER_AFTER + SETTLE
            )
        } else {
            String::new()
        },
        a.rmse_m * 100.0,
        a.rmse_deg,
        a.within * 100.0,
        a.max_m,
        match a.lost_at {
            Some(k) => format!("LOST (error over 1 m) from revolution {k}"),
            None => "never lost".into(),
        }
    );
    if let (Some(g), Some((before, flagged, after))) = (plan.global_at, a.kidnap) {
        println!(
            "kidnap: the global localization from revolution {g} with {CAPACITY} particles was {before:.2} m off {RECOVER_AFTER} revolutions later ({}); the initial pose sent then put the estimate {:.1} cm from the logged pose at the next revolution",
            if flagged { "still flagged global localization" } else { "narrowed to one place, no longer flagged: not a correctness signal" },
            after * 100.0
        );
    }
    if a.lost_at.is_some() {
        return Err(Error::Requirement("the device lost the robot".into()));
    }
    Ok(())
}

/// The firmware's features for `opts`.
fn features(opts: &Options) -> Vec<&'static str> {
    // The Intel map tiled: 297,640 bytes of flash in place of 781,063, the same distances.
    let mut features = vec!["emulator", "tiled"];
    features.extend(opts.board.robot_feature());
    if opts.count {
        features.push("count");
    }
    if opts.isr {
        features.push("count-isr");
    }
    features
}

fn run_device(
    opts: &Options,
    s: &Streams,
    bridge: Option<std::net::TcpStream>,
) -> Result<(Vec<Message>, bridge::Written)> {
    ensure_qemu()?;
    let elf = build_program(opts.board, BIN, &features(opts))?;
    image_size(opts.board, &elf)?;
    let extra = if opts.count || opts.isr {
        qemu_args(&elf, ", or run `cargo xtask robot` without --count")?
    } else {
        Vec::new()
    };
    let run = run_robot(
        crate::qemu::Firmware {
            board: opts.board,
            elf: &elf,
            ready: READY,
        },
        &s.lidar,
        &s.link,
        &extra,
        TIMEOUT_S,
        bridge,
    )?;
    let out = &run.finished;
    for l in out.stdout.lines().filter(|l| l.starts_with("robot: ")) {
        println!("device {l}");
    }
    if out.code != 0 {
        eprint!("{}", out.stderr);
        return Err(crate::qemu::failure(
            out.code,
            "`robot`",
            opts.board.machine(),
            "see its output",
        ));
    }
    let device = decode_device(&run.usart3)?;
    println!(
        "link out: {} bytes on USART3, {} frames ({} estimates, {} heartbeats, {} error reports), {:.1} s in QEMU",
        run.usart3.len(),
        device.len(),
        device.iter().filter(|m| matches!(m, Message::Estimate(_))).count(),
        device.iter().filter(|m| matches!(m, Message::Heartbeat(_))).count(),
        device.iter().filter(|m| matches!(m, Message::Error(_))).count(),
        run.elapsed.as_secs_f64()
    );
    if opts.count {
        budget(&Regions::read(&out.stdout, &out.stderr)?, s, opts.board)?;
    }
    if opts.isr {
        isr(&out.stderr, s)?;
    }
    Ok((device, run.usart2))
}

/// Highest share of the board's flash the image may take: room for the next map.
const FLASH_LIMIT: f64 = 0.85;

/// The image's flash and RAM against the board's memory layout; fails above [`FLASH_LIMIT`].
fn image_size(board: Board, elf: &std::path::Path) -> Result {
    use crate::elf::{gsec, region_length, sections};
    let m = sections(&crate::toolchain::llvm_tool("llvm-size")?, elf)?;
    let layout_path = board.memory_x();
    let layout = fs::read_to_string(&layout_path).map_err(|e| Error::io(&layout_path, e))?;
    let (flash_len, ram_len) = (
        region_length(&layout, "FLASH")?,
        region_length(&layout, "RAM")?,
    );
    let flash = gsec(&m, &[".vector_table", ".text", ".rodata", ".data"]);
    let ram = gsec(&m, &[".data", ".bss", ".uninit"]);
    println!(
        "image ({}): flash {flash} B of {flash_len} ({:.1} %; .text {}, .rodata {}), RAM {ram} B of {ram_len} ({:.1} %; the rest is stack)",
        board.machine(),
        flash as f64 / flash_len as f64 * 100.0,
        gsec(&m, &[".text"]),
        gsec(&m, &[".rodata"]),
        ram as f64 / ram_len as f64 * 100.0,
    );
    if flash as f64 > FLASH_LIMIT * flash_len as f64 {
        return Err(Error::Requirement(format!(
            "the image takes {flash} B, over {:.0} % of the board's {flash_len} B of flash",
            FLASH_LIMIT * 100.0
        )));
    }
    Ok(())
}

/// Every estimate and error report equal, in order; heartbeats (on the device's clock, none
/// from the host) left out.
/// With `by_kind`, estimates and error reports are compared as two sequences: when the link's
/// bytes arrive paced (a bridge), an error report, sent as its frame arrives, may come before
/// or after an estimate on the device and in the host's replay.
fn compare(host: &[Message], device: &[Message], by_kind: bool) -> Result {
    let kind = |m: &Message| match m {
        Message::Estimate(_) => 0,
        Message::Error(_) => 1,
        _ => 2,
    };
    let pick = |v: &[Message], kinds: &[u8]| -> Vec<Message> {
        v.iter()
            .filter(|m| kinds.contains(&kind(m)))
            .copied()
            .collect()
    };
    if by_kind {
        for k in [0, 1] {
            same_frames(&pick(host, &[k]), &pick(device, &[k]))?;
        }
    } else {
        same_frames(&pick(host, &[0, 1]), &pick(device, &[0, 1]))?;
    }
    let estimates = host.iter().filter(|m| kind(m) == 0).count();
    let errors = host.iter().filter(|m| kind(m) == 1).count();
    println!(
        "device = host: all {estimates} estimates bit for bit (time, pose, covariance, ESS, flags, odometry, quality), all {errors} error reports{}",
        if by_kind { " (each kind in order)" } else { "" }
    );
    Ok(())
}

/// `device` is `host` frame for frame.
fn same_frames(host: &[Message], device: &[Message]) -> Result {
    let h: Vec<String> = host.iter().map(deterministic).collect();
    let d: Vec<String> = device.iter().map(deterministic).collect();
    if let Some(i) = (0..h.len().max(d.len())).find(|&i| d.get(i) != h.get(i)) {
        return Err(Error::Mismatch(format!(
            "frame {i} differs: the host computed\n  {}\nthe device sent\n  {}",
            h.get(i).map_or("(nothing)", String::as_str),
            d.get(i).map_or("(nothing)", String::as_str)
        )));
    }
    Ok(())
}

/// The device's heartbeats: at least one, none more than [`MAX_HEARTBEAT_GAP_MS`] after the
/// last on its clock, every counter counting up, and the last one's counters (all but the
/// uptime) those of the host's replay at the end (the device sends heartbeats while its lines
/// are silent before it ends).
fn heartbeats(device: &[Message], host_end: &link::Heartbeat) -> Result {
    let beats: Vec<link::Heartbeat> = device
        .iter()
        .filter_map(|m| match m {
            Message::Heartbeat(h) => Some(*h),
            _ => None,
        })
        .collect();
    let Some(last) = beats.last() else {
        return Err(Error::Mismatch("the device sent no heartbeat".into()));
    };
    let counters = |h: &link::Heartbeat| {
        [
            h.bytes,
            h.frames,
            h.checksum_failures,
            h.scans,
            h.updates,
            h.odometry,
            h.drops,
            h.link_errors,
            h.lidar_skipped,
            h.encode_failures,
            h.refused,
        ]
    };
    let mut longest = 0u32;
    for w in beats.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        let gap = b.uptime_ms.wrapping_sub(a.uptime_ms);
        longest = longest.max(gap);
        let back = counters(a).iter().zip(counters(b)).any(|(x, y)| y < *x);
        if back || b.timestamp_us < a.timestamp_us || gap == 0 {
            return Err(Error::Mismatch(format!(
                "the device's heartbeats went back: {a:?} then {b:?}"
            )));
        }
    }
    if longest > MAX_HEARTBEAT_GAP_MS {
        return Err(Error::Requirement(format!(
            "the device's heartbeats came up to {longest} ms apart on its clock (at most {MAX_HEARTBEAT_GAP_MS})"
        )));
    }
    let want = link::Heartbeat {
        uptime_ms: last.uptime_ms,
        ..*host_end
    };
    if *last != want {
        return Err(Error::Mismatch(format!(
            "the device's last heartbeat is\n  {last:?}\nthe host's replay ends at\n  {want:?}"
        )));
    }
    println!(
        "heartbeats: {} on the device's clock, up to {longest} ms apart; the last one's counters are the host's at the end ({} scans, {} updates, {} odometry, {} refused, {} LiDAR bytes skipped, {} not encodable)",
        beats.len(),
        last.scans,
        last.updates,
        last.odometry,
        last.refused,
        last.lidar_skipped,
        last.encode_failures
    );
    Ok(())
}

/// Instructions per revolution by stage against 100 ms at the board's core clock.
fn budget(r: &Regions, s: &Streams, board: Board) -> Result {
    r.expect(&regions::ALL)?;
    let revs = s.revolutions as f64;
    let core_hz = board.core_hz() as f64;
    let mhz = core_hz / 1e6;
    let budget = core_hz * 0.1;
    println!("time budget (QEMU plugin, exact counts; {mhz:.0} MHz at 1 cycle per instruction, so {:.1} M instructions per 100 ms revolution):", budget / 1e6);
    let mut total = 0.0;
    let rows = [
        (regions::LIDAR, s.lidar.len() as f64, "byte"),
        (regions::LINK, s.link.len() as f64, "byte"),
        (regions::PREDICT, revs, "revolution"),
        (regions::UPDATE, revs, "revolution"),
        (regions::SEND, revs, "revolution"),
    ];
    for (region, per, unit) in rows {
        let (sum, times) = r.sum(region.name);
        let per_rev = sum as f64 / revs;
        total += per_rev;
        println!(
            "  {:<28} {:>12} in {:>6} regions: {:>9.1} per {unit}, {:>10.0} per revolution ({:.2} % of the budget), longest region {}",
            region.what,
            sum,
            times,
            sum as f64 / per,
            per_rev,
            per_rev / budget * 100.0,
            r.max(region.name)
        );
    }
    println!(
        "  total {:.0} instructions per revolution on average = {:.2} ms at {mhz:.0} MHz ({:.1} % of 100 ms)",
        total,
        total / core_hz * 1e3,
        total / budget * 100.0
    );
    let (update, _) = r.sum(regions::UPDATE.name);
    println!(
        "  update per particle: {:.0} instructions on average ({} particles, {BEAMS} beams); the longest update (the global localization's {CAPACITY} particles) {:.0} per particle",
        update as f64 / revs / robot_plan::PARTICLES as f64,
        robot_plan::PARTICLES,
        r.max(regions::UPDATE.name) as f64 / CAPACITY as f64
    );
    // The longest update, and what the LiDAR's line brings meanwhile.
    let longest = r.max(regions::UPDATE.name) + r.max(regions::PREDICT.name);
    let line_bytes_per_s = f64::from(baud::LIDAR) / 10.0;
    let arrive = longest as f64 / core_hz * line_bytes_per_s;
    println!(
        "  the longest predict + update ({} instructions, {:.2} ms) lets {:.0} bytes arrive at {} baud (8N1, the line full); the ring holds {} bytes",
        longest,
        longest as f64 / core_hz * 1e3,
        arrive,
        baud::LIDAR,
        ring::LIDAR
    );
    if arrive >= ring::LIDAR as f64 {
        return Err(Error::Requirement(format!(
            "the LiDAR ring ({} bytes) is smaller than what arrives during the longest update ({arrive:.0} bytes)",
            ring::LIDAR
        )));
    }
    Ok(())
}

/// The receive handlers' counts (feature `count-isr`: every run of a handler is a region).
fn isr(stderr: &str, s: &Streams) -> Result {
    let counts = crate::insncount::region_counts(stderr);
    if counts.is_empty() {
        return Err(Error::Output(
            "the plugin counted no interrupt handler".into(),
        ));
    }
    let max = counts.iter().max().copied().unwrap_or(0);
    let sum: u64 = counts.iter().sum();
    let bytes = (s.lidar.len() + s.link.len()) as f64;
    println!(
        "receive interrupt handlers: {} runs for {} bytes, {:.1} instructions per run on average, longest {} (plus the exception entry and return, done by the hardware: 12 cycles each on a Cortex-M4)",
        counts.len(),
        bytes,
        sum as f64 / counts.len() as f64,
        max
    );
    Ok(())
}
