//! ROS 2 bags (`beamfield-bag`): the CDR decoders of each message type on arbitrary bytes, and
//! the same bytes as a whole MCAP file. Neither may panic, hang or allocate without bound.
#![no_main]

use beamfield_bag::{decode_odometry, decode_scan, decode_stamped_pose, decode_tf, Bag, Topics};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = decode_scan(data);
    let _ = decode_odometry(data);
    let _ = decode_stamped_pose(data);
    let _ = decode_tf(data);
    let topics = Topics {
        reference: Some("/ground_truth".into()),
        ..Topics::default()
    };
    let _ = Bag::from_mcap(std::path::Path::new("fuzz.mcap"), data, &topics);
});
