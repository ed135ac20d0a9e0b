//! `beamfield field build`: a blob from a map_server map (and its variants), the codes computed
//! once and written raw or tiled, optionally followed by the free-space section.

use crate::blob::{build_free_space, union_map, Encoding, FieldCodes, FieldError};
use crate::input::map::load_map_limited;
use beamfield::field::DEFAULT_MAX_DIST_M;
use clap::Args;
use serde::Serialize;
use std::fmt;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `beamfield field build`.
#[derive(Args, Debug)]
pub struct BuildArgs {
    /// The map's YAML file (map_server format: image, resolution, origin, negate,
    /// occupied_thresh, free_thresh).
    pub map: PathBuf,
    /// Where to write the blob.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Clamp distance d_max in metres (AMCL's laser_likelihood_max_dist).
    #[arg(long = "max-dist", default_value_t = DEFAULT_MAX_DIST_M)]
    pub max_dist: f32,
    /// Append a free-space section (the map's known-free cells, p < free_thresh, for
    /// uniform particle sampling; docs/free-space-format.md) right after the blob.
    #[arg(long = "free-space")]
    pub free_space: bool,
    /// How the codes are stored. `raw` is the default because every reader (older
    /// firmware, other languages' parsers) reads it and its lookup is the cheapest;
    /// choose `tiled` when the blob must be small (flash), scores are identical.
    #[arg(long, value_enum, default_value_t = Encoding::Raw)]
    pub encoding: Encoding,
    /// Bounded-lossy clamp (needs --encoding tiled): distances up to D metres keep their
    /// codes (steps of d_max/255), distances beyond D are stored as D and read as "D or
    /// more" (recorded in the blob). Far from walls the tiles become uniform and are
    /// stored once. Choose D several σ_hit from a wall, where the likelihood no longer
    /// changes (docs/blob-format.md gives the bound); 0.5 m keeps every score of the
    /// Intel demo (σ_hit 0.0588 m) bit for bit.
    #[arg(long = "clamp-m", value_name = "D")]
    pub clamp_m: Option<f32>,
    /// Another state of the same map (doors open or closed; same size, resolution and
    /// origin), repeatable. The blob then stores, per cell, the smallest distance over MAP
    /// and every variant: one transform over the union of their occupied cells (Thrun et
    /// al., Probabilistic Robotics, chapter 6, exercises). Build one blob per variant to
    /// tell which one explains a scan (`beamfield score` with each).
    #[arg(long = "variant", value_name = "MAP.yaml")]
    pub variants: Vec<PathBuf>,
    /// Refuse a map image with more cells than this, checked from the image header before
    /// decoding (the build needs about 10 bytes per cell at its peak).
    #[arg(long = "max-cells", default_value_t = crate::input::map::DEFAULT_MAX_CELLS)]
    pub max_cells: u64,
}

/// What `field build` wrote.
#[derive(Debug, Serialize)]
pub struct BuildReport {
    /// The blob file.
    pub output: String,
    /// Grid width, cells.
    pub width: u32,
    /// Grid height, cells.
    pub height: u32,
    /// Cell side, metres.
    pub resolution_m: f64,
    /// Map origin (x, y), metres.
    pub origin_m: [f64; 2],
    /// Occupied cells (of the union with the variants).
    pub occupied_cells: usize,
    /// Number of `--variant` maps.
    pub variants: usize,
    /// Clamp distance d_max, metres.
    pub max_dist_m: f32,
    /// The tiled encoding's clamp, metres.
    pub clamp_m: Option<f32>,
    /// `raw` or `tiled`.
    pub encoding: &'static str,
    /// File length: the blob and its free-space section, bytes.
    pub bytes: usize,
    /// Length of the free-space section, bytes (0 without one).
    pub free_space_bytes: usize,
    /// Blob bytes per cell.
    pub bytes_per_cell: f64,
    /// Time to load the maps, milliseconds.
    pub load_ms: f64,
    /// Time to transform, encode and write the free space, milliseconds.
    pub build_ms: f64,
    /// A free-space section was asked for.
    #[serde(skip)]
    pub free_space: bool,
}

/// Runs `field build`.
///
/// # Errors
/// [`FieldError`].
pub fn run(a: &BuildArgs) -> Result<BuildReport, FieldError> {
    if a.clamp_m.is_some() && a.encoding != Encoding::Tiled {
        return Err(FieldError::ClampNeedsTiled);
    }
    let t0 = Instant::now();
    let mut m = load_map_limited(&a.map, a.max_cells).map_err(FieldError::Map)?;
    // One variant at a time: memory does not grow with the number of variants.
    for p in &a.variants {
        let v = load_map_limited(p, a.max_cells).map_err(FieldError::Map)?;
        m = union_map(&m, &[(p.clone(), v)])?;
    }
    let t1 = Instant::now();
    let mut blob = FieldCodes::of_map(&m, a.max_dist)?.blob(a.encoding, a.clamp_m)?;
    let blob_len = blob.len();
    if a.free_space {
        blob.extend(build_free_space(&m)?);
    }
    let t2 = Instant::now();
    std::fs::write(&a.output, &blob).map_err(|e| FieldError::Io(a.output.clone(), e))?;
    let cells = u64::from(m.width) * u64::from(m.height);
    Ok(BuildReport {
        output: a.output.display().to_string(),
        width: m.width,
        height: m.height,
        resolution_m: m.resolution_m,
        origin_m: [m.origin_x_m, m.origin_y_m],
        occupied_cells: m.occupied_count(),
        variants: a.variants.len(),
        max_dist_m: a.max_dist,
        clamp_m: a.clamp_m,
        encoding: a.encoding.name(),
        bytes: blob.len(),
        free_space_bytes: blob.len() - blob_len,
        bytes_per_cell: blob_len as f64 / cells as f64,
        load_ms: (t1 - t0).as_secs_f64() * 1e3,
        build_ms: (t2 - t1).as_secs_f64() * 1e3,
        free_space: a.free_space,
    })
}

impl fmt::Display for BuildReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let blob_len = self.bytes - self.free_space_bytes;
        write!(
            f,
            "{}: {} × {} cells of {} m, origin ({}, {}), {} occupied, d_max {} m \
             (step {:.4} m){}; {} encoding, {} bytes ({:.4} bytes/cell){}; load {:.1} ms, \
             transform+encode {:.1} ms",
            self.output,
            self.width,
            self.height,
            self.resolution_m,
            self.origin_m[0],
            self.origin_m[1],
            self.occupied_cells,
            self.max_dist_m,
            self.max_dist_m / 255.0,
            self.clamp_m
                .map(|d| format!(", clamped at {d} m"))
                .unwrap_or_default(),
            self.encoding,
            blob_len,
            self.bytes_per_cell,
            if self.free_space {
                format!(" + {} bytes of free space", self.free_space_bytes)
            } else {
                String::new()
            },
            self.load_ms,
            self.build_ms,
        )
    }
}
