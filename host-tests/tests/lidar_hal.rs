//! The `hal` readers: a real LD06 stream (Intel log scans) read through an `embedded-io` reader in
//! uneven pieces and through a non-blocking `embedded-hal-nb` port that sometimes has nothing
//! ready, must give the same points as feeding the decoder directly.

use beamfield::lidar::io::{Error, LidarReader};
use beamfield::lidar::ld06::Ld06Decoder;
use beamfield::lidar::xv11::Xv11Decoder;
use beamfield::lidar::LidarPoint;
use beamfield_tools::input::carmen::{CarmenLog, ReadOptions};
use beamfield_tools::lidar_stream::{encode_scans, layout, Format, LayoutChoice, StreamOptions};
use embedded_hal_nb::nb;
use embedded_hal_nb::serial::{ErrorKind, ErrorType, Read};

fn real_stream(format: Format) -> Vec<u8> {
    let path = host_tests::data_dir().join("laser_intel_lab/intel-corrected.log");
    let log = CarmenLog::read_path(&path, ReadOptions::default()).unwrap();
    let scans: Vec<Vec<f32>> = log.scans[100..110]
        .iter()
        .map(|s| s.ranges_m.clone())
        .collect();
    let l = layout(LayoutChoice::Carmen, 70.0).unwrap();
    let o = StreamOptions {
        format,
        rpm: 600.0,
        noise_m: 0.0,
        garbage: 13,
        corrupt_rate: 0.0,
        seed: 3,
    };
    encode_scans(&l, &scans, &o, |_| {}).unwrap().0
}

fn direct(bytes: &[u8]) -> Vec<LidarPoint> {
    let mut v = Vec::new();
    Ld06Decoder::new().feed(bytes, |p| v.push(p));
    v
}

#[test]
fn embedded_io_reader_feeds_every_byte() {
    let bytes = real_stream(Format::Ld06);
    let want = direct(&bytes);
    assert_eq!(want.len(), 10 * 360);
    let mut r = LidarReader::new(&bytes[..], Ld06Decoder::new());
    let mut got = Vec::new();
    let mut buf = [0u8; 61];
    let mut size = 1;
    loop {
        // Uneven reads: 1, 2, …, 61 bytes, then again.
        let n = r.read_io(&mut buf[..size], |p| got.push(p)).unwrap();
        if n == 0 {
            break;
        }
        size = size % 61 + 1;
    }
    assert_eq!(got, want);
    assert_eq!(r.stats().bytes as usize, bytes.len());
    assert_eq!(r.read_io(&mut [], |_| {}), Ok(0));
    let (rest, dec) = r.release();
    assert!(rest.is_empty());
    assert_eq!(dec.stats().frames_ok, 300);
}

/// A port that has a byte ready only on some polls, and fails once at a chosen byte.
struct Port<'a> {
    bytes: &'a [u8],
    pos: usize,
    poll: u32,
    fail_at: Option<usize>,
}

impl ErrorType for Port<'_> {
    type Error = ErrorKind;
}

impl Read<u8> for Port<'_> {
    fn read(&mut self) -> nb::Result<u8, ErrorKind> {
        self.poll += 1;
        if self.poll % 7 == 0 {
            return Err(nb::Error::WouldBlock);
        }
        if self.fail_at == Some(self.pos) {
            self.fail_at = None;
            return Err(nb::Error::Other(ErrorKind::Overrun));
        }
        let b = *self.bytes.get(self.pos).ok_or(nb::Error::WouldBlock)?;
        self.pos += 1;
        Ok(b)
    }
}

#[test]
fn embedded_hal_nb_port_feeds_what_is_ready() {
    let bytes = real_stream(Format::Ld06);
    let want = direct(&bytes);
    let port = Port {
        bytes: &bytes,
        pos: 0,
        poll: 0,
        fail_at: Some(5000),
    };
    let mut r = LidarReader::new(port, Ld06Decoder::new());
    let mut got = Vec::new();
    let mut errors = 0;
    let mut idle = 0;
    while idle < 3 {
        match r.poll_nb(100, |p| got.push(p)) {
            Ok(0) => idle += 1,
            Ok(n) => {
                assert!(n <= 100);
                idle = 0;
            }
            Err(Error::Port(e)) => {
                assert_eq!(e, ErrorKind::Overrun);
                errors += 1;
            }
            Err(e) => panic!("{e}"),
        }
    }
    assert_eq!(errors, 1);
    assert_eq!(got, want);
    assert_eq!(r.stats().bytes as usize, bytes.len());
}

#[test]
fn any_decoder_works_behind_the_reader() {
    let bytes = real_stream(Format::Xv11);
    let mut want = Vec::new();
    Xv11Decoder::new().feed(&bytes, |p| want.push(p));
    let mut r = LidarReader::new(&bytes[..], Xv11Decoder::new());
    let mut got = Vec::new();
    let mut buf = [0u8; 256];
    while r.read_io(&mut buf, |p| got.push(p)).unwrap() > 0 {}
    assert_eq!(got, want);
    assert_eq!(got.len(), 3600);
}
