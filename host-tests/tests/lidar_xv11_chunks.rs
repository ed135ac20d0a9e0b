//! An XV-11 stream (the Intel lab log's 910 scans encoded as the sensor sends them at 300 rpm,
//! 115,200 baud, behind 29 bytes of start-up garbage) received in chunks and stamped with the
//! receiver's clock per chunk, as `docs/lidar.md` describes for a protocol without timestamps
//! (`Xv11Decoder::feed_received`, `AssemblerConfig::sensor_timestamps` false): the revolutions
//! must be those of the whole stream decoded without stamps, whatever the chunk size, each
//! stamped with the time of the chunk in which its first packet started.

use beamfield::lidar::xv11::Xv11Decoder;
use beamfield::lidar::{AssemblerConfig, ScanAssembler};
use beamfield::BeamLayout;
use beamfield_tools::input::carmen::{CarmenLog, ReadOptions};
use beamfield_tools::lidar_stream::{
    encode_scans, layout, Format, LayoutChoice, StreamOptions, MAX_BEAMS,
};

/// Start-up garbage before the first packet, bytes.
const GARBAGE: usize = 29;
/// Bytes of one turn: 90 packets of 22 bytes.
const TURN_LEN: usize = 90 * 22;

/// Bytes per millisecond on a 115,200-baud 8N1 line.
const BYTES_PER_MS: f64 = 11.52;

fn xv11_layout() -> BeamLayout<MAX_BEAMS> {
    layout(LayoutChoice::Carmen, Format::Xv11.field_max_m() + 1.0).unwrap()
}

fn xv11_stream() -> Vec<u8> {
    let path = host_tests::data_dir().join("laser_intel_lab/intel-corrected.log");
    let log = CarmenLog::read_path(&path, ReadOptions::default()).unwrap();
    let scans: Vec<Vec<f32>> = log.scans.iter().map(|s| s.ranges_m.clone()).collect();
    let o = StreamOptions {
        format: Format::Xv11,
        rpm: 300.0,
        noise_m: 0.0,
        garbage: GARBAGE,
        corrupt_rate: 0.0,
        seed: 7,
    };
    encode_scans(&xv11_layout(), &scans, &o, |_| {}).unwrap().0
}

/// A revolution: its ranges as bit patterns, and its first and last stamps.
type Rev = (Vec<u32>, Option<u16>, Option<u16>);

/// Decodes `bytes` handed over `chunk` bytes at a time (0: all at once, no stamps); each chunk
/// is stamped with the receiver's millisecond clock when its last byte has arrived.
fn revolutions(bytes: &[u8], chunk: usize) -> Vec<Rev> {
    let l = xv11_layout();
    let mut config = AssemblerConfig::for_layout(&l);
    config.timestamp_wrap_ms = 0;
    config.sensor_timestamps = chunk == 0;
    let mut asm = ScanAssembler::<MAX_BEAMS>::new(&l, config).unwrap();
    let mut dec = Xv11Decoder::new();
    let mut out = Vec::new();
    let mut push = |asm: &mut ScanAssembler<MAX_BEAMS>, p| {
        if asm.push(p).is_some() {
            let r = asm.revolution();
            out.push((
                asm.scan().ranges_m().iter().map(|v| v.to_bits()).collect(),
                r.start_timestamp_ms,
                r.end_timestamp_ms,
            ));
        }
    };
    if chunk == 0 {
        dec.feed(bytes, |p| push(&mut asm, p));
        return out;
    }
    let mut received = 0usize;
    for c in bytes.chunks(chunk) {
        received += c.len();
        dec.feed_received(c, receiver_ms(received), |p| push(&mut asm, p));
    }
    out
}

/// The receiver's `u16` millisecond clock when byte `received` − 1 has arrived.
fn receiver_ms(received: usize) -> u16 {
    ((received as f64 / BYTES_PER_MS) as u64 % 65_536) as u16
}

#[test]
fn chunk_stamped_revolutions_are_those_of_the_whole_stream() {
    let bytes = xv11_stream();
    let whole = revolutions(&bytes, 0);
    assert_eq!(whole.len(), 909);
    assert_eq!(bytes.len(), GARBAGE + 910 * TURN_LEN);
    for chunk in [1, 64, 1024, 4096] {
        let got = revolutions(&bytes, chunk);
        assert_eq!(got.len(), whole.len(), "chunks of {chunk} bytes");
        for (k, (g, w)) in got.iter().zip(&whole).enumerate() {
            assert!(
                g.0 == w.0,
                "chunks of {chunk} bytes: revolution {k} differs"
            );
            // Revolution k opens with turn k's first packet: the chunk it started in.
            let first = GARBAGE + k * TURN_LEN;
            let chunk_end = ((first / chunk + 1) * chunk).min(bytes.len());
            assert_eq!(
                g.1,
                Some(receiver_ms(chunk_end)),
                "chunks of {chunk} bytes: revolution {k}"
            );
        }
    }
}
