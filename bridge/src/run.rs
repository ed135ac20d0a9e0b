//! The bridge's loop: the device's frames out to ROS 2, ROS 2's requests in to the device,
//! until the link ends (or `--seconds`, a lifecycle shutdown, SIGINT or SIGTERM), then one
//! report and an exit code ([`BridgeReport::exit_code`], [`BridgeError::exit_code`]).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use beamfield::link::{EstimateFlags, Heartbeat, Message};
use ros2_client::ServiceMapping;
use serde::Serialize;

use crate::clock::{ClockCounters, DeviceClock, HostClock};
use crate::convert::{self, Refused};
use crate::lifecycle::State as LifecycleState;
use crate::msg::{TfMessage, Time};
use crate::outbox::{self, Outbox, OutboxCounters};
use crate::params::{Nav2Params, ParamsError};
use crate::port::{now_ns, Endpoint, Incoming, Port, PortError};
use crate::repeat::Repeater;
use crate::ros::{NodeConfig, RosError, RosNode, ServiceCall};
use crate::stop::Stop;

/// Exit code: the bridge stopped as asked: `--seconds` passed, a lifecycle `shutdown`, or
/// SIGINT or SIGTERM (a requested stop is not a failure: a supervisor must not restart it).
pub const EXIT_STOPPED: u8 = 0;
/// Exit code: the bridge could not start (the link, the DDS participant, the params file).
pub const EXIT_CANNOT_START: u8 = 1;
/// Exit code: a usage error (an option's value).
pub const EXIT_USAGE: u8 = 2;
/// Exit code: the link ended (end of stream, a read or write error, a serial hang-up).
pub const EXIT_LINK_LOST: u8 = 3;

/// How long the bridge goes on after a lifecycle `shutdown` before it ends: the answer to the
/// request travels on a reliable writer that ends with the node.
pub const FINALIZED_LINGER: Duration = Duration::from_millis(500);

/// Examples of refused frames kept in the report (the counts by kind cover all of them).
pub const REFUSED_EXAMPLES: usize = 8;

/// `--seconds`: a positive number of seconds (`inf`, or more than a `Duration` holds: no
/// limit).
pub fn parse_seconds(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a number of seconds"))?;
    if v.is_nan() || v <= 0.0 {
        return Err(format!("{s}: a positive number of seconds"));
    }
    Ok(v)
}

/// Which RMW the ROS 2 peers use: it decides how services map onto DDS.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Rmw {
    /// rmw_fastrtps_cpp (ROS 2's default RMW): the "enhanced" RPC-over-DDS mapping.
    Fastrtps,
    /// rmw_cyclonedds_cpp: Cyclone DDS's request headers.
    Cyclonedds,
}

/// How device time becomes ROS time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ClockArg {
    /// The computer's clock: device time plus the smallest offset over a sliding window,
    /// re-anchored on a confirmed jump (see `clock::HostClock`).
    Host,
    /// The device's clock (µs since it started), as it is until the device restarts or its
    /// clock jumps, then continued without going back or jumping (see `clock::DeviceClock`):
    /// for replays with `use_sim_time`.
    Device,
}

/// `beamfield bridge`: the device's link to ROS 2, as nav2_amcl.
#[derive(Clone, Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("link").required(true).args(["connect", "serial"])))]
pub struct BridgeArgs {
    /// The device's link over TCP, HOST:PORT (an emulator: `cargo xtask robot --bridge-port`).
    #[arg(long, value_name = "HOST:PORT")]
    pub connect: Option<String>,
    /// The device's link on a serial port (e.g. /dev/ttyUSB0).
    #[arg(long, value_name = "PATH")]
    pub serial: Option<String>,
    /// The serial port's baud rate.
    #[arg(long, default_value_t = 230_400)]
    pub baud: u32,
    /// A nav2 params file: its `amcl` parameters with a counterpart are applied (frames,
    /// transform_tolerance, max_particles, alpha1–4, initial pose); the rest are listed.
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// The node's namespace (nav2's multi-robot launch: `robot1`): the node is `NS/amcl`, its
    /// topics and services `NS/amcl_pose` and so on (`/tf` stays `/tf`), and the params file's
    /// section for `NS/amcl` is read.
    #[arg(long, value_name = "NS", default_value = "/")]
    pub namespace: String,
    /// Start unconfigured and publish only once activated through the lifecycle services
    /// (`amcl/change_state`: nav2's lifecycle manager). Without it the node starts active.
    #[arg(long)]
    pub lifecycle: bool,
    /// The DDS domain (ROS_DOMAIN_ID).
    #[arg(long, env = "ROS_DOMAIN_ID", default_value_t = 0)]
    pub domain_id: u16,
    /// Use 127.0.0.1 only (no multicast on other interfaces; same-host peers by unicast).
    #[arg(long)]
    pub loopback_only: bool,
    /// The RMW of the ROS 2 side (how services are mapped).
    #[arg(long, value_enum, default_value_t = Rmw::Fastrtps)]
    pub rmw: Rmw,
    /// How device time becomes the messages' stamps.
    #[arg(long, value_enum, default_value_t = ClockArg::Host)]
    pub clock: ClockArg,
    /// Stop after this many seconds (default: when the link ends). More than the computer's
    /// clock holds, or `inf`, is no limit.
    #[arg(long, value_name = "S", value_parser = parse_seconds)]
    pub seconds: Option<f64>,
}

/// What the bridge did.
#[derive(Clone, Debug, Default, Serialize)]
pub struct BridgeReport {
    pub link: String,
    /// The node's fully qualified name (`/amcl`, `/robot1/amcl`).
    pub node: String,
    /// nav2_amcl's parameters applied as nav2_amcl applies them.
    pub applied: BTreeMap<String, String>,
    /// nav2_amcl's parameters applied in another form, and how.
    pub adapted: BTreeMap<String, String>,
    /// Parameters not applied, and why (unknown names included).
    pub ignored: BTreeMap<String, String>,
    /// Estimates published on `amcl_pose`.
    pub poses: u64,
    /// Transforms published on `/tf` (for estimates and re-sent).
    pub transforms: u64,
    /// Transforms re-sent while no estimate came ([`crate::repeat`]), offered to `/tf`.
    pub transforms_repeated: u64,
    /// Estimates not published: the filter was not initialized.
    pub uninitialized: u64,
    /// Estimates not published: the node was not active (`--lifecycle`).
    pub not_active: u64,
    /// Lifecycle transitions made on request, in order (`unconfigured -> inactive`).
    pub lifecycle_transitions: Vec<String>,
    /// The lifecycle state at the end.
    pub lifecycle_state: String,
    pub heartbeats: u64,
    /// Frames the decoder refused (CRC, length, range …) and messages the bridge does not
    /// take, counted by kind.
    pub link_refused: BTreeMap<String, u64>,
    /// The first [`REFUSED_EXAMPLES`] of them, in full.
    pub link_refused_examples: Vec<String>,
    /// Link items dropped because the bridge's loop fell [`crate::queue::LINK_QUEUE_CAPACITY`]
    /// items behind the link (the oldest go first).
    pub link_queue_dropped: u64,
    /// What the clock model did (re-anchoring, refused stamps), with `--clock host` or
    /// `--clock device`.
    pub clock: Option<ClockCounters>,
    /// `--clock device`: what was added to the device's time to make the last stamps, ns (0
    /// unless the device restarted or its clock jumped; saturating at the i64 range).
    pub device_clock_shift_ns: Option<i64>,
    /// `amcl_pose`'s outbox: published, retried on a full window, superseded (by a newer
    /// estimate while held back: a full window, or less than [`outbox::MIN_INTERVAL`] since the
    /// last), failed.
    pub amcl_pose_outbox: OutboxCounters,
    /// `/tf`'s outbox.
    pub tf_outbox: OutboxCounters,
    /// Error reports from the device, by code.
    pub device_errors: BTreeMap<String, u64>,
    pub initial_poses_sent: u64,
    /// `initialpose` messages not sent, by cause.
    pub initial_poses_refused: BTreeMap<String, u64>,
    pub global_localizations: u64,
    pub nomotion_updates: u64,
    /// Frames sent to the device.
    pub frames_sent: u64,
    /// The last heartbeat's counters.
    pub last_heartbeat: Option<HeartbeatCounters>,
    pub seconds: f64,
    /// Why the bridge stopped.
    pub ended: String,
    /// The process's exit code for this end ([`EXIT_STOPPED`] or [`EXIT_LINK_LOST`]).
    pub exit_code: u8,
}

impl BridgeReport {
    /// The exit code a supervisor sees: [`EXIT_STOPPED`] after `--seconds`, a lifecycle
    /// shutdown, SIGINT or SIGTERM; [`EXIT_LINK_LOST`] when the link ended.
    pub fn exit_code(&self) -> u8 {
        self.exit_code
    }

    fn refuse(&mut self, kind: String, example: impl FnOnce() -> String) {
        *self.link_refused.entry(kind).or_default() += 1;
        if self.link_refused_examples.len() < REFUSED_EXAMPLES {
            self.link_refused_examples.push(example());
        }
    }
}

/// A refusal's kind: its Debug name without the fields (`WrongLength { .. }` → `WrongLength`).
fn kind_of(debug: &str) -> String {
    debug
        .split(['(', '{', ' '])
        .next()
        .unwrap_or("")
        .trim()
        .to_owned()
}

/// A heartbeat, for the report.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct HeartbeatCounters {
    pub timestamp_us: u64,
    pub bytes: u32,
    pub frames: u32,
    pub scans: u32,
    pub updates: u32,
    pub drops: u32,
    pub link_errors: u32,
    /// LiDAR bytes the device's decoder skipped (noise, a wrong baud rate).
    pub lidar_skipped: u32,
    /// Frames the device could not encode (never sent).
    pub encode_failures: u32,
    /// Frames the device refused after their CRC passed.
    pub refused: u32,
    /// The device's own clock, ms since it started (wrapping).
    pub uptime_ms: u32,
}

impl From<Heartbeat> for HeartbeatCounters {
    fn from(h: Heartbeat) -> Self {
        Self {
            timestamp_us: h.timestamp_us,
            bytes: h.bytes,
            frames: h.frames,
            scans: h.scans,
            updates: h.updates,
            drops: h.drops,
            link_errors: h.link_errors,
            lidar_skipped: h.lidar_skipped,
            encode_failures: h.encode_failures,
            refused: h.refused,
            uptime_ms: h.uptime_ms,
        }
    }
}

/// What to tell the user when the device's LiDAR sends bytes its decoder skips and no scan
/// between two heartbeats (noise: a wrong baud rate, a loose wire); `None` otherwise.
fn lidar_noise(last: Option<&HeartbeatCounters>, now: &Heartbeat) -> Option<String> {
    let last = last?;
    let skipped = now.lidar_skipped.wrapping_sub(last.lidar_skipped);
    (skipped > 0 && now.scans == last.scans).then(|| {
        format!(
            "the device's LiDAR sent {skipped} bytes its decoder skipped and no scan since the last heartbeat (a wrong baud rate or a noisy line?)"
        )
    })
}

impl std::fmt::Display for BridgeReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "bridge: {} for {:.1} s, ended: {} (exit code {})",
            self.link, self.seconds, self.ended, self.exit_code
        )?;
        writeln!(
            f,
            "published: {} poses on amcl_pose, {} transforms on /tf ({} of them re-sent between estimates; {} estimates before initialization not published)",
            self.poses, self.transforms, self.transforms_repeated, self.uninitialized
        )?;
        writeln!(
            f,
            "lifecycle: {} at the end, {} estimates while not active; transitions: {}",
            self.lifecycle_state,
            self.not_active,
            if self.lifecycle_transitions.is_empty() {
                "none".to_owned()
            } else {
                self.lifecycle_transitions.join(", ")
            }
        )?;
        writeln!(
            f,
            "to the device: {} frames ({} initial poses, {} global localizations, {} no-motion updates)",
            self.frames_sent, self.initial_poses_sent, self.global_localizations, self.nomotion_updates
        )?;
        let list = |m: &BTreeMap<String, u64>| {
            if m.is_empty() {
                "none".to_owned()
            } else {
                m.iter()
                    .map(|(k, v)| format!("{v} {k}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            }
        };
        writeln!(
            f,
            "initialpose refused: {}",
            list(&self.initial_poses_refused)
        )?;
        writeln!(f, "link frames refused: {}", list(&self.link_refused))?;
        for e in &self.link_refused_examples {
            writeln!(f, "  e.g. {e}")?;
        }
        writeln!(
            f,
            "link queue: {} items dropped (the bridge fell behind)",
            self.link_queue_dropped
        )?;
        if let Some(c) = &self.clock {
            writeln!(
                f,
                "clock: {} jumps forward, {} jumps back, {} restarts, {} outliers dropped, {} held while confirming, {} non-increasing stamps refused",
                c.jump_forward, c.jump_back, c.restart, c.outlier_dropped, c.held_confirming, c.non_increasing_refused
            )?;
        }
        if let Some(shift) = self.device_clock_shift_ns {
            writeln!(
                f,
                "--clock device: stamps are the device's time plus {:.6} s",
                shift as f64 * 1e-9
            )?;
        }
        for (name, o) in [
            ("amcl_pose", &self.amcl_pose_outbox),
            ("/tf", &self.tf_outbox),
        ] {
            writeln!(
                f,
                "{name}: {} published, {} writes retried on a full window, {} superseded, {} failed",
                o.published, o.would_block, o.superseded, o.failed
            )?;
        }
        writeln!(f, "device error reports: {}", list(&self.device_errors))?;
        if let Some(h) = &self.last_heartbeat {
            writeln!(
                f,
                "last heartbeat at {:.3} s (device up {:.3} s): {} scans, {} updates, {} drops, {} link errors ({} refused), {} LiDAR bytes skipped, {} frames not encodable",
                h.timestamp_us as f64 * 1e-6,
                f64::from(h.uptime_ms) * 1e-3,
                h.scans,
                h.updates,
                h.drops,
                h.link_errors,
                h.refused,
                h.lidar_skipped,
                h.encode_failures
            )?;
        }
        for (k, v) in &self.applied {
            writeln!(f, "applied {k}: {v}")?;
        }
        for (k, v) in &self.adapted {
            writeln!(f, "adapted {k}: {v}")?;
        }
        for (k, v) in &self.ignored {
            writeln!(f, "ignored {k}: {v}")?;
        }
        Ok(())
    }
}

/// A bridge that could not start or went wrong.
#[derive(Debug)]
pub enum BridgeError {
    Params(ParamsError),
    Port(PortError),
    Ros(RosError),
    Usage(String),
}

impl std::fmt::Display for BridgeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Params(e) => write!(f, "{e}"),
            Self::Port(e) => write!(f, "{e}"),
            Self::Ros(e) => write!(f, "{e}"),
            Self::Usage(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for BridgeError {}

impl BridgeError {
    /// [`EXIT_USAGE`] for a usage error, [`EXIT_CANNOT_START`] otherwise.
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Usage(_) => EXIT_USAGE,
            _ => EXIT_CANNOT_START,
        }
    }
}

/// How device time becomes stamps.
enum Stamper {
    Host(HostClock),
    Device(DeviceClock),
}

impl Stamper {
    /// The stamp of a message stamped `device_us` on the device that arrived at `arrival_ns`;
    /// `None` when the clock model holds or refuses it (counted by the model). A warning line
    /// goes to stderr when the model re-anchors.
    fn stamp(&mut self, device_us: u64, arrival_ns: u64) -> Option<Time> {
        let before = self.counters();
        let stamp = match self {
            Self::Host(c) => c.stamp(device_us, arrival_ns).ok(),
            Self::Device(c) => c.stamp(device_us, arrival_ns).ok(),
        };
        if let Some(w) = self.reanchor_warning(&before) {
            eprintln!("bridge: {w}");
        }
        stamp
    }

    fn counters(&self) -> ClockCounters {
        match self {
            Self::Host(c) => c.counters,
            Self::Device(c) => c.counters,
        }
    }

    /// What to tell the user when the model re-anchored since its counters were `before`.
    fn reanchor_warning(&self, before: &ClockCounters) -> Option<String> {
        let now = self.counters();
        let cause = if now.restart > before.restart {
            "the device's time went back (a restart, or its clock set back)"
        } else if now.jump_forward > before.jump_forward {
            "the device's clock jumped ahead"
        } else if now.jump_back > before.jump_back {
            "the device's clock fell behind the computer's (a stall)"
        } else {
            return None;
        };
        Some(match self {
            Self::Host(c) => format!(
                "{cause}: --clock host re-anchored, device time + {:.6} s",
                c.offset_ns().unwrap_or(0) as f64 * 1e-9
            ),
            Self::Device(c) => match c.last_reanchor {
                Some(r) => format!(
                    "{cause}, from {:.6} s to {:.6} s: --clock device stamps go on from the last one; they are now the device's time + {:.6} s",
                    r.from_device_ns as f64 * 1e-9,
                    r.to_device_ns as f64 * 1e-9,
                    r.shift_ns as f64 * 1e-9
                ),
                None => format!("{cause}: --clock device re-anchored"),
            },
        })
    }
}

/// The instant a frame that arrived at `arrival_ns` (ns since the Unix epoch, [`now_ns`])
/// arrived: now less the time since (now, for an arrival stamped in the future).
fn arrived(arrival_ns: u64) -> Instant {
    let ago = Duration::from_nanos(now_ns().saturating_sub(arrival_ns));
    Instant::now().checked_sub(ago).unwrap_or_else(Instant::now)
}

/// `transform_tolerance`, seconds, in ns (saturating: more than u64 holds is `u64::MAX`).
fn tolerance_ns(s: f64) -> u64 {
    Duration::try_from_secs_f64(s).map_or(if s > 0.0 { u64::MAX } else { 0 }, |d| {
        u64::try_from(d.as_nanos()).unwrap_or(u64::MAX)
    })
}

/// The transform's stamp: the pose's plus the tolerance, saturating at [`Time::MAX`].
fn post_dated(stamp: Time, tolerance_ns: u64) -> Time {
    Time::from_nanos(stamp.to_nanos().unwrap_or(0).saturating_add(tolerance_ns))
}

/// `--namespace`: an absolute ROS namespace (`/`, `/robot1`, `/a/b`); a relative one is taken
/// from the root, a trailing `/` dropped. Each level must be a ROS name (letters, digits and
/// `_`, not starting with a digit).
fn normalized_namespace(ns: &str) -> Result<String, BridgeError> {
    let levels: Vec<&str> = ns.split('/').filter(|l| !l.is_empty()).collect();
    for l in &levels {
        let ok = l.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            && !l.starts_with(|c: char| c.is_ascii_digit());
        if !ok {
            return Err(BridgeError::Usage(format!(
                "--namespace {ns:?}: {l:?} is not a ROS name (letters, digits, _)"
            )));
        }
    }
    Ok(format!("/{}", levels.join("/")))
}

/// Runs the bridge until the link ends, `args.seconds` pass or a lifecycle `shutdown`;
/// progress lines on stderr. An `Err` is a bridge that could not start; once running, it ends
/// with a report whose [`BridgeReport::exit_code`] says why. No signal stops it: see
/// [`run_until`].
pub fn run(args: &BridgeArgs) -> Result<BridgeReport, BridgeError> {
    run_until(args, &Stop::new())
}

/// [`run`], which also stops when `stop` is requested ([`Stop::on_signals`]: SIGINT or
/// SIGTERM; checked at least every 10 ms once the link is open). It then stops reading the
/// link (frames already read but not yet handled are left), sends what the outboxes hold (at
/// most one message per topic), and returns the report with `ended: signal (SIGINT)` (or
/// `SIGTERM`) and [`EXIT_STOPPED`].
pub fn run_until(args: &BridgeArgs, stop: &Stop) -> Result<BridgeReport, BridgeError> {
    let endpoint = match (&args.connect, &args.serial) {
        (Some(a), None) => Endpoint::Tcp(a.clone()),
        (None, Some(p)) => Endpoint::Serial {
            path: p.clone(),
            baud: args.baud,
        },
        _ => {
            return Err(BridgeError::Usage(
                "give one of --connect and --serial".into(),
            ))
        }
    };
    if let Some(s) = args.seconds {
        if s.is_nan() || s <= 0.0 {
            return Err(BridgeError::Usage(format!(
                "--seconds {s}: a positive number of seconds"
            )));
        }
    }
    // More seconds than a Duration holds (or inf): no limit.
    let limit = args
        .seconds
        .and_then(|s| Duration::try_from_secs_f64(s).ok());
    let namespace = normalized_namespace(&args.namespace)?;
    let node_name = format!("{}/amcl", namespace.trim_end_matches('/'));
    let params = match &args.params {
        Some(p) => Nav2Params::read_for(p, &node_name).map_err(BridgeError::Params)?,
        None => Nav2Params::default(),
    };
    let frames = params.frames.clone();
    let node_config = NodeConfig {
        domain_id: args.domain_id,
        name: "amcl".into(),
        namespace,
        loopback_only: args.loopback_only,
        service_mapping: match args.rmw {
            Rmw::Fastrtps => ServiceMapping::Enhanced,
            Rmw::Cyclonedds => ServiceMapping::Cyclone,
        },
    };
    let mut node = RosNode::new(&node_config).map_err(BridgeError::Ros)?;
    let mut port = Port::open(&endpoint).map_err(BridgeError::Port)?;
    let mut r = BridgeReport {
        link: endpoint.to_string(),
        node: node_name.clone(),
        applied: params.applied.clone(),
        adapted: params.adapted.clone(),
        ignored: params.ignored.clone(),
        ..BridgeReport::default()
    };
    eprintln!(
        "bridge: connected to {endpoint}; node {node_name} on domain {}",
        args.domain_id
    );
    if let Some(sp) = params.set_parameters {
        port.send(&Message::SetParameters(sp))
            .map_err(BridgeError::Port)?;
    }
    if let Some(ip) = params.initial_pose {
        port.send(&Message::SetInitialPose(ip))
            .map_err(BridgeError::Port)?;
        r.initial_poses_sent += 1;
    }
    let mut clock = match args.clock {
        ClockArg::Host => Stamper::Host(HostClock::new()),
        ClockArg::Device => Stamper::Device(DeviceClock::new()),
    };
    let tolerance_ns = tolerance_ns(frames.transform_tolerance_s);
    let mut poses: Outbox<crate::msg::PoseWithCovarianceStamped> = Outbox::default();
    let mut transforms: Outbox<TfMessage> = Outbox::default();
    let mut repeater = Repeater::new();
    let mut finalized_at: Option<Instant> = None;
    let mut state = if args.lifecycle {
        LifecycleState::Unconfigured
    } else {
        LifecycleState::Active
    };
    let started = Instant::now();
    let mut progress = Instant::now();
    let count = |m: &mut BTreeMap<String, u64>, k: String| *m.entry(k).or_default() += 1;
    let ros_failed = |e: RosError| eprintln!("bridge: {e}");
    let lost = |r: &mut BridgeReport, e: PortError| {
        r.ended = format!("the link was lost: {e}");
        r.exit_code = EXIT_LINK_LOST;
    };
    'run: loop {
        if let Some(signal) = stop.requested() {
            r.ended = format!("signal ({})", signal.name());
            r.exit_code = EXIT_STOPPED;
            break;
        }
        if limit.is_some_and(|l| started.elapsed() >= l) {
            r.ended = "the time given with --seconds passed".into();
            r.exit_code = EXIT_STOPPED;
            break;
        }
        // Messages held back (a full window, the interval) go out before newer ones are taken.
        flush_both(&mut poses, &mut transforms, &node, Instant::now());
        let wait = if poses.is_pending() || transforms.is_pending() {
            Duration::from_millis(1)
        } else {
            Duration::from_millis(10)
        };
        for item in port.receive(wait) {
            match item {
                Incoming::Frame {
                    message,
                    arrival_ns,
                } => match message {
                    Message::Estimate(e) => {
                        let at = arrived(arrival_ns);
                        repeater.alive(at);
                        if !e.flags.contains(EstimateFlags::INITIALIZED) {
                            r.uninitialized += 1;
                            repeater.forget();
                            continue;
                        }
                        if state != LifecycleState::Active {
                            r.not_active += 1;
                            continue;
                        }
                        let Some(stamp) = clock.stamp(e.timestamp_us, arrival_ns) else {
                            // Held or refused: counted by the clock model.
                            continue;
                        };
                        poses
                            .offer(
                                convert::amcl_pose(&e, stamp, &frames.global),
                                Instant::now(),
                                |m| node.publish_pose(m),
                            )
                            .unwrap_or_else(ros_failed);
                        if frames.tf_broadcast {
                            let t = convert::map_to_odom_transform(
                                &e,
                                post_dated(stamp, tolerance_ns),
                                &frames.global,
                                &frames.odom,
                            );
                            repeater.sent(&t, at, Instant::now());
                            transforms
                                .offer(
                                    TfMessage {
                                        transforms: vec![t],
                                    },
                                    Instant::now(),
                                    |m| node.publish_tf(m),
                                )
                                .unwrap_or_else(ros_failed);
                        }
                    }
                    Message::Heartbeat(h) => {
                        repeater.alive(arrived(arrival_ns));
                        r.heartbeats += 1;
                        if let Some(note) = lidar_noise(r.last_heartbeat.as_ref(), &h) {
                            eprintln!("bridge: {note}");
                        }
                        r.last_heartbeat = Some(h.into());
                    }
                    Message::Error(e) => {
                        eprintln!(
                            "bridge: the device refused frame {} (type 0x{:02x}): {:?}, detail {}",
                            e.seq, e.msg_type, e.code, e.detail
                        );
                        count(&mut r.device_errors, format!("{:?}", e.code));
                    }
                    other => {
                        let t = other.message_type();
                        r.refuse(format!("unexpected {t:?}"), || {
                            format!("unexpected {other:?}")
                        });
                    }
                },
                Incoming::Refused(e) => {
                    let d = format!("{e:?}");
                    r.refuse(kind_of(&d), || d);
                }
                Incoming::Closed { error, .. } => {
                    r.ended = match error {
                        None => "the device closed the link".into(),
                        Some(e) => format!("reading the link failed: {e}"),
                    };
                    r.exit_code = EXIT_LINK_LOST;
                    break 'run;
                }
            }
        }
        for c in node.lifecycle_calls(&mut state) {
            match c {
                Ok(c) => {
                    eprintln!("bridge: lifecycle {} -> {}", c.from.label(), c.to.label());
                    r.lifecycle_transitions
                        .push(format!("{} -> {}", c.from.label(), c.to.label()));
                }
                Err(e) => eprintln!("bridge: {e}"),
            }
        }
        if state == LifecycleState::Finalized {
            // The shutdown's answer must reach its caller before the node goes.
            let at = *finalized_at.get_or_insert_with(Instant::now);
            if at.elapsed() >= FINALIZED_LINGER {
                r.ended = "the node was shut down through its lifecycle".into();
                r.exit_code = EXIT_STOPPED;
                break;
            }
        }
        if frames.tf_broadcast && state == LifecycleState::Active {
            if let Some(t) = repeater.due(Instant::now()) {
                transforms
                    .offer(
                        TfMessage {
                            transforms: vec![t],
                        },
                        Instant::now(),
                        |m| node.publish_tf(m),
                    )
                    .unwrap_or_else(ros_failed);
            }
        }
        for m in node.initial_poses() {
            let m = match m {
                Ok(m) => m,
                Err(e) => {
                    eprintln!("bridge: {e}");
                    count(&mut r.initial_poses_refused, "unreadable".into());
                    continue;
                }
            };
            match convert::set_initial_pose(&m, &frames.global) {
                Ok(ip) => match port.send(&Message::SetInitialPose(ip)) {
                    Ok(()) => r.initial_poses_sent += 1,
                    Err(PortError::Encode(e)) => {
                        eprintln!("bridge: initialpose not sent: {e}");
                        count(
                            &mut r.initial_poses_refused,
                            "out of the link's range".into(),
                        );
                    }
                    Err(e) => {
                        lost(&mut r, e);
                        break 'run;
                    }
                },
                Err(why) => {
                    eprintln!("bridge: initialpose not sent: {why}");
                    // By kind: a frame name is the sender's and has no bound.
                    let key = match why {
                        Refused::WrongFrame { .. } => "the frame is not the global frame".into(),
                        other => other.to_string(),
                    };
                    count(&mut r.initial_poses_refused, key);
                }
            }
        }
        for call in node.service_calls() {
            let message = match call {
                Ok(ServiceCall::ReinitializeGlobalLocalization) => {
                    r.global_localizations += 1;
                    Message::StartGlobalLocalization
                }
                Ok(ServiceCall::RequestNomotionUpdate) => {
                    r.nomotion_updates += 1;
                    Message::RequestNoMotionUpdate
                }
                Err(e) => {
                    eprintln!("bridge: {e}");
                    continue;
                }
            };
            if let Err(e) = port.send(&message) {
                lost(&mut r, e);
                break 'run;
            }
        }
        if progress.elapsed() >= Duration::from_secs(5) {
            progress = Instant::now();
            eprintln!(
                "bridge: {:.0} s: {} poses published, {} heartbeats, {} frames to the device, {} link items dropped",
                started.elapsed().as_secs_f64(),
                poses.counters.published,
                r.heartbeats,
                port.sent,
                port.dropped()
            );
        }
    }
    // A last try for what was held back.
    flush_both(
        &mut poses,
        &mut transforms,
        &node,
        Instant::now() + outbox::MIN_INTERVAL,
    );
    r.poses = poses.counters.published;
    r.transforms = transforms.counters.published;
    r.transforms_repeated = repeater.repeated;
    r.lifecycle_state = state.label().into();
    r.amcl_pose_outbox = poses.counters;
    r.tf_outbox = transforms.counters;
    r.clock = Some(clock.counters());
    if let Stamper::Device(c) = &clock {
        r.device_clock_shift_ns =
            Some(i64::try_from(c.shift_ns()).unwrap_or(if c.shift_ns() < 0 {
                i64::MIN
            } else {
                i64::MAX
            }));
    }
    r.link_queue_dropped = port.dropped();
    r.frames_sent = port.sent;
    r.seconds = started.elapsed().as_secs_f64();
    Ok(r)
}

/// Sends what both outboxes hold back and may go out at `now` (poses first); a publish error is
/// reported on stderr and the bridge goes on.
fn flush_both(
    poses: &mut Outbox<crate::msg::PoseWithCovarianceStamped>,
    transforms: &mut Outbox<TfMessage>,
    node: &RosNode,
    now: Instant,
) {
    let ros_failed = |e: RosError| eprintln!("bridge: {e}");
    poses
        .flush(now, |m| node.publish_pose(m))
        .unwrap_or_else(ros_failed);
    transforms
        .flush(now, |m| node.publish_tf(m))
        .unwrap_or_else(ros_failed);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seconds_must_be_positive() {
        for bad in ["NaN", "nan", "0", "-1", "-inf", "x", ""] {
            assert!(parse_seconds(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_seconds("2.5"), Ok(2.5));
        // No limit, not a panic.
        assert_eq!(parse_seconds("inf"), Ok(f64::INFINITY));
        assert_eq!(parse_seconds("1e30"), Ok(1e30));
        assert!(Duration::try_from_secs_f64(1e30).is_err());
    }

    #[test]
    fn namespaces_are_absolute_ros_names() {
        for (given, want) in [
            ("/", "/"),
            ("", "/"),
            ("robot1", "/robot1"),
            ("/robot1/", "/robot1"),
            ("/a/b", "/a/b"),
        ] {
            assert_eq!(normalized_namespace(given).unwrap(), want, "{given}");
        }
        for bad in ["/robot-1", "1robot", "/a/b c", "/ä"] {
            assert!(
                matches!(normalized_namespace(bad), Err(BridgeError::Usage(_))),
                "{bad}"
            );
        }
    }

    #[test]
    fn the_transform_tolerance_saturates() {
        assert_eq!(tolerance_ns(1.0), 1_000_000_000);
        assert_eq!(tolerance_ns(0.0), 0);
        assert_eq!(tolerance_ns(1e300), u64::MAX);
        assert_eq!(tolerance_ns(f64::INFINITY), u64::MAX);
        let pose = Time {
            sec: 1_700_000_000,
            nanosec: 5,
        };
        assert_eq!(post_dated(pose, u64::MAX), Time::MAX);
        assert_eq!(
            post_dated(pose, 500_000_000),
            Time {
                sec: 1_700_000_000,
                nanosec: 500_000_005
            }
        );
        // Never before the pose.
        assert_eq!(post_dated(Time::MAX, 1), Time::MAX);
    }

    #[test]
    fn refusals_are_counted_by_kind_with_a_few_examples() {
        let mut r = BridgeReport::default();
        for seq in 0..1000u16 {
            let e = beamfield::link::LinkError::WrongLength {
                msg_type: 0x81,
                seq,
                len: 3,
            };
            let d = format!("{e:?}");
            r.refuse(kind_of(&d), || d);
        }
        r.refuse(kind_of("BadCrc"), || "BadCrc".into());
        assert_eq!(r.link_refused.len(), 2);
        assert_eq!(r.link_refused["WrongLength"], 1000);
        assert_eq!(r.link_refused["BadCrc"], 1);
        assert_eq!(r.link_refused_examples.len(), REFUSED_EXAMPLES);
        assert!(r.link_refused_examples[7].contains("seq: 7"));
    }

    #[test]
    fn a_lidar_that_sends_only_skipped_bytes_is_reported() {
        let beat = |scans, lidar_skipped| Heartbeat {
            scans,
            lidar_skipped,
            ..Heartbeat::default()
        };
        let last = HeartbeatCounters::from(beat(10, 100));
        let noisy = lidar_noise(Some(&last), &beat(10, 23_140)).unwrap();
        assert!(noisy.contains("23040 bytes"), "{noisy}");
        // Scans came (a few bytes lost at a resync), nothing skipped, or no earlier heartbeat.
        assert_eq!(lidar_noise(Some(&last), &beat(20, 150)), None);
        assert_eq!(lidar_noise(Some(&last), &beat(10, 100)), None);
        assert_eq!(lidar_noise(None, &beat(10, 23_140)), None);
    }
}
