//! Hostile inputs to every command that reads a file, standard input or a count: each is bounded
//! (docs/resource-limits.md) and refused with one line on stderr and a non-zero exit status,
//! in bounded memory (the runs get 1 GiB of address space, `ulimit -v`) and without hanging (a
//! run still going after a generous kill timeout fails).

mod common;

use beamfield_tools::input::limits::{
    MAX_CAPTURE_BYTES, MAX_DECODED_SCANS, MAX_FIELD_FILE_BYTES, MAX_QUERY_LINE_BYTES,
    MAX_TEXT_FILE_BYTES,
};
use beamfield_tools::lidar_stream::{
    self, encode_scans, Format, LidarError, StreamDecoder, StreamOptions,
};
use common::{one_line_error, run_bounded};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beamfield-clilimits-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn data() -> PathBuf {
    host_tests::data_dir()
}

fn intel_log() -> String {
    data()
        .join("laser_intel_lab/intel-corrected.log")
        .display()
        .to_string()
}

/// A blob of the TurtleBot3 world map (with its free-space section) in `dir`.
fn blob(dir: &Path) -> String {
    let out = dir.join("tb.bin").display().to_string();
    let map = data().join("map_turtlebot3_world/map.yaml");
    let o = run_bounded(
        &[
            "field",
            "build",
            map.to_str().unwrap(),
            "--free-space",
            "-o",
            &out,
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

/// A FIFO at `path` (nobody ever writes to it: opening it for reading would block forever).
fn fifo(path: &Path) -> String {
    let st = std::process::Command::new("mkfifo")
        .arg(path)
        .status()
        .unwrap();
    assert!(st.success());
    path.display().to_string()
}

/// A sparse file of `len` zero bytes.
fn sparse(path: &Path, len: u64) -> String {
    std::fs::File::create(path).unwrap().set_len(len).unwrap();
    path.display().to_string()
}

/// Runs `args` (bounded), which must fail with exit status 1 and one line on stderr; returns it.
fn fails(args: &[&str]) -> String {
    let o = run_bounded(args, None);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {o:?}");
    one_line_error(&o)
}

/// Runs `args`, which clap must refuse as a usage error (exit status 2); returns the first line
/// of stderr.
fn usage_error(args: &[&str]) -> String {
    let o = run_bounded(args, None);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {o:?}");
    String::from_utf8_lossy(&o.stderr)
        .lines()
        .next()
        .unwrap_or("")
        .to_string()
}

#[test]
fn field_query_reads_stdin_in_bounded_lines() {
    let d = scratch("query");
    let b = blob(&d);
    // /dev/zero: one line that never ends. It used to grow a String to 4 GiB and abort, then
    // echo the line whole to stderr.
    let o = run_bounded(&["field", "query", &b], Some(Path::new("/dev/zero")));
    assert_eq!(o.status.code(), Some(1), "{o:?}");
    assert_eq!(
        one_line_error(&o),
        format!(
            "beamfield field: standard input line 1: longer than {MAX_QUERY_LINE_BYTES} bytes \
             (stopped reading)"
        )
    );
    // A long malformed line with an escape sequence is quoted as a short escaped prefix; a
    // non-UTF-8 line is a counted bad line; the good lines around them are answered.
    let input = d.join("in.txt");
    let mut text = b"1,2\nabc\x1b[31m,".to_vec();
    text.extend(std::iter::repeat_n(b'x', 50_000));
    text.extend_from_slice(b"\n\xff\xfe\n0,0\n");
    std::fs::write(&input, &text).unwrap();
    let o = run_bounded(&["field", "query", &b], Some(&input));
    assert_eq!(o.status.code(), Some(1));
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(out.lines().count(), 2, "{out}");
    assert!(out.starts_with("1,2,") && out.contains("\n0,0,"), "{out}");
    let err = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 3, "{err}");
    assert!(
        lines[0].starts_with("line 2: x is not a number: \"abc\\u{1b}[31m,xxx")
            && lines[0].ends_with("…\"")
            && lines[0].chars().count() < 120,
        "{}",
        lines[0]
    );
    assert_eq!(lines[1], "line 3: not UTF-8 text");
    assert_eq!(lines[2], "beamfield field: 2 malformed input line(s)");
    assert!(!err.contains('\u{1b}'));
}

#[test]
fn field_files_must_be_regular_and_at_most_128_mib() {
    let d = scratch("fieldfiles");
    let b = blob(&d);
    let fifo = fifo(&d.join("fifo"));
    let dir = d.display().to_string();
    let big = sparse(&d.join("big.bin"), MAX_FIELD_FILE_BYTES + 1);
    let out = d.join("out.bin").display().to_string();
    let png = d.join("out.png").display().to_string();
    for input in ["/dev/zero", fifo.as_str(), dir.as_str()] {
        let want = format!("beamfield field: {input} is not a regular file");
        assert_eq!(fails(&["field", "info", input]), want);
        assert_eq!(fails(&["field", "query", input]), want);
        assert_eq!(
            fails(&["field", "encode", input, "-o", &out, "--encoding", "raw"]),
            want
        );
        assert_eq!(fails(&["field", "render", input, "-o", &png]), want);
        let msg = format!("{input} is not a regular file");
        let log = intel_log();
        assert_eq!(
            fails(&["track", "--field", input, "--log", &log]),
            format!("beamfield track: {msg}")
        );
        assert_eq!(
            fails(&["score", "--field", input, "--log", &log, "--scan", "0"]),
            format!("beamfield score: {msg}")
        );
        assert_eq!(
            fails(&["calibrate", "--field", input, "--log", &log]),
            format!("beamfield calibrate: {msg}")
        );
        assert_eq!(
            fails(&["fit", "--field", input, "--log", &log]),
            format!("beamfield fit: {msg}")
        );
    }
    // One byte over the limit is refused from the file's size, before it is read.
    assert_eq!(
        fails(&["field", "info", &big]),
        format!(
            "beamfield field: {big} is larger than {MAX_FIELD_FILE_BYTES} bytes, the limit for \
             a field file"
        )
    );
    // A real blob is still read.
    let o = run_bounded(&["field", "info", &b], None);
    assert!(o.status.success(), "{o:?}");
}

#[test]
fn a_picture_is_at_most_2_pow_25_pixels() {
    use beamfield::field::{emit_blob, FieldHeader};
    let d = scratch("render");
    // 2^24 × 1 cells (16 MiB, within the file limit): one pixel per cell would be
    // 16,777,348 × 149 pixels, 7.5 GB of RGB.
    let header = FieldHeader::new(1 << 24, 1, 0.05, 0.0, 0.0);
    let codes = vec![255u8; 1 << 24];
    let mut bytes = vec![0u8; header.required_len().unwrap()];
    emit_blob(&header, &codes, &mut bytes).unwrap();
    let path = d.join("long.bin");
    std::fs::write(&path, &bytes).unwrap();
    let png = d.join("long.png");
    let err = fails(&[
        "field",
        "render",
        path.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(
        err.ends_with(
            "a picture of 16777348 x 149 = 2499824852 pixels is over the limit of 33554432"
        ),
        "{err}"
    );
    assert!(!png.exists());
}

#[test]
fn lidar_decode_reads_a_capped_stream() {
    let d = scratch("decode");
    // /dev/zero never ends: decoded in chunks, stopped past 64 MiB.
    assert_eq!(
        fails(&["lidar", "decode", "/dev/zero", "--format", "ld06"]),
        format!(
            "beamfield lidar: /dev/zero is larger than {MAX_CAPTURE_BYTES} bytes, the limit for \
             a LiDAR capture"
        )
    );
    // Exactly the limit is read (zeros: no frame, so refused as no XV-11 stream, after reading
    // all of it); one byte more is refused as too large.
    let at = sparse(&d.join("at.bin"), MAX_CAPTURE_BYTES);
    assert!(
        fails(&["lidar", "decode", &at, "--format", "xv11"]).contains(&format!(
            "no xv11 frame in {MAX_CAPTURE_BYTES} bytes: the stream does not look like xv11"
        ))
    );
    let over = sparse(&d.join("over.bin"), MAX_CAPTURE_BYTES + 1);
    assert!(fails(&["lidar", "decode", &over, "--format", "xv11"]).contains("is larger than"));
}

#[test]
fn lidar_decode_keeps_a_bounded_number_of_scans() {
    let log = beamfield_tools::input::carmen::CarmenLog::read_path(
        Path::new(&intel_log()),
        beamfield_tools::input::carmen::ReadOptions::default(),
    )
    .unwrap();
    let layout: beamfield::BeamLayout<{ lidar_stream::MAX_BEAMS }> = log
        .layout_with_mount(beamfield::SensorMount::CENTERED)
        .unwrap();
    let scans: Vec<Vec<f32>> = log
        .scans
        .iter()
        .take(30)
        .map(|s| s.ranges_m.clone())
        .collect();
    let options = StreamOptions {
        format: Format::Ld06,
        rpm: 600.0,
        noise_m: 0.0,
        garbage: 0,
        corrupt_rate: 0.0,
        seed: 1,
    };
    let (stream, _) = encode_scans(&layout, &scans, &options, |_| {}).unwrap();
    let full = lidar_stream::layout(lidar_stream::LayoutChoice::Full, 70.0).unwrap();
    let config = beamfield::lidar::AssemblerConfig::for_layout(&full);
    let decode = |max_scans: usize| {
        let mut d = StreamDecoder::new(Format::Ld06, &full, config, max_scans).unwrap();
        d.feed(&stream).and_then(|()| d.finish())
    };
    let all = decode(MAX_DECODED_SCANS).unwrap();
    assert_eq!(all.scans.len(), 30);
    assert_eq!(decode(30).unwrap().scans.len(), 30);
    assert!(matches!(decode(29), Err(LidarError::TooManyScans)));
}

#[test]
fn lidar_encode_bounds_its_garbage() {
    let d = scratch("encode");
    let out = d.join("s.bin").display().to_string();
    let log = intel_log();
    let first = usage_error(&[
        "lidar",
        "encode",
        "--log",
        &log,
        "--format",
        "ld06",
        "--garbage",
        "1000000000000",
        "-o",
        &out,
    ]);
    assert_eq!(
        first,
        "error: invalid value '1000000000000' for '--garbage <BYTES>': 1000000000000 is not in \
         0..=1048576"
    );
    let o = run_bounded(
        &[
            "--json",
            "lidar",
            "encode",
            "--log",
            &log,
            "--format",
            "ld06",
            "--garbage",
            "1048576",
            "--scans",
            "1",
            "-o",
            &out,
        ],
        None,
    );
    assert!(o.status.success(), "{o:?}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["garbage"], 1_048_576);
    // The log is read with the log's limit.
    assert_eq!(
        fails(&[
            "lidar",
            "encode",
            "--log",
            "/dev/zero",
            "--format",
            "ld06",
            "-o",
            &out
        ]),
        "beamfield lidar: /dev/zero is larger than 268435456 bytes, the limit for a CARMEN log"
    );
}

#[test]
fn count_options_are_bounded() {
    let log = intel_log();
    let f = "unused.bin";
    for (args, want) in [
        (
            vec![
                "track",
                "--field",
                f,
                "--log",
                &log,
                "--seeds",
                "1000000000000",
            ],
            "error: invalid value '1000000000000' for '--seeds <SEEDS>': 1000000000000 is not \
             in 1..=1000",
        ),
        (
            vec!["track", "--field", f, "--log", &log, "--seeds", "0"],
            "error: invalid value '0' for '--seeds <SEEDS>': 0 is not in 1..=1000",
        ),
        (
            vec!["track", "--field", f, "--log", &log, "--particles", "20001"],
            "error: invalid value '20001' for '--particles <PARTICLES>': 20001 is not in \
             1..=20000",
        ),
        (
            vec!["track", "--field", f, "--log", &log, "--stride", "0"],
            "error: invalid value '0' for '--stride <STRIDE>': 0 is not in 1..=1081",
        ),
        (
            vec![
                "fit",
                "--field",
                f,
                "--log",
                &log,
                "--iterations",
                "4000000000",
            ],
            "error: invalid value '4000000000' for '--iterations <ITERATIONS>': 4000000000 is \
             not in 0..=10000",
        ),
    ] {
        assert_eq!(usage_error(&args), want, "{args:?}");
    }
}

#[test]
fn track_with_the_largest_seed_wraps_instead_of_overflowing() {
    let d = scratch("seedwrap");
    let b = blob(&d);
    let log = intel_log();
    // SEED + SEEDS past u64::MAX: the seeds wrap (u64::MAX, 0), no overflow panic.
    let o = run_bounded(
        &[
            "--json",
            "track",
            "--field",
            &b,
            "--log",
            &log,
            "--seed",
            "18446744073709551615",
            "--seeds",
            "2",
            "--scans",
            "3",
            "--particles",
            "20",
        ],
        None,
    );
    assert!(o.status.success(), "{o:?}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let seeds: Vec<u64> = v["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["seed"].as_u64().unwrap())
        .collect();
    assert_eq!(seeds, vec![u64::MAX, 0]);
}

#[test]
fn calibrate_bounds_its_scores() {
    let d = scratch("calibrate");
    let b = blob(&d);
    let log = intel_log();
    // 60 scans × 401 × 401 × 401 poses = 3.9 G scores (31 GB) before the limit.
    let err = fails(&[
        "calibrate",
        "--field",
        &b,
        "--log",
        &log,
        "--half-xy",
        "0.8",
        "--step-xy",
        "0.004",
        "--half-deg",
        "20",
        "--step-deg",
        "0.1",
    ]);
    assert_eq!(
        err,
        "beamfield calibrate: 60 scans of 64481201 grid poses = 3868872060 scores, over the \
         limit of 33554432 (fewer --scans or a coarser grid)"
    );
}

#[test]
fn sonar_ring_file_is_bounded() {
    let d = scratch("sonar");
    assert_eq!(
        fails(&["sonar", "schedule", "--ring", "/dev/zero", "--rate", "5"]),
        "beamfield sonar: /dev/zero is not a regular file"
    );
    let big = sparse(&d.join("ring.toml"), MAX_TEXT_FILE_BYTES + 1);
    assert_eq!(
        fails(&["sonar", "schedule", "--ring", &big, "--rate", "5"]),
        format!(
            "beamfield sonar: {big} is larger than {MAX_TEXT_FILE_BYTES} bytes, the limit for a \
             ring description"
        )
    );
}

#[test]
fn score_variants_takes_at_most_16_variants() {
    let yaml = data().join("map_turtlebot3_world/map.yaml");
    let yaml = yaml.to_str().unwrap();
    let log = intel_log();
    let mut args = vec!["field", "score-variants", "--log", &log, "--scan", "0"];
    for _ in 0..17 {
        args.extend(["--variant", yaml]);
    }
    assert_eq!(
        fails(&args),
        "beamfield field: score-variants: 17 variants given: at most 16 (each is held in memory \
         with its field)"
    );
}

#[test]
fn field_encode_decodes_at_most_as_many_cells_as_a_raw_file_holds() {
    use beamfield::field::{emit_blob_tiled, tiled_max_len, tiled_scratch_len, FieldHeader};
    use beamfield_tools::blob::MAX_DECODED_CELLS;
    let d = scratch("encode-cells");
    // 12,000 × 12,000 = 144 M cells in an 18 MB tiled file (2 bytes of index per 16 cells):
    // decoded, more than a raw blob within the file limit holds.
    let header = FieldHeader::new(12_000, 12_000, 0.05, 0.0, 0.0);
    let codes = vec![255u8; 144_000_000];
    let mut scratch = vec![0u32; tiled_scratch_len(&header).unwrap()];
    let mut out = vec![0u8; tiled_max_len(&header).unwrap()];
    let n = emit_blob_tiled(&header, &codes, &mut scratch, &mut out).unwrap();
    drop((codes, scratch));
    let path = d.join("tiled.bin");
    std::fs::write(&path, &out[..n]).unwrap();
    let p = path.display().to_string();
    let o = d.join("raw.bin").display().to_string();
    for encoding in ["raw", "tiled"] {
        assert_eq!(
            fails(&["field", "encode", &p, "-o", &o, "--encoding", encoding]),
            format!(
                "beamfield field: {p}: a field of 12000 x 12000 = 144000000 cells, more than \
                 {MAX_DECODED_CELLS}, the most a field is decoded to"
            )
        );
    }
    assert!(!d.join("raw.bin").exists());
    // It is still a valid blob: `field info` reads it without decoding.
    let info = run_bounded(&["field", "info", &p], None);
    assert!(info.status.success(), "{info:?}");
}
