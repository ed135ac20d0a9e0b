//! The bridge's loop: the device's frames out to ROS 2, ROS 2's requests in to the device,
//! until the link ends (or `--seconds`), then one report.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use beamfield::link::{EstimateFlags, Heartbeat, Message};
use ros2_client::ServiceMapping;
use serde::Serialize;

use crate::convert::{self, Clock};
use crate::msg::TfMessage;
use crate::params::{Nav2Params, ParamsError};
use crate::port::{Endpoint, Incoming, Port, PortError};
use crate::ros::{NodeConfig, RosError, RosNode, ServiceCall};

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
    /// The computer's clock: device time plus the smallest offset seen (see `convert::Clock`).
    Host,
    /// The device's clock as it is (µs since it started): for replays with `use_sim_time`.
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
    /// Stop after this many seconds (default: when the link ends).
    #[arg(long, value_name = "S")]
    pub seconds: Option<f64>,
}

/// What the bridge did.
#[derive(Clone, Debug, Default, Serialize)]
pub struct BridgeReport {
    pub link: String,
    pub applied: BTreeMap<String, String>,
    pub ignored: BTreeMap<String, String>,
    /// Estimates published on `amcl_pose`.
    pub poses: u64,
    /// Transforms published on `/tf`.
    pub transforms: u64,
    /// Estimates not published: the filter was not initialized.
    pub uninitialized: u64,
    pub heartbeats: u64,
    /// Frames the decoder refused (CRC, length, range …), by cause.
    pub link_refused: BTreeMap<String, u64>,
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
        }
    }
}

impl std::fmt::Display for BridgeReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "bridge: {} for {:.1} s, ended: {}",
            self.link, self.seconds, self.ended
        )?;
        writeln!(
            f,
            "published: {} poses on amcl_pose, {} transforms on /tf ({} estimates before initialization not published)",
            self.poses, self.transforms, self.uninitialized
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
        writeln!(f, "device error reports: {}", list(&self.device_errors))?;
        if let Some(h) = &self.last_heartbeat {
            writeln!(
                f,
                "last heartbeat at {:.3} s: {} scans, {} updates, {} drops, {} link errors",
                h.timestamp_us as f64 * 1e-6,
                h.scans,
                h.updates,
                h.drops,
                h.link_errors
            )?;
        }
        for (k, v) in &self.applied {
            writeln!(f, "applied {k}: {v}")?;
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

/// Runs the bridge until the link ends or `args.seconds` pass; progress lines on stderr.
pub fn run(args: &BridgeArgs) -> Result<BridgeReport, BridgeError> {
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
        if !(s.is_finite() && s > 0.0) {
            return Err(BridgeError::Usage(format!(
                "--seconds {s}: a positive number of seconds"
            )));
        }
    }
    let params = match &args.params {
        Some(p) => Nav2Params::read(p).map_err(BridgeError::Params)?,
        None => Nav2Params::default(),
    };
    let frames = params.frames.clone();
    let node_config = NodeConfig {
        domain_id: args.domain_id,
        name: "amcl".into(),
        namespace: "/".into(),
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
        applied: params.applied.clone(),
        ignored: params.ignored.clone(),
        ..BridgeReport::default()
    };
    eprintln!(
        "bridge: connected to {endpoint}; node /amcl on domain {}",
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
        ClockArg::Host => Clock::Host { offset_ns: None },
        ClockArg::Device => Clock::Device,
    };
    let tolerance_ns = (frames.transform_tolerance_s * 1e9) as u64;
    let started = Instant::now();
    let mut progress = Instant::now();
    let limit = args.seconds.map(Duration::from_secs_f64);
    let count = |m: &mut BTreeMap<String, u64>, k: String| *m.entry(k).or_default() += 1;
    'run: loop {
        if limit.is_some_and(|l| started.elapsed() >= l) {
            r.ended = "the time given with --seconds passed".into();
            break;
        }
        for item in port.receive(Duration::from_millis(10)) {
            match item {
                Incoming::Frame {
                    message,
                    arrival_ns,
                } => match message {
                    Message::Estimate(e) => {
                        if !e.flags.contains(EstimateFlags::INITIALIZED) {
                            r.uninitialized += 1;
                            continue;
                        }
                        let stamp = clock.stamp(e.timestamp_us, arrival_ns);
                        node.publish_pose(convert::amcl_pose(&e, stamp, &frames.global))
                            .map_err(BridgeError::Ros)?;
                        r.poses += 1;
                        if frames.tf_broadcast {
                            let post = crate::msg::Time::from_nanos(
                                stamp.to_nanos().unwrap_or(0) + tolerance_ns,
                            );
                            let t = convert::map_to_odom_transform(
                                &e,
                                post,
                                &frames.global,
                                &frames.odom,
                            );
                            node.publish_tf(TfMessage {
                                transforms: vec![t],
                            })
                            .map_err(BridgeError::Ros)?;
                            r.transforms += 1;
                        }
                    }
                    Message::Heartbeat(h) => {
                        r.heartbeats += 1;
                        r.last_heartbeat = Some(h.into());
                    }
                    Message::Error(e) => {
                        eprintln!(
                            "bridge: the device refused frame {} (type 0x{:02x}): {:?}, detail {}",
                            e.seq, e.msg_type, e.code, e.detail
                        );
                        count(&mut r.device_errors, format!("{:?}", e.code));
                    }
                    other => count(
                        &mut r.link_refused,
                        format!("unexpected {:?}", other.message_type()),
                    ),
                },
                Incoming::Refused(e) => count(
                    &mut r.link_refused,
                    format!("{e:?}")
                        .split('(')
                        .next()
                        .unwrap_or("")
                        .trim()
                        .to_owned(),
                ),
                Incoming::Closed { error, .. } => {
                    r.ended = match error {
                        None => "the device closed the link".into(),
                        Some(e) => format!("reading the link failed: {e}"),
                    };
                    break 'run;
                }
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
                    Err(e) => return Err(BridgeError::Port(e)),
                },
                Err(why) => {
                    eprintln!("bridge: initialpose not sent: {why}");
                    count(&mut r.initial_poses_refused, why.to_string());
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
            port.send(&message).map_err(BridgeError::Port)?;
        }
        if progress.elapsed() >= Duration::from_secs(5) {
            progress = Instant::now();
            eprintln!(
                "bridge: {:.0} s: {} poses published, {} heartbeats, {} frames to the device",
                started.elapsed().as_secs_f64(),
                r.poses,
                r.heartbeats,
                port.sent
            );
        }
    }
    r.frames_sent = port.sent;
    r.seconds = started.elapsed().as_secs_f64();
    Ok(r)
}
