//! A bag file is outside bytes: the reader checks what the file says of itself before using it.
//! Each test builds a file with the `mcap` crate's writer, damages it the way a disk, a copy or
//! a crafted file would, and checks that the reader refuses it with the error that names the
//! damage (or, for a CRC of 0, "not written", that it reads it). `bag/tests/mcap_reference.py`
//! reads the same files with the reference MCAP library (PyPI `mcap`) to confirm it refuses and
//! accepts the same ones.
//!
//! The tests that could exhaust memory or block (a huge length in a compressed chunk,
//! `/dev/zero`, a FIFO, a file over the size limit) run the reader in a child process (this test
//! binary's `child` test) with 4 GB of address space (`ulimit -v 4000000`) and a time limit, so
//! a reader that allocates from an unchecked length or reads without bound fails them by
//! aborting or by being killed instead of taking the machine with it.

mod common;

use common::Out;
use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::process::Command;

use beamfield_bag::guard::{BadLength, Corrupt, CrcOf, MAX_CHUNK_BYTES};
use beamfield_bag::{read_bounded, Bag, BagError, Topics, MAX_BAG_FILE_BYTES};

const SCAN: &str = "sensor_msgs/msg/LaserScan";
const ODOM: &str = "nav_msgs/msg/Odometry";
const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

fn scan(t_s: u32) -> Vec<u8> {
    let mut o = Out::new();
    o.u32(t_s).u32(0).string("laser");
    for v in [-1.5707964, 1.553_343, 0.017453292, 0.0, 0.0, 0.1, 12.0] {
        o.f32(v);
    }
    o.u32(180);
    for i in 0..180 {
        o.f32(2.0 + i as f32 * 0.01);
    }
    o.u32(0);
    o.0
}

fn odometry(t_s: u32, x: f64) -> Vec<u8> {
    let mut o = Out::new();
    o.u32(t_s).u32(0).string("odom").string("base_link");
    for v in [x, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0] {
        o.f64(v);
    }
    for _ in 0..36 + 42 {
        o.f64(0.0);
    }
    o.0
}

/// The x of odometry message `i`: 0.25 m apart, so each is a distinct 8-byte pattern.
fn odom_x(i: u32) -> f64 {
    0.25 * f64::from(i)
}

/// Twenty scans and twenty odometry messages, one second apart, in chunks compressed as given.
fn write_bag(compression: Option<mcap::Compression>) -> Vec<u8> {
    let mut w = mcap::WriteOptions::new()
        .compression(compression)
        .create(Cursor::new(Vec::new()))
        .unwrap();
    let mut ids = BTreeMap::new();
    for (topic, schema) in [("/scan", SCAN), ("/odom", ODOM)] {
        let s = w.add_schema(schema, "ros2msg", b"").unwrap();
        ids.insert(
            topic,
            w.add_channel(s, topic, "cdr", &BTreeMap::new()).unwrap(),
        );
    }
    for i in 1..=20u32 {
        for (topic, data) in [("/scan", scan(i)), ("/odom", odometry(i, odom_x(i)))] {
            let header = mcap::records::MessageHeader {
                channel_id: ids[topic],
                sequence: i,
                log_time: u64::from(i) * 1_000_000_000,
                publish_time: u64::from(i) * 1_000_000_000,
            };
            w.write_to_known_channel(&header, &data).unwrap();
        }
    }
    w.finish().unwrap();
    w.into_inner().into_inner()
}

/// The file's top-level records: (opcode, byte offset, body length).
fn records(file: &[u8]) -> Vec<(u8, usize, usize)> {
    let mut out = Vec::new();
    let mut at = MAGIC.len();
    while at + 9 <= file.len() - MAGIC.len() {
        let op = file[at];
        let len = u64::from_le_bytes(file[at + 1..at + 9].try_into().unwrap()) as usize;
        out.push((op, at, len));
        at += 9 + len;
    }
    out
}

/// The byte offset of the first record with opcode `op`.
fn first(file: &[u8], op: u8) -> usize {
    records(file)
        .iter()
        .find(|r| r.0 == op)
        .unwrap_or_else(|| panic!("no record {op:#04x}"))
        .1
}

/// Where the uncompressed CRC of the chunk at `at` is written.
fn chunk_crc_at(at: usize) -> usize {
    at + 9 + 24
}

/// Where the data section's CRC (in the Data End record) is written.
fn data_crc_at(file: &[u8]) -> usize {
    first(file, 0x0F) + 9
}

fn topics() -> Topics {
    Topics::default()
}

fn read(bytes: &[u8]) -> Result<Bag, BagError> {
    Bag::from_mcap(Path::new("test.mcap"), bytes, &topics())
}

fn corrupt(bytes: &[u8]) -> Corrupt {
    match read(bytes) {
        Err(BagError::Corrupt(_, e)) => e,
        Err(e) => panic!("refused, but not as damaged: {e}"),
        Ok(b) => panic!(
            "read as valid: {} odometry poses, x of the last {:?}",
            b.odometry.len(),
            b.odometry.last().map(|o| o.value.x)
        ),
    }
}

/// Overwrites the 8 bytes of odometry message `i`'s x (in an uncompressed chunk) with `x`.
fn damage_odometry(file: &mut [u8], i: u32, x: f64) -> usize {
    let pattern = odom_x(i).to_le_bytes();
    let at = file
        .windows(8)
        .position(|w| w == pattern)
        .expect("the message's x in the file");
    file[at..at + 8].copy_from_slice(&x.to_le_bytes());
    at
}

#[test]
fn a_damaged_message_is_refused_by_its_chunk_crc() {
    let good = write_bag(None);
    let bag = read(&good).unwrap();
    assert_eq!(bag.odometry.len(), 20);
    assert_eq!(bag.odometry[5].value.x, odom_x(6));
    let chunk = first(&good, 0x06);
    // One message's position 15 m off, as a damaged sector would put it.
    let mut bad = good.clone();
    damage_odometry(&mut bad, 6, odom_x(6) + 15.0);
    let e = corrupt(&bad);
    assert!(
        matches!(e, Corrupt::BadCrc { what: CrcOf::Chunk { at }, saved, calculated }
            if at == chunk && saved != calculated),
        "{e:?}"
    );
    let message = e.to_string();
    assert!(
        message.contains(&format!("chunk at byte {chunk}")),
        "{message}"
    );
    // Without the chunk's CRC, the data section's CRC still covers the chunk.
    bad[chunk_crc_at(chunk)..][..4].fill(0);
    let data_end = first(&bad, 0x0F);
    let e = corrupt(&bad);
    assert!(
        matches!(e, Corrupt::BadCrc { what: CrcOf::DataSection { at }, .. } if at == data_end),
        "{e:?}"
    );
    assert!(e.to_string().contains(&format!("byte {data_end}")), "{e}");
    // With neither CRC written (0: "not written" in the MCAP specification) nothing says the
    // message is damaged: it is read, as the reference library reads it.
    let at = data_crc_at(&bad);
    bad[at..at + 4].fill(0);
    let bag = read(&bad).unwrap();
    assert_eq!(bag.odometry[5].value.x, odom_x(6) + 15.0);
}

#[test]
fn a_zstd_chunk_whose_crc_is_wrong_is_refused() {
    let good = write_bag(Some(mcap::Compression::Zstd));
    read(&good).unwrap();
    let chunk = first(&good, 0x06);
    let mut bad = good.clone();
    bad[chunk_crc_at(chunk)] ^= 0x01;
    let e = corrupt(&bad);
    assert!(
        matches!(e, Corrupt::BadCrc { what: CrcOf::Chunk { at }, .. } if at == chunk),
        "{e:?}"
    );
    // The same chunk with its CRC not written reads (the data section's CRC is then wrong too:
    // it covers the chunk's bytes, so it is cleared as well).
    bad[chunk_crc_at(chunk)..][..4].fill(0);
    let at = data_crc_at(&bad);
    bad[at..at + 4].fill(0);
    assert_eq!(read(&bad).unwrap().odometry.len(), 20);
}

/// Changes the last byte of the header record (of its library string).
fn damage_header(file: &mut [u8]) {
    let header = first(file, 0x01);
    let len = u64::from_le_bytes(file[header + 1..header + 9].try_into().unwrap()) as usize;
    assert!(len > 8, "a library string");
    file[header + 9 + len - 1] ^= 0x20;
}

#[test]
fn a_damaged_header_is_refused_by_the_data_section_crc() {
    let mut bad = write_bag(Some(mcap::Compression::Zstd));
    damage_header(&mut bad);
    let data_end = first(&bad, 0x0F);
    let e = corrupt(&bad);
    assert!(
        matches!(e, Corrupt::BadCrc { what: CrcOf::DataSection { at }, .. } if at == data_end),
        "{e:?}"
    );
}

#[test]
fn a_damaged_summary_is_refused_by_the_summary_crc() {
    let good = write_bag(Some(mcap::Compression::Zstd));
    // The statistics' message count (the record's first field).
    let stats = first(&good, 0x0B);
    let mut bad = good.clone();
    bad[stats + 9] ^= 0x04;
    let footer = first(&bad, 0x02);
    let e = corrupt(&bad);
    assert!(
        matches!(e, Corrupt::BadCrc { what: CrcOf::SummarySection { at }, .. } if at == footer),
        "{e:?}"
    );
    assert!(e.to_string().contains(&format!("byte {footer}")), "{e}");
}

/// A file with one zstd chunk whose first record (a schema) says its name is 4,294,967,280
/// bytes long; the chunk's CRC and sizes are right, so only the length check can refuse it.
fn huge_length_in_zstd_chunk() -> Vec<u8> {
    let good = write_bag(Some(mcap::Compression::Zstd));
    let chunk = first(&good, 0x06);
    let body = &good[chunk + 9..];
    let name_len = u32::from_le_bytes(body[28..32].try_into().unwrap()) as usize;
    assert_eq!(&body[32..32 + name_len], b"zstd");
    let data_at = 32 + name_len + 8;
    let data_len = u64::from_le_bytes(body[data_at - 8..data_at].try_into().unwrap()) as usize;
    let mut records = zstd::decode_all(&body[data_at..data_at + data_len]).unwrap();
    assert_eq!(records[0], 0x03, "a schema first");
    // Schema: opcode, length, id (u16), name length (u32) …
    records[9 + 2..9 + 6].copy_from_slice(&0xffff_fff0u32.to_le_bytes());
    let compressed = zstd::encode_all(&records[..], 3).unwrap();
    let mut chunk_body = body[..16].to_vec();
    chunk_body.extend((records.len() as u64).to_le_bytes());
    chunk_body.extend(crc32fast::hash(&records).to_le_bytes());
    chunk_body.extend(4u32.to_le_bytes());
    chunk_body.extend(b"zstd");
    chunk_body.extend((compressed.len() as u64).to_le_bytes());
    chunk_body.extend(&compressed);
    let mut file = good[..chunk].to_vec();
    let mut record = |op: u8, body: &[u8]| {
        file.push(op);
        file.extend((body.len() as u64).to_le_bytes());
        file.extend(body);
    };
    record(0x06, &chunk_body);
    record(0x0F, &[0; 4]);
    record(0x02, &[0; 20]);
    file.extend(MAGIC);
    file
}

/// Where this test binary writes its files.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bf-bag-integrity-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Reads the bag at `path` in a child process with 4 GB of address space and 60 s; its stdout
/// (`CHILD accepted` or `CHILD refused ERROR`, the error's `Debug`). The child must exit
/// cleanly: an abort (an allocation from an unchecked length) or a kill (a read without end)
/// fails the test.
fn in_child(path: &Path) -> String {
    let exe = std::env::current_exe().unwrap();
    let out = Command::new("sh")
        .arg("-c")
        .arg(
            r#"ulimit -v 4000000; exec timeout 60 "$0" child --exact --nocapture --test-threads=1"#,
        )
        .arg(&exe)
        .env("BEAMFIELD_BAG_CHILD", path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "the reader of {} in 4 GB of address space ended with {}:\n{stdout}\n{}",
        path.display(),
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// Not a test by itself: the child of [`in_child`] (does nothing without its variable).
#[test]
fn child() {
    let Some(path) = std::env::var_os("BEAMFIELD_BAG_CHILD") else {
        return;
    };
    match Bag::read(Path::new(&path), &topics()) {
        Ok(_) => println!("CHILD accepted"),
        Err(e) => println!("CHILD refused {e:?}"),
    }
}

#[test]
fn a_huge_length_inside_a_zstd_chunk_is_refused_before_anything_is_allocated() {
    let file = huge_length_in_zstd_chunk();
    let chunk = first(&file, 0x06);
    // In this process: the typed error, at the schema (byte 0 of the chunk's records).
    assert_eq!(
        corrupt(&file),
        Corrupt::Length(BadLength {
            at: 0,
            what: "a schema's field",
            chunk: Some(chunk),
        })
    );
    let path = scratch("huge-length.mcap");
    std::fs::write(&path, &file).unwrap();
    let out = in_child(&path);
    std::fs::remove_file(&path).unwrap();
    assert!(
        out.contains("CHILD refused Corrupt(") && out.contains("a schema's field"),
        "{out}"
    );
}

#[test]
fn devices_and_fifos_are_refused_before_they_are_read() {
    let out = in_child(Path::new("/dev/zero"));
    assert!(
        out.contains("CHILD refused NotAFile(\"/dev/zero\")"),
        "{out}"
    );
    let fifo = scratch("fifo.mcap");
    let _ = std::fs::remove_file(&fifo);
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let out = in_child(&fifo);
    std::fs::remove_file(&fifo).unwrap();
    assert!(out.contains("CHILD refused NotAFile("), "{out}");
}

#[test]
fn a_file_over_2_gib_is_refused_from_its_size() {
    // Sparse: 2 GiB + 1 byte of holes, no disk space used.
    let path = scratch("big.mcap");
    let f = std::fs::File::create(&path).unwrap();
    f.set_len(MAX_BAG_FILE_BYTES + 1).unwrap();
    drop(f);
    let out = in_child(&path);
    std::fs::remove_file(&path).unwrap();
    assert!(
        out.contains(&format!(
            "TooLarge {{ path: {path:?}, bytes: {}, limit: {MAX_BAG_FILE_BYTES} }}",
            MAX_BAG_FILE_BYTES + 1
        )),
        "{out}"
    );
}

#[test]
fn a_file_longer_than_its_size_says_is_cut_at_the_limit_plus_one() {
    // /proc files say they are 0 bytes long: only the bounded read can stop one.
    let path = Path::new("/proc/self/status");
    assert_eq!(std::fs::metadata(path).unwrap().len(), 0);
    match read_bounded(path, 16) {
        Err(BagError::TooLarge { bytes, limit, .. }) => assert_eq!((bytes, limit), (17, 16)),
        other => panic!("{other:?}"),
    }
    assert!(read_bounded(path, 1 << 20).unwrap().len() > 16);
}

#[test]
fn a_chunk_that_decompresses_to_another_size_than_declared_is_refused() {
    let good = write_bag(Some(mcap::Compression::Zstd));
    let chunk = first(&good, 0x06);
    let size_at = chunk + 9 + 16;
    let declared = u64::from_le_bytes(good[size_at..size_at + 8].try_into().unwrap());
    assert!(declared < MAX_CHUNK_BYTES);
    for wrong in [declared - 1, declared + 1] {
        let mut bad = good.clone();
        bad[size_at..size_at + 8].copy_from_slice(&wrong.to_le_bytes());
        let e = corrupt(&bad);
        assert!(
            matches!(e, Corrupt::Decompress { at, compression: "zstd", .. } if at == chunk),
            "{e:?}"
        );
    }
}

/// The damaged files of the tests above, each with whether this reader accepts it.
fn cases() -> Vec<(&'static str, Vec<u8>)> {
    let none = write_bag(None);
    let zstd = write_bag(Some(mcap::Compression::Zstd));
    let lz4 = write_bag(Some(mcap::Compression::Lz4));
    let mut message = none.clone();
    damage_odometry(&mut message, 6, odom_x(6) + 15.0);
    let mut message_no_chunk_crc = message.clone();
    message_no_chunk_crc[chunk_crc_at(first(&none, 0x06))..][..4].fill(0);
    let mut message_no_crcs = message_no_chunk_crc.clone();
    let at = data_crc_at(&none);
    message_no_crcs[at..at + 4].fill(0);
    let mut zstd_crc = zstd.clone();
    zstd_crc[chunk_crc_at(first(&zstd, 0x06))] ^= 1;
    let mut lz4_crc = lz4.clone();
    lz4_crc[chunk_crc_at(first(&lz4, 0x06))] ^= 1;
    let mut header = zstd.clone();
    damage_header(&mut header);
    let mut summary = zstd.clone();
    summary[first(&zstd, 0x0B) + 9] ^= 0x04;
    vec![
        ("good_uncompressed", none),
        ("good_zstd", zstd),
        ("good_lz4", lz4),
        ("message_damaged", message),
        ("message_damaged_no_chunk_crc", message_no_chunk_crc),
        ("message_damaged_no_crcs", message_no_crcs),
        ("zstd_chunk_crc_wrong", zstd_crc),
        ("lz4_chunk_crc_wrong", lz4_crc),
        ("header_damaged", header),
        ("summary_damaged", summary),
        ("huge_length_in_zstd_chunk", huge_length_in_zstd_chunk()),
    ]
}

fn python_missing() -> Option<String> {
    match Command::new("python3").args(["-c", "import mcap"]).output() {
        Err(e) => Some(format!("python3 not found ({e})")),
        Ok(o) if !o.status.success() => Some(format!(
            "python3 has no `mcap` package (pip install mcap==1.6.0): {}",
            String::from_utf8_lossy(&o.stderr)
                .lines()
                .last()
                .unwrap_or("")
        )),
        Ok(_) => None,
    }
}

#[test]
fn the_reference_library_refuses_and_accepts_the_same_files() {
    if let Some(why) = python_missing() {
        println!("SKIPPED mcap reference check: {why}");
        return;
    }
    let mut paths = Vec::new();
    let mut ours = BTreeMap::new();
    for (name, bytes) in cases() {
        let path = scratch(&format!("{name}.mcap"));
        std::fs::write(&path, &bytes).unwrap();
        ours.insert(name.to_string(), read(&bytes).map_err(|e| e.to_string()));
        paths.push(path);
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/mcap_reference.py");
    let out = Command::new("python3")
        .arg(&script)
        .args(&paths)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "mcap_reference.py failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for path in &paths {
        std::fs::remove_file(path).unwrap();
    }
    let stdout = String::from_utf8(out.stdout).unwrap();
    let mut seen = 0;
    for line in stdout.lines() {
        let (name, verdict) = line.split_once(' ').unwrap();
        let accepted = verdict == "accept";
        assert!(accepted || verdict.starts_with("refuse"), "{line}");
        let us = &ours[name];
        assert_eq!(
            us.is_ok(),
            accepted,
            "{name}: the reference says {verdict}, this reader says {us:?}",
            us = us.as_ref().map(|_| "accept")
        );
        seen += 1;
    }
    assert_eq!(seen, ours.len(), "{stdout}");
    // Both kinds are among the files: the comparison is not one-sided.
    assert!(ours.values().filter(|r| r.is_ok()).count() >= 4);
    assert!(ours.values().filter(|r| r.is_err()).count() >= 6);
}

/// Files written by another writer (PyPI rosbags) pass every check: the shared Intel bag and
/// the fuzz seed. rosbags writes no CRC (0 in every chunk, the Data End and the Footer), so
/// only the length and size checks apply to its files.
#[test]
fn bags_written_by_rosbags_pass_the_checks() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let intel = root.join("tools/tests/data/intel-bag");
    let topics = Topics {
        reference: Some("/ground_truth".into()),
        ..Topics::default()
    };
    let bag = Bag::read(&intel, &topics).unwrap();
    assert!(bag.scans.len() > 100 && !bag.reference.is_empty());
    let seed = std::fs::read(root.join("fuzz/seeds/bag_decode/three-scans.mcap")).unwrap();
    beamfield_bag::guard::check(&seed).unwrap();
    for bytes in [
        read_bounded(&intel.join("intel-bag.mcap"), MAX_BAG_FILE_BYTES).unwrap(),
        seed,
    ] {
        let chunk = first(&bytes, 0x06);
        let at = data_crc_at(&bytes);
        assert_eq!(
            (&bytes[chunk_crc_at(chunk)..][..4], &bytes[at..at + 4]),
            (&[0u8; 4][..], &[0u8; 4][..])
        );
    }
}

/// Inputs the fuzzer (`fuzz/fuzz_targets/bag_decode.rs`) found, kept as its seeds: each is
/// refused without a panic.
#[test]
fn fuzz_findings_are_refused() {
    let seeds = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/seeds/bag_decode");
    // An attachment with no room for its CRC: the `mcap` crate panicked slicing it.
    let bytes = std::fs::read(seeds.join("panic-attachment-without-crc.mcap")).unwrap();
    let e = corrupt(&bytes);
    assert!(
        matches!(
            e,
            Corrupt::Length(BadLength {
                what: "an attachment's field",
                ..
            })
        ),
        "{e:?}"
    );
}
