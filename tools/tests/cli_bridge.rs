//! `beamfield bridge`'s exit codes as a supervisor sees them, and options that must not panic:
//! the bridge runs against a fake device on a TCP port of 127.0.0.1, with DDS on 127.0.0.1.
//! 0: ran for `--seconds`; 1: could not start; 2: usage error; 3: the link was lost.

#![cfg(feature = "bridge")]

use std::io::Write;
use std::net::TcpListener;
use std::process::Output;
use std::time::Duration;

use beamfield::link::{Encoder, Estimate, EstimateFlags, Message, MAX_WIRE_LEN};
use beamfield::Pose;

mod common;
use common::bin;

/// A device that sends `n` initialized estimates 20 ms apart, then keeps the link open for
/// `hold` and closes it. Returns its address.
fn device(n: u64, hold: Duration) -> (String, std::thread::JoinHandle<()>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let h = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        let mut enc = Encoder::new();
        for k in 0..n {
            let m = Message::Estimate(Estimate {
                timestamp_us: 1_000_000 + k * 20_000,
                pose: Pose::new(k as f32, 0.0, 0.0),
                flags: EstimateFlags::INITIALIZED,
                ess: 100.0,
                ..Estimate::default()
            });
            let mut w = [0u8; MAX_WIRE_LEN];
            let len = enc.encode(&m, &mut w).unwrap();
            // The bridge may have gone (a time limit): that ends the device too.
            if s.write_all(&w[..len]).is_err() {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        std::thread::sleep(hold);
    });
    (addr, h)
}

/// Held for reading by every bridge run, for writing by the flood: the flood's load would
/// delay the others' loops enough to merge estimates (superseded, not published).
static HEAVY: std::sync::RwLock<()> = std::sync::RwLock::new(());

fn bridge(addr: &str, domain: u16, extra: &[&str]) -> Output {
    let _shared = HEAVY.read().unwrap_or_else(|p| p.into_inner());
    bin()
        .args(["--json", "bridge", "--connect", addr, "--loopback-only"])
        .args(["--domain-id", &domain.to_string()])
        .args(extra)
        .output()
        .unwrap()
}

fn report(out: &Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "no JSON report ({e}); stderr: {}",
            String::from_utf8_lossy(&out.stderr)
        )
    })
}

fn code(out: &Output) -> Option<i32> {
    out.status.code()
}

#[test]
fn seconds_that_are_not_a_positive_number_are_usage_errors() {
    for bad in ["NaN", "0", "-1", "-inf", "soon"] {
        // No device is needed: the option is refused before anything starts.
        // `--seconds=-1`: the value itself reaches the check (not read as another option).
        let out = bridge("127.0.0.1:9", 70, &[&format!("--seconds={bad}")]);
        assert_eq!(
            code(&out),
            Some(2),
            "--seconds {bad}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("a positive number of seconds") || err.contains("not a number"),
            "{err}"
        );
    }
}

#[test]
fn huge_seconds_are_no_limit_and_a_closed_link_exits_3() {
    for (domain, seconds) in [(71, "1e30"), (72, "inf")] {
        let (addr, dev) = device(5, Duration::ZERO);
        let out = bridge(&addr, domain, &["--seconds", seconds]);
        dev.join().unwrap();
        assert_eq!(
            code(&out),
            Some(3),
            "--seconds {seconds}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let r = report(&out);
        assert_eq!(r["exit_code"], 3);
        assert_eq!(r["poses"], 5, "{r}");
    }
}

#[test]
fn a_closed_link_exits_3() {
    let (addr, dev) = device(3, Duration::ZERO);
    let out = bridge(&addr, 76, &[]);
    dev.join().unwrap();
    assert_eq!(
        code(&out),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = report(&out);
    assert_eq!(r["poses"], 3, "{r}");
    assert_eq!(r["ended"], "the device closed the link", "{r}");
}

#[test]
fn a_time_limit_exits_0() {
    let (addr, dev) = device(3, Duration::from_secs(4));
    let out = bridge(&addr, 73, &["--seconds", "1.5"]);
    assert_eq!(
        code(&out),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(report(&out)["poses"], 3);
    dev.join().unwrap();
}

#[test]
fn no_device_exits_1() {
    // A port nobody listens on.
    let free = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = free.local_addr().unwrap().to_string();
    drop(free);
    let out = bridge(&addr, 74, &[]);
    assert_eq!(
        code(&out),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn a_huge_transform_tolerance_saturates() {
    let dir = std::env::temp_dir().join(format!("beamfield-bridge-tol-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let params = dir.join("params.yaml");
    std::fs::write(
        &params,
        "amcl:\n  ros__parameters:\n    transform_tolerance: 1.0e300\n",
    )
    .unwrap();
    let (addr, dev) = device(4, Duration::ZERO);
    let out = bridge(&addr, 75, &["--params", params.to_str().unwrap()]);
    dev.join().unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(
        code(&out),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = report(&out);
    assert_eq!(r["transforms"], 4, "{r}");
}

#[test]
fn a_namespaced_params_file_needs_the_namespace_and_a_bad_namespace_is_a_usage_error() {
    let dir = std::env::temp_dir().join(format!("beamfield-bridge-ns-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let params = dir.join("params.yaml");
    std::fs::write(
        &params,
        "robot1:\n  amcl:\n    ros__parameters:\n      transform_tolerance: 0.25\n",
    )
    .unwrap();
    let params = params.to_str().unwrap();

    // For the node /amcl the file has no section: it says which it has.
    let (addr, _dev) = device(0, Duration::ZERO);
    let out = bridge(&addr, 76, &["--params", params]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(code(&out), Some(1), "{err}");
    assert!(
        err.contains("/robot1/amcl") && err.contains("--namespace"),
        "{err}"
    );

    // In the namespace it is read.
    let (addr, dev) = device(3, Duration::ZERO);
    let out = bridge(&addr, 76, &["--params", params, "--namespace", "robot1"]);
    dev.join().unwrap();
    assert_eq!(
        code(&out),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = report(&out);
    assert_eq!(r["node"], "/robot1/amcl", "{r}");
    assert_eq!(r["applied"]["transform_tolerance"], "0.25 s", "{r}");
    assert_eq!(r["poses"], 3, "{r}");

    // Not a ROS name.
    let (addr, _dev) = device(0, Duration::ZERO);
    let out = bridge(&addr, 76, &["--params", params, "--namespace", "robot-1"]);
    assert_eq!(
        code(&out),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A device that sends `n` initialized estimates 20 ms apart, then an error report (a mark:
/// the bridge prints it on stderr once it has handled every estimate before it), and keeps the
/// link open until the bridge closes it.
fn device_until_closed(n: u64) -> (String, std::thread::JoinHandle<()>) {
    device_paced_until_closed(n, Duration::from_millis(20))
}

/// [`device_until_closed`] with estimates `pace` apart (zero: as fast as the socket takes
/// them, in writes of up to 64 KiB).
fn device_paced_until_closed(n: u64, pace: Duration) -> (String, std::thread::JoinHandle<()>) {
    use beamfield::link::{ErrorCode, ErrorReport};
    use std::io::Read;
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let h = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        let mut enc = Encoder::new();
        let mut w = [0u8; MAX_WIRE_LEN];
        let mut batch = Vec::new();
        for k in 0..n {
            let m = Message::Estimate(Estimate {
                timestamp_us: 1_000_000 + k * 20_000,
                pose: Pose::new((k % 1000) as f32, 0.0, 0.0),
                flags: EstimateFlags::INITIALIZED,
                ess: 100.0,
                ..Estimate::default()
            });
            let len = enc.encode(&m, &mut w).unwrap();
            batch.extend_from_slice(&w[..len]);
            if pace.is_zero() && batch.len() < 1 << 16 && k + 1 < n {
                continue;
            }
            if s.write_all(&batch).is_err() {
                return;
            }
            batch.clear();
            std::thread::sleep(pace);
        }
        let mark = Message::Error(ErrorReport {
            code: ErrorCode::Refused,
            msg_type: 0x10,
            seq: 7,
            detail: 0,
        });
        let len = enc.encode(&mark, &mut w).unwrap();
        if s.write_all(&w[..len]).is_err() {
            return;
        }
        // Until the bridge's end closes (its process exits).
        let mut buf = [0u8; 256];
        while s.read(&mut buf).is_ok_and(|r| r > 0) {}
    });
    (addr, h)
}

/// Generous: a process that has not exited by then is taken as hung (not a timing assertion).
const EXIT_WAIT: Duration = Duration::from_secs(120);

/// Waits for `child` to exit, at most [`EXIT_WAIT`] (then kills it and fails).
fn wait_exit(child: &mut std::process::Child) -> std::process::ExitStatus {
    let since = std::time::Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if since.elapsed() > EXIT_WAIT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("the process did not exit within {EXIT_WAIT:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Sends `signal` (`INT`, `TERM`) to process `pid` with kill(1).
fn send_signal(pid: u32, signal: &str) {
    let sent = std::process::Command::new("kill")
        .args([&format!("-{signal}"), &pid.to_string()])
        .status()
        .unwrap();
    assert!(sent.success(), "kill -{signal} {pid}");
}

/// Runs the bridge against [`device_until_closed`] with 5 estimates, sends `signal` once the
/// bridge has handled them, and returns its exit code and JSON report.
fn stopped_by(signal: &str, domain: u16) -> (Option<i32>, serde_json::Value) {
    let _shared = HEAVY.read().unwrap_or_else(|p| p.into_inner());
    stopped_by_after(signal, domain, device_until_closed(5), |_| {})
}

/// Runs the bridge against `device` (one of [`device_paced_until_closed`]), calls `marked`
/// with the bridge's process id once the bridge has handled the device's mark, sends `signal`,
/// and returns the bridge's exit code and JSON report.
fn stopped_by_after(
    signal: &str,
    domain: u16,
    device: (String, std::thread::JoinHandle<()>),
    at_mark: impl FnOnce(u32),
) -> (Option<i32>, serde_json::Value) {
    use std::io::{BufRead, Read};
    use std::process::Stdio;
    let (addr, dev) = device;
    let mut child = bin()
        .args(["--json", "bridge", "--connect", &addr, "--loopback-only"])
        .args(["--domain-id", &domain.to_string()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = child.stdout.take().unwrap();
    let out = std::thread::spawn(move || {
        let mut v = Vec::new();
        stdout.read_to_end(&mut v).map(|_| v)
    });
    let (tx, rx) = std::sync::mpsc::channel();
    let stderr = std::io::BufReader::new(child.stderr.take().unwrap());
    let err = std::thread::spawn(move || {
        let mut all = String::new();
        for line in stderr.lines().map_while(Result::ok) {
            let _ = tx.send(line.clone());
            all.push_str(&line);
            all.push('\n');
        }
        all
    });
    let since = std::time::Instant::now();
    let mut marked = false;
    while !marked && since.elapsed() < EXIT_WAIT {
        match rx.recv_timeout(Duration::from_secs(1)) {
            Ok(line) => marked = line.contains("the device refused frame 7"),
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break,
        }
    }
    if !marked {
        let _ = child.kill();
        let _ = child.wait();
        panic!(
            "the bridge never handled the device's mark: {}",
            err.join().unwrap()
        );
    }
    at_mark(child.id());
    send_signal(child.id(), signal);
    let status = wait_exit(&mut child);
    let stderr = err.join().unwrap();
    let stdout = out.join().unwrap().unwrap();
    dev.join().unwrap();
    let report = serde_json::from_slice(&stdout).unwrap_or_else(|e| {
        panic!(
            "no JSON report ({e}): {}; stderr: {stderr}",
            String::from_utf8_lossy(&stdout)
        )
    });
    (status.code(), report)
}

#[test]
fn sigint_and_sigterm_stop_the_bridge_with_its_report_and_exit_0() {
    for (signal, name, domain) in [("INT", "SIGINT", 77), ("TERM", "SIGTERM", 78)] {
        let (code, r) = stopped_by(signal, domain);
        assert_eq!(code, Some(0), "{name}: {r}");
        assert_eq!(r["ended"], format!("signal ({name})"), "{r}");
        assert_eq!(r["exit_code"], 0, "{r}");
        // Every estimate sent before the signal went out, or was replaced by a newer one
        // before it could (the outbox's interval), and none failed.
        let published = r["poses"].as_u64().unwrap();
        let superseded = r["amcl_pose_outbox"]["superseded"].as_u64().unwrap();
        assert!(published >= 1, "{r}");
        assert_eq!(published + superseded, 5, "{r}");
        assert_eq!(r["amcl_pose_outbox"]["failed"], 0, "{r}");
        assert_eq!(r["device_errors"]["Refused"], 1, "{r}");
    }
}

/// The process of [`a_second_signal_during_the_stop_exits_at_once`]: takes SIGINT and SIGTERM
/// as the bridge does, signals itself once, says so on stdout, signals itself again and waits
/// (it prints `survived` and ends normally only if the second signal did not end it).
#[test]
#[ignore = "a helper process, started by a_second_signal_during_the_stop_exits_at_once"]
fn second_signal_process() {
    let stop = beamfield_bridge::stop::Stop::on_signals().unwrap();
    let me = std::process::id();
    send_signal(me, "INT");
    let since = std::time::Instant::now();
    while stop.requested().is_none() && since.elapsed() < EXIT_WAIT {
        std::thread::sleep(Duration::from_millis(5));
    }
    println!("stopping after {:?}", stop.requested().map(|s| s.name()));
    send_signal(me, "TERM");
    let since = std::time::Instant::now();
    while since.elapsed() < Duration::from_secs(30) {
        std::thread::sleep(Duration::from_millis(5));
    }
    println!("survived");
}

#[test]
fn a_second_signal_during_the_stop_exits_at_once() {
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "second_signal_process",
            "--ignored",
            "--nocapture",
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("stopping after Some(\"SIGINT\")"),
        "{stdout}"
    );
    assert!(!stdout.contains("survived"), "{stdout}");
    assert_eq!(
        out.status.code(),
        Some(i32::from(beamfield_bridge::stop::EXIT_FORCED_SIGTERM)),
        "{stdout}"
    );
}

/// A device that sends one initialized estimate per device time in `times_us`, 20 ms apart,
/// then closes the link.
fn device_with_times(times_us: Vec<u64>) -> (String, std::thread::JoinHandle<()>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let h = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        let mut enc = Encoder::new();
        let mut w = [0u8; MAX_WIRE_LEN];
        for (k, t) in times_us.into_iter().enumerate() {
            let m = Message::Estimate(Estimate {
                timestamp_us: t,
                pose: Pose::new(k as f32, 0.0, 0.0),
                flags: EstimateFlags::INITIALIZED,
                ess: 100.0,
                ..Estimate::default()
            });
            let len = enc.encode(&m, &mut w).unwrap();
            if s.write_all(&w[..len]).is_err() {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    });
    (addr, h)
}

#[test]
fn clock_device_goes_on_from_the_last_stamp_after_a_device_restart() {
    // 20 estimates 30 s into the device's uptime, then it restarts: its clock is back at 0.
    let times: Vec<u64> = (0..20u64)
        .map(|k| 30_000_000 + k * 20_000)
        .chain((0..20u64).map(|k| k * 20_000))
        .collect();
    let (addr, dev) = device_with_times(times);
    let out = bridge(&addr, 79, &["--clock", "device"]);
    dev.join().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(code(&out), Some(3), "{err}");
    let r = report(&out);
    assert_eq!(r["clock"]["restart"], 1, "{r}");
    assert_eq!(r["clock"]["non_increasing_refused"], 0, "{r}");
    // Held until 0.1 s of device time confirms: at 50 Hz five at the start and five while
    // the restart was confirmed.
    assert_eq!(r["clock"]["held_confirming"], 10, "{r}");
    let superseded = r["amcl_pose_outbox"]["superseded"].as_u64().unwrap();
    assert_eq!(r["poses"].as_u64().unwrap() + superseded, 30, "{r}");
    // The restart's stamps went on after 30.38 s of device time, not from 0.
    let shift = r["device_clock_shift_ns"].as_i64().unwrap();
    assert!(shift > 30_380_000_000, "{r}");
    assert!(
        err.contains("the device's time went back") && err.contains("--clock device"),
        "{err}"
    );
}

/// The peak resident memory of process `pid` (`VmHWM` in /proc), bytes.
fn peak_rss_bytes(pid: u32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    let kib: u64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or_else(|| panic!("no VmHWM in {status}"));
    kib * 1024
}

/// The bridge's memory bound (docs/nav2.md, "Queues and back-pressure").
const MAX_BRIDGE_RSS_BYTES: u64 = 64 << 20;

#[test]
fn a_flood_without_a_subscriber_keeps_the_bridge_within_64_mib() {
    // 1,000,000 estimates as fast as the socket takes them, nobody subscribed to amcl_pose.
    // Before the bounded link queue and the outbox's interval a flood of 2,000,000 peaked at
    // 1.16 GB, and at 252 MB with the bounded queue alone (the transient-local writer kept
    // every sample, about 126 bytes each): either regression exceeds the bound here.
    const FLOOD: u64 = 1_000_000;
    let _alone = HEAVY.write().unwrap_or_else(|p| p.into_inner());
    let device = device_paced_until_closed(FLOOD, Duration::ZERO);
    let mut peak = 0;
    let (code, r) = stopped_by_after("TERM", 80, device, |pid| peak = peak_rss_bytes(pid));
    eprintln!("peak RSS {peak} bytes; {r}");
    assert_eq!(code, Some(0), "{r}");
    assert!(
        peak <= MAX_BRIDGE_RSS_BYTES,
        "peak RSS {peak} bytes > {MAX_BRIDGE_RSS_BYTES}"
    );
    // Every estimate was read: published, superseded, dropped by the link queue, or not
    // stamped by the clock model (the flood's device time runs far ahead of the computer's,
    // and the stamps of a batch read at one instant are refused as not increasing).
    let o = &r["amcl_pose_outbox"];
    let c = &r["clock"];
    let handled: u64 = [
        &o["published"],
        &o["superseded"],
        &r["link_queue_dropped"],
        &c["non_increasing_refused"],
        &c["held_confirming"],
        &c["outlier_dropped"],
    ]
    .iter()
    .map(|v| v.as_u64().unwrap())
    .sum();
    assert_eq!(handled, FLOOD, "{r}");
}
