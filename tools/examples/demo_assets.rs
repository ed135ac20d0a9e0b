//! Writes the demo firmware's assets (`firmware/assets/intel.bin`, the same field tiled as
//! `firmware/assets/intel-tiled.bin`; `fixtures/assets/scans.rs`,
//! `fixtures/assets/lidar_segment.rs`) from the Intel lab log. Run by `cargo xtask demo-assets`.
//!
//! Usage: `demo_assets LOG BLOB_DIR SOURCE_DIR`.

use beamfield_tools::blob::tile_blob;
use beamfield_tools::demo_assets::generate;
use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [log, out, sources] = args.as_slice() else {
        eprintln!("usage: demo_assets LOG BLOB_DIR SOURCE_DIR");
        return ExitCode::FAILURE;
    };
    let work = std::env::temp_dir().join(format!("beamfield-demo-{}", std::process::id()));
    let assets = match generate(log, &work) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("demo_assets: {e}");
            return ExitCode::FAILURE;
        }
    };
    let _ = std::fs::remove_dir_all(&work);
    let write = |dir: &PathBuf, name: &str, bytes: &[u8]| -> Result<(), String> {
        let p = dir.join(name);
        std::fs::write(&p, bytes).map_err(|e| format!("{}: {e}", p.display()))?;
        println!("wrote {} ({} bytes)", p.display(), bytes.len());
        Ok(())
    };
    let mkdir =
        |dir: &PathBuf| std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()));
    if let Err(e) = mkdir(out)
        .and_then(|()| mkdir(sources))
        .and_then(|()| write(out, "intel.bin", &assets.blob))
        .and_then(|()| tile_blob(&assets.blob).map_err(|e| format!("tiling the blob: {e}")))
        .and_then(|tiled| write(out, "intel-tiled.bin", &tiled))
        .and_then(|()| write(sources, "scans.rs", assets.scans_rs.as_bytes()))
        .and_then(|()| {
            write(
                sources,
                "lidar_segment.rs",
                assets.lidar_segment_rs.as_bytes(),
            )
        })
    {
        eprintln!("demo_assets: {e}");
        return ExitCode::FAILURE;
    }
    ExitCode::SUCCESS
}
