//! map → odom while the robot stands still: a fake device on a TCP port of 127.0.0.1 sends
//! estimates for 1 s, then only heartbeats for 3 s (a robot that does not move sends no
//! estimate), then nothing for 4 s with the link open, then closes it. A subscriber here, with
//! DDS on 127.0.0.1 only, receives `/tf`. The transform must keep coming while the heartbeats
//! do, the same transform, each stamped the computer's time plus `transform_tolerance` and later
//! than the one before; and it must stop once the device is silent.

mod common;
use common::frame;

use std::io::Write;
use std::net::TcpListener;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use beamfield::link::{Encoder, Estimate, EstimateFlags, Heartbeat, Message};
use beamfield::Pose;
use beamfield_bridge::msg::TfMessage;
use beamfield_bridge::port::now_ns;
use beamfield_bridge::repeat::DEVICE_SILENT_AFTER;
use beamfield_bridge::{run, BridgeArgs, ClockArg, Rmw};

const TOLERANCE_S: f64 = 0.5;
/// Largest |receive − (stamp − tolerance)| accepted, ns.
const MAX_LAG_NS: i128 = 200_000_000;

/// `/tf` as received here: (stamp ns, receive ns, x, y).
type Received = Vec<(i128, i128, f64, f64)>;

#[test]
fn map_to_odom_is_resent_while_the_device_is_alive_and_stops_when_it_is_silent() {
    let domain = 71;
    let mut node = common::loopback_node(domain, "tf_check");
    let sub = common::subscribe::<TfMessage>(&mut node, "tf", "tf2_msgs", "TFMessage", 10_000);
    let done = Arc::new(AtomicBool::new(false));
    let stop = Arc::clone(&done);
    let reader = std::thread::spawn(move || {
        let mut got = Received::new();
        while !stop.load(Ordering::Relaxed) {
            match sub.take() {
                Ok(Some((m, _))) => {
                    for t in m.transforms {
                        got.push((
                            i128::from(t.header.stamp.to_nanos().unwrap()),
                            i128::from(now_ns()),
                            t.transform.translation.x,
                            t.transform.translation.y,
                        ));
                    }
                }
                _ => std::thread::sleep(Duration::from_millis(1)),
            }
        }
        got
    });

    // The phases, on this process's clock from the device's start.
    let estimates_until = Duration::from_secs(1);
    let heartbeats_until = Duration::from_secs(4);
    let silent_until = Duration::from_secs(8);
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let device = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        let start = Instant::now();
        let t0_us = 30_000_000u64;
        let device_us = |at: Duration| t0_us + at.as_micros() as u64;
        let mut enc = Encoder::new();
        // Estimates at 10 Hz: the robot at (2, 1) in the map, 0.5 m along its odometry.
        while start.elapsed() < estimates_until {
            let e = Message::Estimate(Estimate {
                timestamp_us: device_us(start.elapsed()),
                pose: Pose::new(2.0, 1.0, 0.0),
                odometry: Pose::new(0.5, 0.0, 0.0),
                flags: EstimateFlags::INITIALIZED,
                ess: 100.0,
                ..Estimate::default()
            });
            s.write_all(&frame(&mut enc, &e)).unwrap();
            std::thread::sleep(Duration::from_millis(100));
        }
        // Standing still: a heartbeat every 0.5 s.
        while start.elapsed() < heartbeats_until {
            let h = Message::Heartbeat(Heartbeat {
                timestamp_us: device_us(start.elapsed()),
                ..Heartbeat::default()
            });
            s.write_all(&frame(&mut enc, &h)).unwrap();
            std::thread::sleep(Duration::from_millis(500));
        }
        let silent_from = now_ns();
        std::thread::sleep(silent_until.saturating_sub(start.elapsed()));
        drop(s);
        silent_from
    });
    let dir = std::env::temp_dir().join(format!("bf-tf-repeat-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let params = dir.join("nav2.yaml");
    std::fs::write(
        &params,
        format!("amcl:\n  ros__parameters:\n    transform_tolerance: {TOLERANCE_S}\n"),
    )
    .unwrap();
    let args = BridgeArgs {
        connect: Some(addr),
        serial: None,
        baud: 230_400,
        params: Some(params),
        namespace: "/".into(),
        lifecycle: false,
        domain_id: domain,
        loopback_only: true,
        rmw: Rmw::Fastrtps,
        clock: ClockArg::Host,
        seconds: Some(60.0),
    };
    let report = run(&args).unwrap_or_else(|e| panic!("the bridge stopped: {e}"));
    std::thread::sleep(Duration::from_millis(300));
    done.store(true, Ordering::Relaxed);
    let got = reader.join().unwrap();
    let silent_from = i128::from(device.join().unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
    eprintln!("{report}");

    assert!(!got.is_empty(), "no transform received");
    // One transform throughout: map → odom = (2, 1) − (0.5, 0).
    for g in &got {
        assert!(
            (g.2 - 1.5).abs() < 1e-6 && (g.3 - 1.0).abs() < 1e-6,
            "{g:?}"
        );
    }
    for w in got.windows(2) {
        assert!(w[1].0 > w[0].0, "stamps not increasing: {w:?}");
    }
    let tolerance_ns = (TOLERANCE_S * 1e9) as i128;
    // While only heartbeats came (after the last estimate's transform, until the silence):
    // about 10 Hz, each stamped the time it was sent plus the tolerance.
    let first = got[0].1;
    let standing: Vec<_> = got
        .iter()
        .filter(|g| g.1 > first + 1_300_000_000 && g.1 < silent_from)
        .collect();
    assert!(
        standing.len() >= 15,
        "{} transforms while the robot stood still: {got:?}",
        standing.len()
    );
    for g in &standing {
        let lag = g.1 - (g.0 - tolerance_ns);
        assert!(
            (-1_000_000..=MAX_LAG_NS).contains(&lag),
            "received {lag} ns after its stamp less the tolerance: {g:?}"
        );
    }
    // Silent: nothing once the device has been silent for DEVICE_SILENT_AFTER (and a margin).
    let gone = silent_from + DEVICE_SILENT_AFTER.as_nanos() as i128 + 200_000_000;
    let late: Vec<_> = got.iter().filter(|g| g.1 > gone).collect();
    assert!(
        late.is_empty(),
        "sent after the device fell silent: {late:?}"
    );
    assert!(report.transforms_repeated >= standing.len() as u64);
}
