//! `cargo xtask ros2`: the ROS 2 bridge checked against a ROS 2 peer written with another DDS
//! implementation (PyPI `cyclonedds`), on 127.0.0.1 only.
//!
//! Three programs: the robot application in QEMU with its link offered on a TCP port of
//! 127.0.0.1 (`crate::robot::bridge`), `beamfield bridge --connect` on that port, and
//! `host-tests/python/ros2_peer.py`. The peer prints what it receives and checks the
//! `initialpose` round trip, a refused NaN pose and a service call; the bridge's report and the
//! device = host comparison (on the stream the device really received) are checked here.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::error::{Error, Result};
use crate::process::{cargo, repo_root, run, show, spawn_error};
use crate::robot;

/// Cyclone DDS on 127.0.0.1 only: unicast discovery to the loopback address, no multicast.
pub const CYCLONEDDS_LOOPBACK: &str = "<CycloneDDS><Domain><General><Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain></CycloneDDS>";

/// A DDS domain of its own, so that a ROS 2 system on this host is not disturbed.
const DOMAIN: &str = "42";
/// `beamfield bridge`'s exit code when its link ends (docs/nav2.md).
const BRIDGE_LINK_LOST: i32 = 3;

/// Seconds the peer and the bridge may run.
const TIMEOUT_S: u64 = 900;

/// Kills a child left running when dropped (an error on the way).
struct Running(Option<Child>, &'static str);

impl Drop for Running {
    fn drop(&mut self) {
        if let Some(mut c) = self.0.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

impl Running {
    /// Waits at most `limit` for the child to end; its exit code (`None`: killed).
    fn wait(&mut self, limit: Duration) -> Result<Option<i32>> {
        let started = Instant::now();
        let Some(c) = self.0.as_mut() else {
            return Ok(None);
        };
        loop {
            if let Some(s) = c
                .try_wait()
                .map_err(|e| Error::Host(format!("{}: {e}", self.1)))?
            {
                self.0 = None;
                return Ok(s.code());
            }
            if started.elapsed() > limit {
                return Ok(None);
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    }
}

fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo_root().join("target"))
}

fn spawn(mut cmd: Command, out: &Path, err: &Path, name: &'static str) -> Result<Running> {
    let file = |p: &Path| File::create(p).map_err(|e| Error::io(p, e));
    cmd.stdin(Stdio::null())
        .stdout(file(out)?)
        .stderr(file(err)?);
    eprintln!("+ {} >{} 2>{}", show(&cmd), out.display(), err.display());
    let child = cmd.spawn().map_err(|e| spawn_error(&cmd, e))?;
    Ok(Running(Some(child), name))
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_default()
}

/// Runs the three programs; fails when the peer's checks, the bridge or the robot task fail.
pub fn ros2(scans: usize) -> Result {
    let python = Command::new("python3")
        .args(["-c", "import cyclonedds"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status();
    if !python.is_ok_and(|s| s.success()) {
        return Err(Error::Requirement(
            "python3 with PyPI's cyclonedds is needed: python3 -m pip install cyclonedds".into(),
        ));
    }
    run(cargo().args(["build", "-p", "beamfield-tools", "--bin", "beamfield"]))?;
    let beamfield = target_dir().join("debug/beamfield");
    // Not `scratch()`: the QEMU run removes that directory when it ends.
    let dir = std::env::temp_dir().join(format!("beamfield-ros2-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let listener = robot::bridge::listen(0)?;
    let port = listener
        .local_addr()
        .map_err(|e| Error::Host(e.to_string()))?
        .port();

    let mut peer_cmd = Command::new("python3");
    peer_cmd
        .arg(repo_root().join("host-tests/python/ros2_peer.py"))
        .args(["--domain", DOMAIN, "--timeout", &TIMEOUT_S.to_string()])
        .env("CYCLONEDDS_URI", CYCLONEDDS_LOOPBACK);
    let (peer_out, peer_err) = (dir.join("peer.stdout"), dir.join("peer.stderr"));
    let mut peer = spawn(peer_cmd, &peer_out, &peer_err, "the ROS 2 peer")?;

    let mut bridge_cmd = Command::new(&beamfield);
    bridge_cmd
        .args([
            "--json",
            "bridge",
            "--connect",
            &format!("127.0.0.1:{port}"),
        ])
        .args([
            "--loopback-only",
            "--rmw",
            "cyclonedds",
            "--domain-id",
            DOMAIN,
        ]);
    let (bridge_out, bridge_err) = (dir.join("bridge.stdout"), dir.join("bridge.stderr"));
    let mut bridge = spawn(bridge_cmd, &bridge_out, &bridge_err, "the bridge")?;

    let robot_result = robot::robot(
        robot::Options {
            scans: Some(scans),
            no_kidnap: true,
            count: false,
            isr: false,
            host_only: false,
            bridge: true,
            bag: None,
            board: crate::qemu::Board::Netduinoplus2,
        },
        Some(&listener),
    );
    // The bridge ends when the device's link closes; the peer when its checks are done.
    let bridge_code = bridge.wait(Duration::from_secs(30))?;
    let peer_code = peer.wait(Duration::from_secs(60))?;
    for (name, out, err) in [
        ("bridge", &bridge_out, &bridge_err),
        ("ros2 peer", &peer_out, &peer_err),
    ] {
        for l in read(out).lines() {
            println!("{name}: {l}");
        }
        let e = read(err);
        if !e.trim().is_empty() {
            let lines: Vec<&str> = e.lines().collect();
            let from = lines.len().saturating_sub(12);
            for l in &lines[from..] {
                println!("{name} (stderr): {l}");
            }
        }
    }
    robot_result?;
    // The robot's end closes the link: the bridge's exit code for a lost link is 3
    // (docs/nav2.md, "Exit codes and the report's counters").
    if bridge_code != Some(BRIDGE_LINK_LOST) {
        return Err(Error::Requirement(format!(
            "the bridge ended with {bridge_code:?}, not {BRIDGE_LINK_LOST} (the link closed when the robot ended; see its output above)"
        )));
    }
    if peer_code != Some(0) {
        return Err(Error::Requirement(format!(
            "the ROS 2 peer's checks failed or it did not finish: {peer_code:?} (see above)"
        )));
    }
    let report: serde_json::Value = serde_json::from_str(&read(&bridge_out))
        .map_err(|e| Error::Output(format!("the bridge's JSON report: {e}")))?;
    let number = |path: &[&str]| {
        path.iter()
            .try_fold(&report, |v, k| v.get(k))
            .and_then(serde_json::Value::as_u64)
    };
    let want = [
        (&["initial_poses_sent"][..], 1),
        (
            &["initial_poses_refused", "the position is not finite"][..],
            1,
        ),
        (&["nomotion_updates"][..], 1),
        (&["frames_sent"][..], 2),
    ];
    for (path, n) in want {
        if number(path) != Some(n) {
            return Err(Error::Requirement(format!(
                "the bridge's report has {} = {:?}, not {n}: the peer sent one good and one NaN initialpose and called one service",
                path.join("."),
                number(path)
            )));
        }
    }
    if number(&["poses"]).unwrap_or(0) == 0 {
        return Err(Error::Requirement("the bridge published no pose".into()));
    }
    let _ = std::fs::remove_dir_all(&dir);
    println!("ros2: the peer received the device's poses and transforms, moved the estimate with initialpose, had its NaN pose refused and its service call answered");
    Ok(())
}
