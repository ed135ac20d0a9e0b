//! A faulty device on a TCP port of 127.0.0.1, for measuring `beamfield bridge` against it:
//!
//! ```sh
//! cargo run -p beamfield-bridge --example fault_device -- 7400 flood 3000000 &
//! beamfield bridge --connect 127.0.0.1:7400 --loopback-only
//! ```
//!
//! Scenarios (estimates every 50 ms unless said otherwise, after 2 s of normal ones):
//! - `flood N`: N estimates as fast as the socket takes them, then 1 s of normal ones;
//! - `restart`: the device restarts (its clock back near 0) after 20 s of uptime;
//! - `stall S`: the device and its clock stop for S seconds;
//! - `jump`: one estimate stamped 10⁹ s ahead;
//! - `slow S`: S seconds of a device clock 0.5 % slow.
//!
//! The link is closed at the end (`reset` as a last argument resets it instead).

use std::io::Write;
use std::net::{TcpListener, TcpStream};
use std::time::Duration;

use beamfield::link::{Encoder, Estimate, EstimateFlags, Message, MAX_WIRE_LEN};
use beamfield::Pose;

struct Device {
    s: TcpStream,
    enc: Encoder,
    sent: u64,
    buf: Vec<u8>,
}

impl Device {
    /// Queues an estimate at `t_us` on the device's clock.
    fn estimate(&mut self, t_us: u64) {
        let m = Message::Estimate(Estimate {
            timestamp_us: t_us,
            pose: Pose::new((self.sent % 1000) as f32, 1.0, 0.5),
            flags: EstimateFlags::INITIALIZED,
            ess: 100.0,
            ..Estimate::default()
        });
        let mut w = [0u8; MAX_WIRE_LEN];
        let n = self.enc.encode(&m, &mut w).expect("a valid estimate");
        self.buf.extend_from_slice(&w[..n]);
        self.sent += 1;
        if self.buf.len() >= 1 << 16 {
            self.flush();
        }
    }

    fn flush(&mut self) {
        if let Err(e) = self.s.write_all(&self.buf) {
            eprintln!("fault_device: the bridge went away: {e}");
            std::process::exit(0);
        }
        self.buf.clear();
    }

    /// `n` estimates 50 ms apart in real time, the device's clock from `from_us` at `rate`
    /// device seconds per second; returns the device time after them.
    fn paced(&mut self, from_us: u64, n: u64, rate: f64) -> u64 {
        let step = (50_000.0 * rate) as u64;
        for k in 0..n {
            self.estimate(from_us + k * step);
            self.flush();
            std::thread::sleep(Duration::from_millis(50));
        }
        from_us + n * step
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: fault_device PORT flood N | restart | stall S | jump | slow S [reset]";
    let (Some(port), Some(scenario)) = (args.first(), args.get(1)) else {
        eprintln!("{usage}");
        std::process::exit(2);
    };
    let number = |i: usize| -> f64 {
        args.get(i).and_then(|a| a.parse().ok()).unwrap_or_else(|| {
            eprintln!("{usage}");
            std::process::exit(2)
        })
    };
    let listener = TcpListener::bind(format!("127.0.0.1:{port}")).expect("the port is free");
    eprintln!("fault_device: waiting on 127.0.0.1:{port}");
    let (s, _) = listener.accept().expect("a connection");
    s.set_nodelay(true).ok();
    let mut d = Device {
        s,
        enc: Encoder::new(),
        sent: 0,
        buf: Vec::new(),
    };
    let uptime = if scenario == "restart" {
        20_000_000
    } else {
        1_000_000
    };
    let t = d.paced(uptime, 40, 1.0);
    match scenario.as_str() {
        "flood" => {
            let n = number(2) as u64;
            for k in 0..n {
                d.estimate(t + k);
            }
            d.flush();
            d.paced(t + n + 50_000, 20, 1.0);
        }
        "restart" => {
            d.paced(50_000, 100, 1.0);
        }
        "stall" => {
            std::thread::sleep(Duration::from_secs_f64(number(2)));
            d.paced(t, 100, 1.0);
        }
        "jump" => {
            d.estimate(1_000_000_000_000_000);
            d.flush();
            d.paced(t + 50_000, 100, 1.0);
        }
        "slow" => {
            let n = (number(2) * 20.0) as u64;
            d.paced(t, n, 0.995);
        }
        other => {
            eprintln!("fault_device: no scenario {other:?}; {usage}");
            std::process::exit(2);
        }
    }
    d.flush();
    if args.last().map(String::as_str) == Some("reset") {
        socket2::SockRef::from(&d.s)
            .set_linger(Some(Duration::ZERO))
            .ok();
    }
    eprintln!("fault_device: {} estimates sent", d.sent);
}
