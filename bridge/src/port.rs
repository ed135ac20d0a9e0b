//! The device's end of the link on the computer: a serial port, or a TCP connection (an
//! emulator's UART, `cargo xtask robot --bridge-port`). A thread reads and decodes the frames
//! (`beamfield::link::Decoder`) as they come; the caller sends frames with `beamfield`'s
//! encoder. Between the reader and the caller is a bounded queue
//! ([`crate::queue::LINK_QUEUE_CAPACITY`] entries): when the caller falls
//! behind, the oldest entries are dropped and counted ([`Port::dropped`]).

use std::io::{Read, Write};
use std::net::TcpStream;
use std::sync::Arc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use beamfield::link::{Decoder, Encoder, LinkError, LinkStats, Message, MAX_WIRE_LEN};

use crate::queue::{Bounded, LINK_QUEUE_CAPACITY};

/// Where the device is.
#[derive(Clone, Debug, PartialEq)]
pub enum Endpoint {
    /// `host:port` of a TCP server carrying the UART's bytes.
    Tcp(String),
    /// A serial port's path and its baud rate.
    Serial { path: String, baud: u32 },
}

impl std::fmt::Display for Endpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Tcp(a) => write!(f, "tcp:{a}"),
            Self::Serial { path, baud } => write!(f, "{path} at {baud} Bd"),
        }
    }
}

/// What the reader thread hands over.
#[derive(Debug)]
pub enum Incoming {
    /// A frame that passed every check, and when it was complete (ns since the Unix epoch).
    Frame { message: Message, arrival_ns: u64 },
    /// A frame refused by the decoder (counted; the stream goes on at the next delimiter).
    Refused(LinkError),
    /// The link ended (end of stream, or an error); the decoder's counters at the end.
    Closed {
        error: Option<std::io::Error>,
        stats: LinkStats,
    },
}

/// Nanoseconds since the Unix epoch now.
pub fn now_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64)
}

/// An open link.
pub struct Port {
    incoming: Arc<Bounded<Incoming>>,
    writer: Box<dyn Write + Send>,
    encoder: Encoder,
    /// Frames sent.
    pub sent: u64,
}

/// A link that could not be opened or written.
#[derive(Debug)]
pub enum PortError {
    Open(Endpoint, String),
    Write(std::io::Error),
    /// A message the encoder refused (a value out of the link's range).
    Encode(LinkError),
}

impl std::fmt::Display for PortError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Open(e, why) => write!(f, "cannot open the device link {e}: {why}"),
            Self::Write(e) => write!(f, "writing to the device failed: {e}"),
            Self::Encode(e) => write!(f, "the link cannot carry this message: {e}"),
        }
    }
}

impl std::error::Error for PortError {}

fn reader_thread(mut r: Box<dyn Read + Send>, tx: Arc<Bounded<Incoming>>) {
    let mut decoder = Decoder::new();
    let mut buf = [0u8; 512];
    loop {
        let n = match r.read(&mut buf) {
            Ok(0) => {
                tx.push(Incoming::Closed {
                    error: None,
                    stats: decoder.stats(),
                });
                return;
            }
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::TimedOut
                        | std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::Interrupted
                ) =>
            {
                continue
            }
            Err(e) => {
                tx.push(Incoming::Closed {
                    error: Some(e),
                    stats: decoder.stats(),
                });
                return;
            }
        };
        let mut out = Vec::new();
        decoder.feed(&buf[..n], |f| out.push(f));
        let arrival_ns = now_ns();
        for f in out {
            let item = match f {
                Ok(frame) => Incoming::Frame {
                    message: frame.message,
                    arrival_ns,
                },
                Err(e) => Incoming::Refused(e),
            };
            if !tx.push(item) {
                return;
            }
        }
    }
}

impl Drop for Port {
    fn drop(&mut self) {
        // The reader stops at its next read.
        self.incoming.abandon();
    }
}

impl Port {
    /// Opens the link and starts its reader.
    pub fn open(endpoint: &Endpoint) -> Result<Self, PortError> {
        let fail = |why: String| PortError::Open(endpoint.clone(), why);
        let (reader, writer): (Box<dyn Read + Send>, Box<dyn Write + Send>) = match endpoint {
            Endpoint::Tcp(addr) => {
                let s = TcpStream::connect(addr).map_err(|e| fail(e.to_string()))?;
                s.set_nodelay(true).map_err(|e| fail(e.to_string()))?;
                let r = s.try_clone().map_err(|e| fail(e.to_string()))?;
                (Box::new(r), Box::new(s))
            }
            Endpoint::Serial { path, baud } => {
                let p = serialport::new(path, *baud)
                    .timeout(Duration::from_millis(100))
                    .open()
                    .map_err(|e| fail(e.to_string()))?;
                let r = p.try_clone().map_err(|e| fail(e.to_string()))?;
                (Box::new(r), Box::new(p))
            }
        };
        let incoming = Arc::new(Bounded::new(LINK_QUEUE_CAPACITY));
        let tx = Arc::clone(&incoming);
        std::thread::Builder::new()
            .name("device link".into())
            .spawn(move || reader_thread(reader, tx))
            .map_err(|e| fail(e.to_string()))?;
        Ok(Self {
            incoming,
            writer,
            encoder: Encoder::new(),
            sent: 0,
        })
    }

    /// What has arrived, waiting at most `timeout` for the first item.
    /// At most [`LINK_QUEUE_CAPACITY`] items.
    pub fn receive(&self, timeout: Duration) -> Vec<Incoming> {
        self.incoming.take_all(timeout)
    }

    /// Items the reader dropped because the caller was [`LINK_QUEUE_CAPACITY`] items behind
    /// (the oldest go first).
    pub fn dropped(&self) -> u64 {
        self.incoming.dropped()
    }

    /// Encodes and sends one message (a whole frame in one write).
    pub fn send(&mut self, message: &Message) -> Result<(), PortError> {
        let mut wire = [0u8; MAX_WIRE_LEN];
        let n = self
            .encoder
            .encode(message, &mut wire)
            .map_err(PortError::Encode)?;
        self.writer
            .write_all(&wire[..n])
            .and_then(|()| self.writer.flush())
            .map_err(PortError::Write)?;
        self.sent += 1;
        Ok(())
    }
}
