//! Times building one map's blob raw and tiled in the same process, alternately, and prints the
//! medians and their ratio (tiled over raw). Both include the exact transform and the encoding;
//! the tiled build also deduplicates the tiles.
//!
//! Usage: `blob_build_ratio MAP.yaml [ROUNDS]` (default 7 rounds). The criterion bench
//! `cargo bench -p host-tests --bench field -- blob_build` measures the same two builds.

use beamfield_tools::blob::{build_blob_encoded, Encoding};
use beamfield_tools::input::map::load_map;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(map_path) = args.first().map(PathBuf::from) else {
        eprintln!("usage: blob_build_ratio MAP.yaml [ROUNDS]");
        return ExitCode::FAILURE;
    };
    let rounds: usize = match args.get(1).map(|r| r.parse()) {
        None => 7,
        Some(Ok(r)) if r > 0 => r,
        Some(_) => {
            eprintln!("blob_build_ratio: ROUNDS must be a positive integer");
            return ExitCode::FAILURE;
        }
    };
    let map = match load_map(&map_path) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("blob_build_ratio: {e}");
            return ExitCode::FAILURE;
        }
    };
    let mut times = [Vec::new(), Vec::new()];
    let mut sizes = [0usize; 2];
    for round in 0..rounds {
        for (k, enc) in [Encoding::Raw, Encoding::Tiled].into_iter().enumerate() {
            let t = Instant::now();
            match build_blob_encoded(&map, 2.0, enc) {
                Ok(b) => sizes[k] = b.len(),
                Err(e) => {
                    eprintln!("blob_build_ratio: {e}");
                    return ExitCode::FAILURE;
                }
            }
            times[k].push(t.elapsed().as_secs_f64() * 1e3);
        }
        eprintln!("round {}/{rounds}", round + 1);
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (raw, tiled) = (median(&mut times[0]), median(&mut times[1]));
    println!(
        "{}: raw {} bytes in {raw:.1} ms, tiled {} bytes in {tiled:.1} ms (medians of {rounds}); tiled/raw build time {:.2}x",
        map_path.display(),
        sizes[0],
        sizes[1],
        tiled / raw
    );
    ExitCode::SUCCESS
}
