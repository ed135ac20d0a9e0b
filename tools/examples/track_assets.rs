//! Writes the track firmware's input (`fixtures/assets/track.rs`) from the Intel lab log. Run by
//! `cargo xtask track-assets`.
//!
//! Usage: `track_assets LOG OUT_FILE`.

use beamfield_tools::track_assets::generate;
use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [log, out] = args.as_slice() else {
        eprintln!("usage: track_assets LOG OUT_FILE");
        return ExitCode::FAILURE;
    };
    let text = match generate(log) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("track_assets: {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Err(e) = std::fs::write(out, &text) {
        eprintln!("track_assets: {}: {e}", out.display());
        return ExitCode::FAILURE;
    }
    println!("wrote {} ({} bytes)", out.display(), text.len());
    ExitCode::SUCCESS
}
