//! ROS 2 sqlite3 bags (`beamfield-bag`): the fuzz bytes as a `.db3` file read by `Bag::read`
//! (SQLite opened read-only and immutable, the rosbag2 schema, every message's CDR). It may
//! refuse, never panic, hang or allocate without bound.
#![no_main]

use beamfield_bag::{Bag, OdomFromTf, Topics};
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;

/// One file per fuzzing process, written for every input and removed after it (SQLite reads a
/// file, not bytes).
fn path() -> PathBuf {
    std::env::temp_dir().join(format!("beamfield-fuzz-{}.db3", std::process::id()))
}

fuzz_target!(|data: &[u8]| {
    let file = path();
    if std::fs::write(&file, data).is_err() {
        return;
    }
    let topics = Topics {
        reference: Some("/ground_truth".into()),
        odom_from_tf: Some(OdomFromTf {
            topic: "/tf".into(),
            odom_frame: "odom".into(),
            base_frame: "base_link".into(),
        }),
        ..Topics::default()
    };
    let _ = Bag::read(&file, &topics);
    let _ = std::fs::remove_file(&file);
});
