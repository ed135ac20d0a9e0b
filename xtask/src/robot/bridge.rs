//! `cargo xtask robot --bridge-port P`: the emulated device's link offered to a computer-side
//! program (`beamfield bridge --connect 127.0.0.1:P`) over TCP on 127.0.0.1.
//!
//! The device's USART3 output is forwarded to the connection as it is written. Frames the
//! connection sends are put into USART2 between the replay's own frames, whole; everything
//! written into USART2 is recorded, so that the host can replay exactly the stream the device
//! received. The replay's frames are paced by the device's progress: a frame is written once the
//! device's latest estimate or heartbeat is within [`LEAD_US`] of its timestamp, so a command
//! from the bridge reaches the device near the time it was sent instead of after the whole
//! replay, which a socket's buffer would otherwise take in at once.

use std::collections::VecDeque;
use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use beamfield::link::{self, Decoder, Message, DELIMITER};

use crate::error::{Error, Result};

/// How far the replay's odometry may run ahead of the device's last estimate, µs.
pub const LEAD_US: u64 = 200_000;
/// How long to wait for the device's progress before writing on anyway.
const STALL: Duration = Duration::from_secs(3);
/// How long to wait for the bridge to connect.
const ACCEPT_TIMEOUT: Duration = Duration::from_secs(120);

/// What the device and the bridge share while the run lasts.
pub struct Shared {
    /// The device's latest estimate or heartbeat time, µs (0: none yet).
    pub device_us: AtomicU64,
    /// Set when QEMU has ended.
    pub done: AtomicBool,
    /// Frames from the bridge, each with its delimiter, not yet written.
    pub from_bridge: Mutex<VecDeque<Vec<u8>>>,
}

/// Listens on 127.0.0.1:`port` (0: a free port).
pub fn listen(port: u16) -> Result<TcpListener> {
    TcpListener::bind(("127.0.0.1", port))
        .map_err(|e| Error::Host(format!("listening on 127.0.0.1:{port}: {e}")))
}

/// Waits for the bridge to connect to `listener`.
pub fn accept(listener: &TcpListener) -> Result<TcpStream> {
    let port = listener.local_addr().map(|a| a.port()).unwrap_or(0);
    listener
        .set_nonblocking(true)
        .map_err(|e| Error::Host(e.to_string()))?;
    println!("robot: waiting for the bridge on 127.0.0.1:{port} (beamfield bridge --connect 127.0.0.1:{port})");
    let started = Instant::now();
    loop {
        match listener.accept() {
            Ok((s, peer)) => {
                println!("robot: the bridge connected from {peer}");
                s.set_nonblocking(false)
                    .and_then(|()| s.set_nodelay(true))
                    .map_err(|e| Error::Host(e.to_string()))?;
                return Ok(s);
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                if started.elapsed() > ACCEPT_TIMEOUT {
                    return Err(Error::Host(format!(
                        "no bridge connected to 127.0.0.1:{port} within {} s",
                        ACCEPT_TIMEOUT.as_secs()
                    )));
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            Err(e) => return Err(Error::Host(format!("accepting the bridge: {e}"))),
        }
    }
}

/// Reads the bridge's bytes into whole frames until it closes the connection.
pub fn read_bridge(mut conn: TcpStream, shared: Arc<Shared>) {
    let mut partial = Vec::new();
    let mut buf = [0u8; 512];
    while let Ok(n) = conn.read(&mut buf) {
        if n == 0 {
            return;
        }
        for &b in &buf[..n] {
            partial.push(b);
            if b == DELIMITER {
                if let Ok(mut q) = shared.from_bridge.lock() {
                    q.push_back(std::mem::take(&mut partial));
                }
            }
        }
    }
}

/// Forwards what the device writes into `usart3` (a file QEMU appends to) to the bridge, and
/// keeps `shared.device_us` at the device's latest time, until QEMU has ended and the file is
/// read to its end.
pub fn forward_output(usart3: &Path, mut conn: TcpStream, shared: Arc<Shared>) {
    let mut file = None;
    let mut decoder = Decoder::new();
    let mut buf = [0u8; 4096];
    let mut connected = true;
    loop {
        let finished = shared.done.load(Ordering::Acquire);
        if file.is_none() {
            file = std::fs::File::open(usart3).ok();
        }
        let n = file
            .as_mut()
            .and_then(|f| f.read(&mut buf).ok())
            .unwrap_or(0);
        if n == 0 {
            if finished {
                // The reader's clone holds the connection open otherwise: the bridge sees the
                // end of the link only when both directions are shut.
                let _ = conn.shutdown(std::net::Shutdown::Both);
                return;
            }
            std::thread::sleep(Duration::from_millis(5));
            continue;
        }
        let bytes = &buf[..n];
        decoder.feed(bytes, |f| {
            let t = match f.map(|f| f.message) {
                Ok(Message::Estimate(e)) => e.timestamp_us,
                Ok(Message::Heartbeat(h)) => h.timestamp_us,
                _ => return,
            };
            shared.device_us.fetch_max(t, Ordering::AcqRel);
        });
        if connected && conn.write_all(bytes).is_err() {
            eprintln!("xtask: the bridge closed its connection; the device's output is no longer forwarded");
            connected = false;
        }
    }
}

/// The timestamp a frame of the replay carries, if any.
fn timestamp(frame: &[u8]) -> Option<u64> {
    let body = frame.strip_suffix(&[DELIMITER]).unwrap_or(frame);
    match link::decode(body).ok()?.message {
        Message::WheelTicks(m) => Some(m.timestamp_us),
        Message::WheelOdometry(m) => Some(m.timestamp_us),
        Message::SetInitialPose(m) if m.timestamp_us != 0 => Some(m.timestamp_us),
        _ => None,
    }
}

/// What went into USART2.
pub struct Written {
    /// Every byte, in order.
    pub bytes: Vec<u8>,
    /// Frames from the bridge.
    pub bridge_frames: usize,
    /// The replay's latest timestamp when the first bridge frame went in, µs.
    pub first_bridge_at_us: Option<u64>,
}

/// Writes the replay's `link` into `out` paced by the device, with the bridge's frames between.
pub fn write_paced(out: &mut impl Write, link: &[u8], shared: &Shared) -> std::io::Result<Written> {
    let mut w = Written {
        bytes: Vec::with_capacity(link.len() + 4096),
        bridge_frames: 0,
        first_bridge_at_us: None,
    };
    let mut last_ts = 0u64;
    let mut base = None;
    let drain = |out: &mut dyn Write, w: &mut Written, last_ts: u64| -> std::io::Result<()> {
        let frames: Vec<Vec<u8>> = shared
            .from_bridge
            .lock()
            .map(|mut q| q.drain(..).collect())
            .unwrap_or_default();
        for f in frames {
            out.write_all(&f)?;
            w.bytes.extend_from_slice(&f);
            w.bridge_frames += 1;
            w.first_bridge_at_us.get_or_insert(last_ts);
        }
        out.flush()
    };
    for frame in link.split_inclusive(|&b| b == DELIMITER) {
        if let Some(ts) = timestamp(frame) {
            let base = *base.get_or_insert(ts);
            let waited = Instant::now();
            loop {
                let device = shared.device_us.load(Ordering::Acquire).max(base);
                if ts <= device + LEAD_US || waited.elapsed() > STALL {
                    break;
                }
                drain(out, &mut w, last_ts)?;
                std::thread::sleep(Duration::from_millis(2));
            }
            last_ts = last_ts.max(ts);
        }
        drain(out, &mut w, last_ts)?;
        out.write_all(frame)?;
        w.bytes.extend_from_slice(frame);
    }
    out.flush()?;
    Ok(w)
}
