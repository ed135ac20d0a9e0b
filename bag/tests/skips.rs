//! What a bag reader must not trust: stamps that go backwards, scans with no ranges, a message
//! cut short, a pose that is not finite. Each is skipped and counted by cause; the rest is read.
//! The bag is written here with the `mcap` crate's writer and CDR laid out by hand from the
//! message definitions.

mod common;

use beamfield_bag::{Bag, Topics};
use common::Out;
use std::collections::BTreeMap;
use std::io::Cursor;

fn scan(t_s: u32, beams: u32) -> Vec<u8> {
    let mut o = Out::new();
    o.header(t_s, "laser")
        .f32(-1.5707964)
        .f32(1.553_343)
        .f32(0.017453292)
        .f32(0.0)
        .f32(0.0)
        .f32(0.0)
        .f32(30.0)
        .u32(beams);
    for i in 0..beams {
        o.f32(1.0 + i as f32 * 0.01);
    }
    o.u32(0); // no intensities
    o.0
}

fn odometry(t_s: u32, x: f64) -> Vec<u8> {
    let mut o = Out::new();
    o.header(t_s, "odom").string("base_link");
    o.f64(x)
        .f64(0.0)
        .f64(0.0)
        .f64(0.0)
        .f64(0.0)
        .f64(0.0)
        .f64(1.0);
    for _ in 0..36 {
        o.f64(0.0);
    }
    for _ in 0..42 {
        o.f64(0.0); // the twist and its covariance
    }
    o.0
}

fn write_bag(messages: &[(&str, &str, Vec<u8>)]) -> Vec<u8> {
    let mut w = mcap::Writer::new(Cursor::new(Vec::new())).unwrap();
    let mut channels = BTreeMap::new();
    for (i, (topic, schema, data)) in messages.iter().enumerate() {
        let id = *channels.entry(*topic).or_insert_with(|| {
            let s = w.add_schema(schema, "ros2msg", b"").unwrap();
            w.add_channel(s, topic, "cdr", &BTreeMap::new()).unwrap()
        });
        let header = mcap::records::MessageHeader {
            channel_id: id,
            sequence: i as u32,
            log_time: i as u64,
            publish_time: i as u64,
        };
        w.write_to_known_channel(&header, data).unwrap();
    }
    w.finish().unwrap();
    w.into_inner().into_inner()
}

#[test]
fn untrustworthy_messages_are_skipped_and_counted() {
    const SCAN: &str = "sensor_msgs/msg/LaserScan";
    const ODOM: &str = "nav_msgs/msg/Odometry";
    let mut cut = scan(9, 181);
    cut.truncate(cut.len() - 40);
    let bytes = write_bag(&[
        ("/scan", SCAN, scan(1, 181)),
        ("/odom", ODOM, odometry(1, 0.0)),
        ("/scan", SCAN, scan(2, 181)),
        ("/odom", ODOM, odometry(2, 0.1)),
        // Backwards in time on both topics.
        ("/scan", SCAN, scan(1, 181)),
        ("/odom", ODOM, odometry(1, 0.2)),
        // No ranges.
        ("/scan", SCAN, scan(3, 0)),
        // Cut short.
        ("/scan", SCAN, cut),
        // A NaN position.
        ("/odom", ODOM, odometry(4, f64::NAN)),
        ("/scan", SCAN, scan(5, 181)),
        ("/odom", ODOM, odometry(5, 0.3)),
    ]);
    let dir = std::env::temp_dir().join(format!("bf-bag-skips-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("run.mcap");
    std::fs::write(&path, bytes).unwrap();
    let bag = Bag::read(&path, &Topics::default()).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let stamps: Vec<u64> = bag
        .scans
        .iter()
        .map(|s| s.stamp_ns / 1_000_000_000)
        .collect();
    assert_eq!(stamps, [1, 2, 5]);
    assert_eq!(bag.scans[0].value.ranges.len(), 181);
    let odom: Vec<f64> = bag.odometry.iter().map(|o| o.value.x).collect();
    assert_eq!(odom, [0.0, 0.1, 0.3]);
    let count = |prefix: &str| -> u64 {
        bag.skipped
            .iter()
            .filter(|(k, _)| k.starts_with(prefix))
            .map(|(_, n)| n)
            .sum()
    };
    assert_eq!(count("/scan: stamped at or before"), 1, "{:?}", bag.skipped);
    assert_eq!(count("/odom: stamped at or before"), 1, "{:?}", bag.skipped);
    assert_eq!(count("/scan: no ranges"), 1, "{:?}", bag.skipped);
    assert_eq!(count("/scan: malformed"), 1, "{:?}", bag.skipped);
    assert_eq!(
        count("/odom: a pose that is not finite"),
        1,
        "{:?}",
        bag.skipped
    );
    assert_eq!(bag.topics["/scan"], (SCAN.to_string(), 6));
}
