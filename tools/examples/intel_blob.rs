//! Writes the distance-field blob of the Intel lab map built from its own log (5 cm cells,
//! d_max 2 m): `cargo run -p beamfield-tools --release --example intel_blob -- LOG OUT.bin`.

use beamfield::field::DEFAULT_MAX_DIST_M;
use beamfield_tools::beam_fit::map_from_log;
use beamfield_tools::blob::build_blob;
use beamfield_tools::input::carmen::{CarmenLog, ReadOptions};
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let (Some(log_path), Some(out)) = (args.get(1), args.get(2)) else {
        eprintln!("usage: intel_blob LOG OUT.bin");
        return ExitCode::FAILURE;
    };
    let result = (|| -> Result<usize, String> {
        let log = CarmenLog::read_path(log_path.as_ref(), ReadOptions::default())
            .map_err(|e| e.to_string())?;
        let max = log
            .max_range
            .value_m()
            .ok_or("log has no max-range value")?;
        let map = map_from_log(&log, max).map_err(|e| e.to_string())?;
        let blob = build_blob(&map, DEFAULT_MAX_DIST_M).map_err(|e| e.to_string())?;
        std::fs::write(out, &blob).map_err(|e| format!("{out}: {e}"))?;
        Ok(blob.len())
    })();
    match result {
        Ok(n) => {
            eprintln!("wrote {out} ({n} bytes)");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("intel_blob: {e}");
            ExitCode::FAILURE
        }
    }
}
