//! The bridge as a managed node: run with `--lifecycle` against a fake device on a TCP port of
//! 127.0.0.1 (estimates at 20 Hz), driven from here through `amcl/get_state`,
//! `amcl/change_state`, `amcl/get_available_states` and `amcl/get_available_transitions` with
//! the lifecycle_msgs types, DDS on 127.0.0.1 only. `amcl_pose` must come only while the node
//! is active.

mod common;

use std::io::Write;
use std::net::TcpListener;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use beamfield::link::{Encoder, Estimate, EstimateFlags, Message, MAX_WIRE_LEN};
use beamfield::Pose;
use beamfield_bridge::msg::{
    ChangeStateRequest, ChangeStateResponse, Empty, GetAvailableStatesResponse,
    GetAvailableTransitionsResponse, GetStateResponse, LifecycleTransition,
    PoseWithCovarianceStamped,
};
use beamfield_bridge::{run, BridgeArgs, ClockArg, Rmw, EXIT_STOPPED};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{
    Client, Message as RosMessage, Name, Node, QosProfile, ServiceMapping, ServiceTypeName,
};

/// Calls `client` with `req` until an answer comes (service discovery takes a moment), at most
/// 20 s.
fn call<Q: RosMessage + Clone + 'static, A: RosMessage + 'static>(
    client: &Client<Q, A>,
    req: Q,
) -> A {
    let deadline = Instant::now() + Duration::from_secs(20);
    while Instant::now() < deadline {
        if let Ok(id) = client.send_request(req.clone()) {
            let until = Instant::now() + Duration::from_millis(500);
            while Instant::now() < until {
                if let Ok(Some((got, a))) = client.receive_response() {
                    if got == id {
                        return a;
                    }
                }
                std::thread::sleep(Duration::from_millis(5));
            }
        }
    }
    panic!("no answer in 20 s");
}

fn client<Q: RosMessage + Clone + 'static, A: RosMessage + 'static>(
    node: &mut Node,
    name: &str,
    srv: &str,
) -> Client<Q, A> {
    let qos = QosProfile::publisher_default()
        .reliability_reliable(WhenFull::DEFAULT)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 });
    node.create_client(
        ServiceMapping::Enhanced,
        &Name::new("/amcl", name).unwrap(),
        &ServiceTypeName::new("lifecycle_msgs", srv),
        qos.clone(),
        qos,
    )
    .unwrap()
}

fn transition(label: &str) -> ChangeStateRequest {
    ChangeStateRequest {
        transition: LifecycleTransition {
            id: 0,
            label: label.into(),
        },
    }
}

#[test]
fn the_lifecycle_services_drive_the_node_and_poses_come_only_while_active() {
    let domain = 72;
    let mut node = common::loopback_node(domain, "lifecycle_manager_check");
    let poses = common::subscribe::<PoseWithCovarianceStamped>(
        &mut node,
        "amcl_pose",
        "geometry_msgs",
        "PoseWithCovarianceStamped",
        1000,
    );
    let get_state: Client<Empty, GetStateResponse> = client(&mut node, "get_state", "GetState");
    let change: Client<ChangeStateRequest, ChangeStateResponse> =
        client(&mut node, "change_state", "ChangeState");
    let states: Client<Empty, GetAvailableStatesResponse> =
        client(&mut node, "get_available_states", "GetAvailableStates");
    let transitions: Client<Empty, GetAvailableTransitionsResponse> = client(
        &mut node,
        "get_available_transitions",
        "GetAvailableTransitions",
    );

    // Poses received, counted by a reader thread.
    let received = Arc::new(AtomicUsize::new(0));
    let done = Arc::new(AtomicBool::new(false));
    let (count, stop) = (Arc::clone(&received), Arc::clone(&done));
    let reader = std::thread::spawn(move || {
        while !stop.load(Ordering::Relaxed) {
            match poses.take() {
                Ok(Some(_)) => {
                    count.fetch_add(1, Ordering::Relaxed);
                }
                _ => std::thread::sleep(Duration::from_millis(1)),
            }
        }
    });

    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let device_done = Arc::new(AtomicBool::new(false));
    let device_stop = Arc::clone(&device_done);
    let device = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        let mut enc = Encoder::new();
        let start = Instant::now();
        while !device_stop.load(Ordering::Relaxed) {
            let m = Message::Estimate(Estimate {
                timestamp_us: 5_000_000 + start.elapsed().as_micros() as u64,
                pose: Pose::new(1.0, 2.0, 0.0),
                flags: EstimateFlags::INITIALIZED,
                ess: 100.0,
                ..Estimate::default()
            });
            let mut w = [0u8; MAX_WIRE_LEN];
            let n = enc.encode(&m, &mut w).unwrap();
            if s.write_all(&w[..n]).is_err() {
                return;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    });
    let args = BridgeArgs {
        connect: Some(addr),
        serial: None,
        baud: 230_400,
        params: None,
        namespace: "/".into(),
        lifecycle: true,
        domain_id: domain,
        loopback_only: true,
        rmw: Rmw::Fastrtps,
        clock: ClockArg::Host,
        seconds: Some(120.0),
    };
    let bridge = std::thread::spawn(move || run(&args));

    let state = || call(&get_state, Empty::default()).current_state;
    assert_eq!((state().id, state().label), (1, "unconfigured".into()));
    let all = call(&states, Empty::default()).available_states;
    assert_eq!(all.len(), 11, "{all:?}");
    let ids: Vec<u8> = call(&transitions, Empty::default())
        .available_transitions
        .iter()
        .map(|t| t.transition.id)
        .collect();
    assert_eq!(ids, [1, 5]);
    // Unconfigured and inactive: no pose.
    std::thread::sleep(Duration::from_millis(1000));
    assert!(call(&change, transition("configure")).success);
    assert_eq!(state().label, "inactive");
    std::thread::sleep(Duration::from_millis(1000));
    assert_eq!(
        received.load(Ordering::Relaxed),
        0,
        "poses before activation"
    );
    // Not from inactive.
    assert!(!call(&change, transition("deactivate")).success);
    assert_eq!(state().label, "inactive");
    // By id: activate is 3.
    let activate = ChangeStateRequest {
        transition: LifecycleTransition {
            id: 3,
            label: String::new(),
        },
    };
    assert!(call(&change, activate).success);
    assert_eq!(state().label, "active");
    std::thread::sleep(Duration::from_millis(1500));
    let while_active = received.load(Ordering::Relaxed);
    assert!(while_active >= 10, "{while_active} poses while active");
    assert!(call(&change, transition("deactivate")).success);
    // What was in flight lands; then nothing more.
    std::thread::sleep(Duration::from_millis(300));
    let at_deactivation = received.load(Ordering::Relaxed);
    std::thread::sleep(Duration::from_millis(1500));
    assert_eq!(
        received.load(Ordering::Relaxed),
        at_deactivation,
        "poses after deactivation"
    );
    assert!(call(&change, transition("shutdown")).success);

    let report = bridge.join().unwrap().unwrap();
    device_done.store(true, Ordering::Relaxed);
    done.store(true, Ordering::Relaxed);
    reader.join().unwrap();
    device.join().unwrap();
    eprintln!("{report}");
    assert_eq!(report.exit_code(), EXIT_STOPPED);
    assert_eq!(report.lifecycle_state, "finalized");
    assert_eq!(
        report.lifecycle_transitions,
        [
            "unconfigured -> inactive",
            "inactive -> active",
            "active -> inactive",
            "inactive -> finalized"
        ]
    );
    assert!(report.not_active > 0);
    assert_eq!(report.poses as usize, at_deactivation);
}
