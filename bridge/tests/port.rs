//! The bridge's link reader against a device that garbles and drops bytes: every intact frame
//! arrives, every broken one is refused and counted, and the reader keeps going.

mod common;
use common::frame;

use beamfield::link::{Encoder, Estimate, EstimateFlags, Heartbeat, Message};
use beamfield::Pose;
use beamfield_bridge::port::{Endpoint, Incoming, Port};
use std::io::Write;
use std::net::TcpListener;
use std::time::{Duration, Instant};

#[test]
fn garbled_and_cut_frames_are_counted_and_the_rest_arrives() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap();
    let device = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        let mut enc = Encoder::new();
        let mut bytes = Vec::new();
        for k in 0..20u64 {
            let e = Message::Estimate(Estimate {
                timestamp_us: 1_000_000 + k * 100_000,
                pose: Pose::new(k as f32 * 0.1, 1.0, 0.5),
                flags: EstimateFlags::INITIALIZED,
                ess: 100.0,
                ..Estimate::default()
            });
            let mut f = frame(&mut enc, &e);
            match k {
                // A flipped bit in the COBS bytes: the frame does not decode.
                3 => f[10] ^= 0x04,
                // Cut short: the rest of the frame is lost, the next delimiter ends it.
                7 => f.truncate(f.len() / 2),
                _ => {}
            }
            bytes.extend_from_slice(&f);
            if k == 11 {
                // Line noise ending in a delimiter.
                bytes.extend_from_slice(&[0x13, 0x37, 0xff, 0x00]);
            }
        }
        bytes.extend_from_slice(&frame(
            &mut enc,
            &Message::Heartbeat(Heartbeat {
                timestamp_us: 3_000_000,
                ..Heartbeat::default()
            }),
        ));
        // In small pieces, as a UART delivers them.
        for piece in bytes.chunks(7) {
            s.write_all(piece).unwrap();
        }
    });
    let port = Port::open(&Endpoint::Tcp(addr.to_string())).unwrap();
    let (mut estimates, mut refused, mut heartbeats) = (Vec::new(), 0, 0);
    let started = Instant::now();
    'read: while started.elapsed() < Duration::from_secs(20) {
        for item in port.receive(Duration::from_millis(50)) {
            match item {
                Incoming::Frame {
                    message: Message::Estimate(e),
                    ..
                } => estimates.push(e.timestamp_us),
                Incoming::Frame {
                    message: Message::Heartbeat(_),
                    ..
                } => heartbeats += 1,
                Incoming::Frame { message, .. } => panic!("unexpected {message:?}"),
                Incoming::Refused(_) => refused += 1,
                Incoming::Closed { error, stats } => {
                    assert!(error.is_none(), "{error:?}");
                    // 17 estimates and the heartbeat; the decoder also saw the sequence gaps.
                    assert_eq!(stats.frames, 18, "{stats:?}");
                    assert_eq!(stats.sequence_gaps, 2, "{stats:?}");
                    break 'read;
                }
            }
        }
    }
    device.join().unwrap();
    // 18 of 20 estimates intact (frames 3 and 7 broken); the cut frame 7 runs into frame 8's
    // bytes up to its delimiter, so frame 8 is lost with it.
    let want: Vec<u64> = (0..20u64)
        .filter(|k| ![3, 7, 8].contains(k))
        .map(|k| 1_000_000 + k * 100_000)
        .collect();
    assert_eq!(estimates, want);
    assert_eq!(heartbeats, 1);
    // The flipped bit, the cut frame with its neighbour, the noise.
    assert_eq!(refused, 3);
}

/// A serial port whose other end hangs up (a USB adapter unplugged): the bridge ends with the
/// link-lost code and its report, so that a supervisor restarts it.
#[test]
fn a_serial_hang_up_ends_the_bridge_with_the_link_lost_code() {
    use beamfield_bridge::{run, BridgeArgs, ClockArg, Rmw, EXIT_LINK_LOST};
    use serialport::SerialPort;
    use std::io::Read;

    let (mut master, slave) = serialport::TTYPort::pair().unwrap();
    let path = slave.name().unwrap();
    // With no slave open the master reads a hang-up; once the bridge opens the port, it reads
    // a timeout. The bridge sends nothing at start without a params file, so the hang-up
    // below comes while it runs (during its start it would fail to start, exit 1).
    drop(slave);
    let args = BridgeArgs {
        connect: None,
        serial: Some(path),
        baud: 230_400,
        params: None,
        namespace: "/".into(),
        lifecycle: false,
        domain_id: 67,
        loopback_only: true,
        rmw: Rmw::Fastrtps,
        clock: ClockArg::Host,
        seconds: Some(120.0),
    };
    let bridge = std::thread::spawn(move || run(&args));
    let mut buf = [0u8; 256];
    let started = Instant::now();
    let mut opened = false;
    while !opened && started.elapsed() < Duration::from_secs(60) {
        match master.read(&mut buf) {
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => opened = true,
            _ => std::thread::sleep(Duration::from_millis(5)),
        }
    }
    assert!(opened, "the bridge never opened the port");
    let mut enc = Encoder::new();
    for k in 0..3u64 {
        let e = Message::Estimate(Estimate {
            timestamp_us: 1_000_000 + k * 100_000,
            pose: Pose::new(1.0, 2.0, 0.0),
            flags: EstimateFlags::INITIALIZED,
            ess: 100.0,
            ..Estimate::default()
        });
        master.write_all(&frame(&mut enc, &e)).unwrap();
    }
    // The other end goes away.
    drop(master);
    let report = bridge
        .join()
        .unwrap()
        .unwrap_or_else(|e| panic!("the bridge stopped: {e}"));
    eprintln!("{report}");
    assert_eq!(report.exit_code(), EXIT_LINK_LOST, "{report}");
    assert!(
        report.ended.contains("reading the link failed")
            || report.ended.contains("the device closed the link"),
        "{}",
        report.ended
    );
}
