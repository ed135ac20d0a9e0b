//! YDLIDAR packets cut short and with single bits flipped, on real data.
//!
//! The first scans of the Intel lab log go through the CLI's stream builder
//! (`beamfield_tools::lidar_stream`, format `ydlidar`: a zero packet and nine packets of up to 40
//! samples per revolution). Then, for every packet of the second revolution, every truncation
//! (the packet cut after 1 … len − 1 bytes) and every single-bit flip of every byte is put in the
//! stream between intact packets. What must hold, case by case: exactly the points of the intact
//! packets come out (a damaged header also costs the packet before it, which the decoder only
//! takes when the next packet's header follows it) (in order, bit for bit as from the clean stream), the damage is seen in the
//! counters (a failed check code, or skipped bytes when the header itself was hit), and every
//! byte is accounted for (`bytes == frame_bytes + skipped_bytes + buffered`).
//!
//! The check code alone does not get there: a 16-bit XOR lets a cut packet through whenever the
//! bytes of the next packet that fill it XOR to the missing ones, and in the rear half of these
//! revolutions (no measurement, all samples 0) that is most cuts (179 of these 810). The decoder
//! also asks for the next packet's header right after a packet; this test is what shows it.
//!
//! A flipped LSN changes the packet's length, so the decoder reads into the next packets before
//! the check code fails; it then finds them again inside the rejected bytes. The intact packets
//! that follow the damage (two revolutions, 1,640 bytes) outnumber the longest packet (520 bytes),
//! so every such case is resolved before the stream ends.

use beamfield::lidar::ydlidar::{self, YdlidarDecoder};
use beamfield::lidar::LidarPoint;
use beamfield_tools::input::carmen::{CarmenLog, ReadOptions};
use beamfield_tools::lidar_stream::{encode_scans, layout, Format, LayoutChoice, StreamOptions};

fn intel_stream(scans: usize) -> Vec<u8> {
    let path = host_tests::data_dir().join("laser_intel_lab/intel-corrected.log");
    let log = CarmenLog::read_path(&path, ReadOptions::default()).unwrap();
    let ranges: Vec<Vec<f32>> = log
        .scans
        .iter()
        .skip(400)
        .take(scans)
        .map(|s| s.ranges_m.clone())
        .collect();
    let l = layout(LayoutChoice::Carmen, Format::Ydlidar.field_max_m() + 1.0).unwrap();
    let options = StreamOptions {
        format: Format::Ydlidar,
        rpm: 420.0,
        noise_m: 0.0,
        garbage: 0,
        corrupt_rate: 0.0,
        seed: 1,
    };
    encode_scans(&l, &ranges, &options, |_| {}).unwrap().0
}

/// The packets of a clean stream, as byte ranges (read from the LSN bytes, the layout of the
/// protocol document, independent of the decoder).
fn packets(stream: &[u8]) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    let mut at = 0;
    while at < stream.len() {
        assert_eq!(&stream[at..at + 2], &[0xAA, 0x55]);
        let len = 10 + 2 * usize::from(stream[at + 3]);
        out.push(at..at + len);
        at += len;
    }
    out
}

fn decode(bytes: &[u8]) -> (Vec<LidarPoint>, YdlidarDecoder) {
    let mut d = YdlidarDecoder::new();
    let mut v = Vec::new();
    d.feed(bytes, |p| v.push(p));
    d.flush(|p| v.push(p));
    (v, d)
}

/// Feeds `damaged` (the clean stream with the packets `lost` damaged) and checks the rules above.
fn check(clean_points: &[Vec<LidarPoint>], lost: &[usize], damaged: &[u8], what: &str) {
    let (got, d) = decode(damaged);
    let want: Vec<LidarPoint> = clean_points
        .iter()
        .enumerate()
        .filter(|(j, _)| !lost.contains(j))
        .flat_map(|(_, p)| p.iter().copied())
        .collect();
    assert_eq!(got, want, "{what}");
    let s = d.stats();
    assert!(s.bad_checksum + s.skipped_bytes > 0, "{what}: unseen");
    assert_eq!(s.bytes as usize, damaged.len(), "{what}");
    assert_eq!(
        s.bytes as usize,
        d.frame_bytes() as usize + s.skipped_bytes as usize + d.buffered(),
        "{what}"
    );
    assert_eq!(d.buffered(), 0, "{what}");
}

#[test]
fn every_truncation_and_every_bit_flip_of_a_real_revolution_costs_only_its_packet() {
    let stream = intel_stream(4);
    let ranges = packets(&stream);
    assert_eq!(ranges.len(), 40);
    let clean_points: Vec<Vec<LidarPoint>> = ranges
        .iter()
        .map(|r| decode(&stream[r.clone()]).0)
        .collect();
    // The clean stream decodes to the packets' points, all of them.
    let (all, _) = decode(&stream);
    assert_eq!(all, clean_points.concat());
    let (mut truncations, mut flips) = (0usize, 0usize);
    for (k, r) in ranges.iter().enumerate().take(20).skip(10) {
        let r = r.clone();
        for cut in 1..r.len() {
            let mut s = stream[..r.start + cut].to_vec();
            s.extend_from_slice(&stream[r.end..]);
            // Cut after its first byte, the packet's header is gone too.
            let lost: &[usize] = if cut < 2 { &[k - 1, k] } else { &[k] };
            check(&clean_points, lost, &s, &format!("packet {k} cut at {cut}"));
            truncations += 1;
        }
        for at in r.clone() {
            for bit in 0..8 {
                let mut s = stream.clone();
                s[at] ^= 1 << bit;
                let what = format!("packet {k} byte {} bit {bit}", at - r.start);
                let lost: &[usize] = if at - r.start < 2 { &[k - 1, k] } else { &[k] };
                check(&clean_points, lost, &s, &what);
                flips += 1;
            }
        }
    }
    println!(
        "{truncations} truncations and {flips} single-bit flips: each cost only its packet (and \
         the one before it when the header was hit)"
    );
}

#[test]
fn a_stream_with_the_scan_answer_in_front_decodes_the_same() {
    let stream = intel_stream(2);
    let mut with = ydlidar::SCAN_ANSWER.to_vec();
    with.extend_from_slice(&stream);
    let (a, _) = decode(&stream);
    let (b, d) = decode(&with);
    assert_eq!(a, b);
    assert_eq!(d.stats().skipped_bytes, 7);
    assert_eq!(d.start_packets(), 2);
    // 420 rpm is 7 Hz: the zero packets carry 70 in CT bits 7..1.
    assert_eq!(d.scan_freq_decihz(), Some(70));
}
