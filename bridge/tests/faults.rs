//! The bridge against a faulty device: a fake device on a TCP port of 127.0.0.1 plays a
//! script (a restart, a stall, one estimate stamped far ahead, a flood, a reset link), the
//! bridge runs in this process with DDS on 127.0.0.1 only, and a subscriber here receives
//! `amcl_pose`. Every stamp received must be later than the one before and, on the computer's
//! clock, within 0.2 s of when it was received; the bridge must end with the link-lost code.

mod common;

use std::io::Write;
use std::net::{TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use beamfield::link::{Encoder, Estimate, EstimateFlags, Message, MAX_WIRE_LEN};
use beamfield::Pose;
use beamfield_bridge::msg::{Header, PoseWithCovarianceStamped, Time};
use beamfield_bridge::outbox::Outbox;
use beamfield_bridge::port::now_ns;
use beamfield_bridge::ros::{NodeConfig, RosNode};
use beamfield_bridge::{run, BridgeArgs, BridgeReport, ClockArg, Rmw, EXIT_LINK_LOST};
use ros2_client::{Node, Subscription};

/// One DDS run at a time: the machine has few cores and discovery is timing-sensitive.
static SERIAL: Mutex<()> = Mutex::new(());

/// Largest |receive − stamp| accepted, ns.
const MAX_LAG_NS: i128 = 200_000_000;

/// What the fake device does.
#[derive(Clone, Copy, Debug)]
enum Step {
    /// An initialized estimate with this device time (µs); its index goes in its pose.
    Estimate(u64),
    Sleep(Duration),
    /// Stops a process (SIGSTOP): a subscriber that hangs.
    Freeze(u32),
}

fn estimate(enc: &mut Encoder, index: u32, device_us: u64) -> Vec<u8> {
    let m = Message::Estimate(Estimate {
        timestamp_us: device_us,
        // The index in metres, x the units and y the thousands (the link takes 100 km at most).
        pose: Pose::new((index % 1000) as f32, (index / 1000) as f32, 0.5),
        flags: EstimateFlags::INITIALIZED,
        ess: 100.0,
        ..Estimate::default()
    });
    let mut w = [0u8; MAX_WIRE_LEN];
    let n = enc.encode(&m, &mut w).unwrap();
    w[..n].to_vec()
}

/// Estimates every 50 ms from `from_us`, `n` of them.
fn paced(from_us: u64, n: u64) -> Vec<Step> {
    (0..n)
        .flat_map(|k| {
            [
                Step::Estimate(from_us + k * 50_000),
                Step::Sleep(Duration::from_millis(50)),
            ]
        })
        .collect()
}

/// The fake device: accepts the bridge, plays `script`, then resets the connection (`reset`)
/// or closes it. Returns how many estimates it wrote (it stops when the bridge goes away).
fn device(script: Vec<Step>, reset: bool) -> (String, std::thread::JoinHandle<u32>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let h = std::thread::spawn(move || {
        let (mut s, _): (TcpStream, _) = listener.accept().unwrap();
        let mut enc = Encoder::new();
        let mut index = 0u32;
        let mut batch = Vec::new();
        for step in script {
            match step {
                Step::Estimate(t) => {
                    batch.extend(estimate(&mut enc, index, t));
                    index += 1;
                }
                Step::Sleep(d) => {
                    // The bridge went away: the device stops there.
                    if s.write_all(&batch).is_err() {
                        return index;
                    }
                    batch.clear();
                    std::thread::sleep(d);
                }
                Step::Freeze(pid) => {
                    let stopped = std::process::Command::new("kill")
                        .args(["-STOP", &pid.to_string()])
                        .status()
                        .unwrap();
                    assert!(stopped.success());
                }
            }
            if batch.len() >= 1 << 16 {
                if s.write_all(&batch).is_err() {
                    return index;
                }
                batch.clear();
            }
        }
        if s.write_all(&batch).is_err() {
            return index;
        }
        if reset {
            // A zero linger turns the close into a reset.
            socket2::SockRef::from(&s)
                .set_linger(Some(Duration::ZERO))
                .unwrap();
        }
        drop(s);
        index
    });
    (addr, h)
}

/// `amcl_pose` as received here: (index, stamp ns, receive ns).
type Received = Vec<(u32, i128, i128)>;

/// A node on `domain` (DDS on 127.0.0.1 only) subscribed to `amcl_pose`.
fn subscriber(domain: u16) -> (Node, Subscription<PoseWithCovarianceStamped>) {
    let mut node = common::loopback_node(domain, "fault_check");
    let sub = common::subscribe(
        &mut node,
        "amcl_pose",
        "geometry_msgs",
        "PoseWithCovarianceStamped",
        10_000,
    );
    (node, sub)
}

/// Runs the bridge against the device's script with a subscriber on `domain`; returns the
/// bridge's result and what the subscriber received.
fn scenario(domain: u16, script: Vec<Step>, reset: bool) -> (BridgeReport, Received, u32) {
    let _one = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let (node, sub) = subscriber(domain);
    let done = Arc::new(AtomicBool::new(false));
    let stop = Arc::clone(&done);
    let reader = std::thread::spawn(move || {
        let mut got = Received::new();
        let mut quiet_since: Option<Instant> = None;
        loop {
            match sub.take() {
                Ok(Some((m, _))) => {
                    got.push((
                        m.pose.pose.position.x as u32 + 1000 * m.pose.pose.position.y as u32,
                        i128::from(m.header.stamp.to_nanos().unwrap()),
                        i128::from(now_ns()),
                    ));
                    quiet_since = None;
                }
                _ => {
                    if stop.load(Ordering::Relaxed) {
                        // Whatever is still in flight gets half a second.
                        let q = *quiet_since.get_or_insert_with(Instant::now);
                        if q.elapsed() > Duration::from_millis(500) {
                            return got;
                        }
                    }
                    std::thread::sleep(Duration::from_millis(1));
                }
            }
        }
    });
    // Discovery first: the device starts when the bridge connects, and its first two seconds
    // are a warm-up the checks do not depend on.
    let (addr, device) = device(script, reset);
    let args = BridgeArgs {
        connect: Some(addr),
        serial: None,
        baud: 230_400,
        params: None,
        namespace: "/".into(),
        lifecycle: false,
        domain_id: domain,
        loopback_only: true,
        rmw: Rmw::Fastrtps,
        clock: ClockArg::Host,
        seconds: Some(120.0),
    };
    let report = run(&args).unwrap_or_else(|e| panic!("the bridge stopped: {e}"));
    done.store(true, Ordering::Relaxed);
    let got = reader.join().unwrap();
    let sent = device.join().unwrap();
    drop(node);
    eprintln!("{report}");
    (report, got, sent)
}

/// Stamps strictly increasing; from estimate `settled_from` on, within [`MAX_LAG_NS`] of their
/// receipt (and none after it); at least `want_after` of those received.
fn check_stamps(got: &Received, settled_from: u32, want_after: usize) {
    for w in got.windows(2) {
        assert!(
            w[1].1 > w[0].1,
            "estimate {} stamped {} ns, not after estimate {} at {} ns",
            w[1].0,
            w[1].1,
            w[0].0,
            w[0].1
        );
    }
    let lags: Vec<i128> = got
        .iter()
        .filter(|g| g.0 >= settled_from)
        .map(|g| g.2 - g.1)
        .collect();
    eprintln!(
        "{} estimates received, {} from {settled_from} on: receive − stamp from {:?} to {:?} ns",
        got.len(),
        lags.len(),
        lags.iter().min(),
        lags.iter().max()
    );
    let mut after = 0;
    for (i, stamp, recv) in got {
        if *i >= settled_from {
            after += 1;
            let lag = recv - stamp;
            assert!(
                (-1_000_000..=MAX_LAG_NS).contains(&lag),
                "estimate {i}: received {lag} ns after its stamp"
            );
        }
    }
    assert!(
        after >= want_after,
        "{after} estimates received from {settled_from} on: {got:?}"
    );
}

/// 40 estimates (2 s) on the device's clock from `t0_us`.
fn warm_up(t0_us: u64) -> Vec<Step> {
    paced(t0_us, 40)
}

#[test]
fn a_device_restart_is_followed() {
    // 20 s of uptime, 2 s of estimates, then the device restarts: its clock is back near 0.
    let mut script = warm_up(20_000_000);
    script.extend(paced(50_000, 40));
    let (report, got, sent) = scenario(61, script, false);
    assert_eq!(sent, 80);
    // Three estimates confirm the restart; the fourth on is stamped on the new anchor.
    check_stamps(&got, 40 + 3, 30);
    let clock = report.clock.unwrap();
    assert_eq!(clock.restart, 1, "{report}");
    assert_eq!(clock.non_increasing_refused, 0, "{report}");
    assert_eq!(report.exit_code(), EXIT_LINK_LOST, "{report}");
}

#[test]
fn a_device_stall_is_followed() {
    // The device, its clock with it, stops for 1.5 s.
    let mut script = warm_up(1_000_000);
    script.push(Step::Sleep(Duration::from_millis(1_500)));
    script.extend(paced(1_000_000 + 40 * 50_000, 40));
    let (report, got, _) = scenario(62, script, false);
    check_stamps(&got, 40 + 3, 30);
    let clock = report.clock.unwrap();
    assert_eq!(clock.jump_back, 1, "{report}");
    assert_eq!(report.exit_code(), EXIT_LINK_LOST, "{report}");
}

#[test]
fn one_estimate_stamped_far_ahead_is_dropped() {
    let mut script = warm_up(1_000_000);
    // 10^9 s ahead, once.
    script.push(Step::Estimate(1_000_000_000_000_000));
    script.push(Step::Sleep(Duration::from_millis(50)));
    script.extend(paced(1_000_000 + 41 * 50_000, 40));
    let (report, got, _) = scenario(63, script, false);
    // From estimate 20 on: the first ones can wait for discovery on the subscriber's side.
    check_stamps(&got, 20, 50);
    assert!(
        got.iter().all(|g| g.0 != 40),
        "the wild estimate was published"
    );
    let clock = report.clock.unwrap();
    assert_eq!(clock.outlier_dropped, 1, "{report}");
    assert_eq!(clock.jump_forward + clock.jump_back + clock.restart, 0);
}

#[test]
fn a_flood_keeps_stamps_increasing_and_a_reset_link_ends_with_the_link_lost_code() {
    let mut script = warm_up(1_000_000);
    // 150,000 estimates 1 µs apart on the device's clock, as fast as the socket takes them.
    script.extend((0..150_000u64).map(|k| Step::Estimate(3_000_000 + k)));
    script.push(Step::Sleep(Duration::from_millis(200)));
    // Then the device goes on normally.
    script.extend(paced(3_200_000, 20));
    let (report, got, sent) = scenario(64, script, true);
    assert_eq!(sent, 150_060);
    assert_eq!(report.exit_code(), EXIT_LINK_LOST, "{report}");
    assert!(
        report.ended.contains("the link was lost") || report.ended.contains("reading"),
        "{}",
        report.ended
    );
    // Stamps stay increasing through the flood; the normal estimates after it arrive.
    check_stamps(&got, u32::MAX, 0);
    assert!(
        got.iter().any(|g| g.0 >= 150_040),
        "no estimate after the flood was received"
    );
}

/// The subscriber process of [`a_flood_with_a_hung_subscriber_is_survived`]: it subscribes,
/// says so on stdout and waits to be stopped.
#[test]
#[ignore = "a helper process, started by a_flood_with_a_hung_subscriber_is_survived"]
fn hung_subscriber_process() {
    let domain: u16 = std::env::var("BEAMFIELD_HUNG_SUBSCRIBER_DOMAIN")
        .expect("started by a_flood_with_a_hung_subscriber_is_survived")
        .parse()
        .unwrap();
    let (_node, sub) = subscriber(domain);
    println!("subscribed");
    let started = Instant::now();
    while started.elapsed() < Duration::from_secs(120) {
        let _ = sub.take();
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Starts [`hung_subscriber_process`] on `domain` and waits until it has subscribed.
fn spawn_hung_subscriber(domain: u16) -> std::process::Child {
    use std::io::BufRead;
    let mut child = std::process::Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "hung_subscriber_process",
            "--ignored",
            "--nocapture",
        ])
        .env("BEAMFIELD_HUNG_SUBSCRIBER_DOMAIN", domain.to_string())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = std::io::BufReader::new(child.stdout.take().unwrap()).lines();
    assert!(lines.any(|l| l.is_ok_and(|l| l == "subscribed")));
    child
}

#[test]
fn a_flood_with_a_hung_subscriber_is_survived() {
    let _one = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let domain = 65;
    let mut child = spawn_hung_subscriber(domain);
    // Two seconds of normal estimates (discovery), the subscriber hangs, then a flood.
    let mut script = warm_up(1_000_000);
    script.push(Step::Freeze(child.id()));
    script.extend((0..150_000u64).map(|k| Step::Estimate(3_000_000 + k)));
    script.push(Step::Sleep(Duration::from_millis(200)));
    let (addr, device) = device(script, false);
    let args = BridgeArgs {
        connect: Some(addr),
        serial: None,
        baud: 230_400,
        params: None,
        namespace: "/".into(),
        lifecycle: false,
        domain_id: domain,
        loopback_only: true,
        rmw: Rmw::Fastrtps,
        clock: ClockArg::Host,
        seconds: Some(120.0),
    };
    let result = run(&args);
    child.kill().unwrap();
    child.wait().unwrap();
    let report = result.unwrap_or_else(|e| panic!("the bridge stopped: {e}"));
    eprintln!("{report}");
    // The device wrote everything: the bridge kept reading to the end of the link.
    assert_eq!(device.join().unwrap(), 150_040);
    assert_eq!(report.exit_code(), EXIT_LINK_LOST, "{report}");
    assert!(report.poses > 0, "{report}");
    assert_eq!(report.amcl_pose_outbox.failed, 0, "{report}");
}

#[test]
fn a_full_window_is_handed_back_and_retried() {
    let _one = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let domain = 66;
    let mut child = spawn_hung_subscriber(domain);
    let node = RosNode::new(&NodeConfig {
        domain_id: domain,
        name: "amcl".into(),
        namespace: "/".into(),
        loopback_only: true,
        service_mapping: ros2_client::ServiceMapping::Enhanced,
    })
    .unwrap();
    let pose = |k: u32| PoseWithCovarianceStamped {
        header: Header {
            stamp: Time::from_nanos(u64::from(k) + 1),
            frame_id: "map".into(),
        },
        ..PoseWithCovarianceStamped::default()
    };
    // Discovery, then the subscriber hangs: nothing is acknowledged from there on.
    let mut outbox = Outbox::new(Duration::ZERO);
    for k in 0..20 {
        outbox
            .offer(pose(k), Instant::now(), |m| node.publish_pose(m))
            .unwrap();
        std::thread::sleep(Duration::from_millis(100));
    }
    let stopped = std::process::Command::new("kill")
        .args(["-STOP", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(stopped.success());
    // More than the writer's window of unacknowledged samples.
    for k in 20..20_000 {
        outbox
            .offer(pose(k), Instant::now(), |m| node.publish_pose(m))
            .unwrap();
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let c = outbox.counters;
    eprintln!("{c:?}");
    // The window filled: writes were refused at once, the newest kept, nothing failed.
    assert!(c.would_block > 0, "{c:?}");
    assert!(outbox.is_pending());
    assert_eq!(c.failed, 0);
    assert_eq!(c.published + c.superseded + 1, 20_000, "{c:?}");
}
