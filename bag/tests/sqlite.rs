//! sqlite3 (`.db3`) bags: the Intel bag converted from MCAP by PyPI rosbags
//! (`tools/tests/data/make_db3.py`) reads as the MCAP bag reads, message for message; damaged
//! and foreign files are refused with their typed error, never a panic.

use beamfield_bag::{Bag, BagError, OdomFromTf, Topics};
use std::path::{Path, PathBuf};

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tools/tests/data")
}

fn topics() -> Topics {
    Topics {
        reference: Some("/ground_truth".into()),
        ..Topics::default()
    }
}

fn db3_bytes() -> Vec<u8> {
    std::fs::read(data().join("intel-bag-db3/intel-bag-db3.db3")).unwrap()
}

/// A scratch directory of this test binary.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bf-bag-sqlite-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn assert_same(a: &Bag, b: &Bag) {
    assert_eq!(a.scans, b.scans);
    assert_eq!(a.odometry, b.odometry);
    assert_eq!(a.reference, b.reference);
    assert_eq!(a.mounts, b.mounts);
    assert_eq!(a.skipped, b.skipped);
    assert_eq!(a.topics, b.topics);
}

#[test]
fn a_db3_bag_reads_as_the_mcap_bag_it_was_converted_from() {
    let mcap = Bag::read(&data().join("intel-bag"), &topics()).unwrap();
    assert_eq!(mcap.scans.len(), 120);
    // The directory, and the .db3 file by itself.
    let dir = Bag::read(&data().join("intel-bag-db3"), &topics()).unwrap();
    assert_same(&dir, &mcap);
    let file = Bag::read(&data().join("intel-bag-db3/intel-bag-db3.db3"), &topics()).unwrap();
    assert_same(&file, &mcap);
    // An SQLite file is known by its header, whatever its name.
    let renamed = scratch("renamed.bag");
    std::fs::write(&renamed, db3_bytes()).unwrap();
    assert_same(&Bag::read(&renamed, &topics()).unwrap(), &mcap);
}

#[test]
fn odometry_comes_from_tf_only_when_the_topic_is_missing() {
    let chain = data().join("intel-bag-chain");
    let tf = OdomFromTf {
        topic: "/tf".into(),
        odom_frame: "odom".into(),
        base_frame: "base_footprint".into(),
    };
    let with = |odom: &str, tf: Option<OdomFromTf>| Topics {
        odom: odom.into(),
        odom_from_tf: tf,
        ..topics()
    };
    let from_topic = Bag::read(&chain, &with("/odom", Some(tf.clone()))).unwrap();
    assert!(!from_topic.odometry_from_tf);
    let from_tf = Bag::read(&chain, &with("/wheel_odom", Some(tf.clone()))).unwrap();
    assert!(from_tf.odometry_from_tf);
    // make_db3.py wrote /tf from /odom's poses and stamps.
    assert_eq!(from_tf.odometry, from_topic.odometry);
    assert_eq!(from_tf.odometry.len(), 120);
    // Without the fallback, or with frames /tf does not have: typed errors naming what is
    // there.
    let e = Bag::read(&chain, &with("/wheel_odom", None)).unwrap_err();
    assert!(matches!(e, BagError::MissingTopic { .. }), "{e}");
    let other = OdomFromTf {
        base_frame: "base_link".into(),
        ..tf
    };
    let e = Bag::read(&chain, &with("/wheel_odom", Some(other))).unwrap_err();
    assert!(matches!(e, BagError::NoOdometry { .. }), "{e}");
    let line = e.to_string();
    assert!(
        line.contains("no transform odom → base_link on /tf (there: odom → base_footprint)"),
        "{line}"
    );
}

/// `bytes` with every `from` replaced by `to` (of the same length).
fn replaced(bytes: &[u8], from: &[u8], to: &[u8]) -> Vec<u8> {
    assert_eq!(from.len(), to.len());
    let mut out = bytes.to_vec();
    let mut hits = 0;
    for i in 0..out.len().saturating_sub(from.len()) {
        if &out[i..i + from.len()] == from {
            out[i..i + from.len()].copy_from_slice(to);
            hits += 1;
        }
    }
    assert!(hits > 0, "{:?} not found", String::from_utf8_lossy(from));
    out
}

fn read_bytes(name: &str, bytes: &[u8]) -> Result<Bag, BagError> {
    let path = scratch(name);
    std::fs::write(&path, bytes).unwrap();
    Bag::read(&path, &topics())
}

#[test]
fn damaged_and_foreign_db3_files_are_refused_with_their_error() {
    let good = db3_bytes();
    // Not SQLite.
    let e = read_bytes("junk.db3", b"not a database, only text").unwrap_err();
    assert!(matches!(e, BagError::NotSqlite(_)), "{e:?}");
    assert!(e.to_string().contains("is not an SQLite database"), "{e}");
    let e = read_bytes("empty.db3", b"").unwrap_err();
    assert!(matches!(e, BagError::NotSqlite(_)), "{e:?}");
    // SQLite, but no messages table (renamed in the schema and its SQL alike: a valid
    // database), or no column the reader needs.
    let e = read_bytes(
        "no-messages.db3",
        &replaced(&good, b"messages", b"messagez"),
    )
    .unwrap_err();
    assert!(
        matches!(&e, BagError::Db3Schema { what, .. } if what == "no table messages"),
        "{e:?}"
    );
    let e = read_bytes(
        "no-format.db3",
        &replaced(&good, b"serialization_format", b"serialization_formaX"),
    )
    .unwrap_err();
    assert!(
        matches!(&e, BagError::Db3Schema { what, .. } if what.contains("serialization_format")),
        "{e:?}"
    );
    // Cut in half; a page's type byte overwritten; a page's cells overwritten: SQLite finds
    // the file damaged.
    let e = read_bytes("half.db3", &good[..good.len() / 2]).unwrap_err();
    assert!(matches!(e, BagError::Db3Damaged(..)), "{e:?}");
    assert!(e.to_string().contains("is damaged"), "{e}");
    for page in [20usize, 40, 60] {
        let mut bad = good.clone();
        bad[(page - 1) * 4096] = 0xff;
        let e = read_bytes("page-type.db3", &bad).unwrap_err();
        assert!(matches!(e, BagError::Db3Damaged(..)), "page {page}: {e:?}");
        let mut bad = good.clone();
        bad[(page - 1) * 4096 + 8..(page - 1) * 4096 + 200].fill(0xab);
        let e = read_bytes("page-cells.db3", &bad).unwrap_err();
        assert!(matches!(e, BagError::Db3Damaged(..)), "page {page}: {e:?}");
    }
}

#[test]
fn a_message_whose_cdr_does_not_decode_is_skipped_and_counted() {
    // Every scan's frame id "laser" (CDR: length 6, then the bytes and a NUL) given a length
    // past the message's end: those scans are malformed; /tf_static's "laser" too.
    let bad = replaced(
        &db3_bytes(),
        b"\x06\x00\x00\x00laser\x00",
        b"\xf0\xff\xff\x7flaser\x00",
    );
    let bag = read_bytes("bad-cdr.db3", &bad).unwrap();
    assert!(bag.scans.is_empty());
    assert_eq!(bag.odometry.len(), 120);
    let malformed: u64 = bag
        .skipped
        .iter()
        .filter(|(why, _)| why.starts_with("/scan: malformed"))
        .map(|(_, n)| n)
        .sum();
    assert_eq!(malformed, 120, "{:?}", bag.skipped);
}

#[test]
fn directories_hold_one_storage() {
    let dir = scratch("mixed");
    std::fs::create_dir_all(&dir).unwrap();
    let e = Bag::read(&dir, &topics()).unwrap_err();
    assert!(matches!(e, BagError::NoBagFile(_)), "{e:?}");
    std::fs::write(dir.join("a.db3"), db3_bytes()).unwrap();
    std::fs::copy(data().join("intel-bag/intel-bag.mcap"), dir.join("a.mcap")).unwrap();
    let e = Bag::read(&dir, &topics()).unwrap_err();
    assert!(matches!(e, BagError::MixedStorage(_)), "{e:?}");
}
