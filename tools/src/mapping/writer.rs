//! Writing an [`OccupancyGrid`] as a ROS map_server map (YAML + binary P5 PGM), the way
//! `map_saver` does (the PNG picture for people is [`crate::draw::map_picture`]).
//!
//! PGM pixels: 0 occupied, 254 free, 205 unknown; image row 0 is the **top** of the map (the
//! grid's last row). With `negate: 0` map_server reads `p = (255 − v)/255`: 0 → p = 1 > 0.65
//! occupied, 254 → p ≈ 0.004 < 0.196 free, 205 → p ≈ 0.19608, just above 0.196: unknown. The
//! YAML's `origin` is the lower-left corner of the lower-left cell, with yaw 0.

use super::grid::{Cell, OccupancyGrid};
use super::{FREE_THRESH, OCCUPIED_THRESH};
use std::io::Write;
use std::path::{Path, PathBuf};

/// PGM value of an occupied cell.
pub const PGM_OCCUPIED: u8 = 0;
/// PGM value of a free cell.
pub const PGM_FREE: u8 = 254;
/// PGM value of an unknown cell.
pub const PGM_UNKNOWN: u8 = 205;

/// Errors writing a map or a picture.
#[derive(Debug)]
#[non_exhaustive]
pub enum MapIoError {
    /// A file could not be written.
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The PNG encoder failed.
    Image {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: image::ImageError,
    },
    /// The YAML path has no file name to derive the PGM's name from.
    BadPath(PathBuf),
}

impl std::fmt::Display for MapIoError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Io { path, source } => write!(f, "cannot write {}: {source}", path.display()),
            Self::Image { path, source } => {
                write!(f, "cannot write image {}: {source}", path.display())
            }
            Self::BadPath(p) => write!(f, "{} is not a file path", p.display()),
        }
    }
}

impl std::error::Error for MapIoError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io { source, .. } => Some(source),
            Self::Image { source, .. } => Some(source),
            Self::BadPath(_) => None,
        }
    }
}

/// The two files written by [`write_map_server`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MapServerMap {
    /// The YAML file.
    pub yaml: PathBuf,
    /// The PGM image beside it (same stem, `.pgm`).
    pub pgm: PathBuf,
}

fn pgm_value(cell: Cell) -> u8 {
    match cell {
        Cell::Occupied => PGM_OCCUPIED,
        Cell::Free => PGM_FREE,
        Cell::Unknown => PGM_UNKNOWN,
    }
}

/// The P5 PGM bytes of a grid (row 0 of the image = top row of the map).
pub fn pgm_bytes(grid: &OccupancyGrid) -> Vec<u8> {
    let g = grid.geometry();
    let mut out = format!(
        "P5\n# CREATOR: beamfield map from-log {} m/pix\n{} {}\n255\n",
        g.resolution_m, g.width, g.height
    )
    .into_bytes();
    out.reserve(g.cells());
    for row in grid.cells().chunks(g.width).rev() {
        out.extend(row.iter().map(|&c| pgm_value(c)));
    }
    out
}

/// The YAML text of a map whose image file is `image_name` (a path relative to the YAML file).
pub fn yaml_text(grid: &OccupancyGrid, image_name: &str) -> String {
    let g = grid.geometry();
    // `{}` on f64 prints the shortest text that reads back to the same value.
    format!(
        "image: {image_name}\nmode: trinary\nresolution: {}\norigin: [{}, {}, 0.0]\n\
         negate: 0\noccupied_thresh: {OCCUPIED_THRESH}\nfree_thresh: {FREE_THRESH}\n",
        g.resolution_m, g.origin_x_m, g.origin_y_m
    )
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<(), MapIoError> {
    let io = |source| MapIoError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut f = std::fs::File::create(path).map_err(io)?;
    f.write_all(bytes).map_err(io)?;
    f.sync_all().map_err(io)
}

/// Writes `yaml_path` and the PGM beside it (same stem, `.pgm`). The YAML names the image by
/// its file name only, so the pair can be moved together.
///
/// # Errors
/// [`MapIoError::BadPath`] when `yaml_path` has no file name, [`MapIoError::Io`] when a file
/// cannot be written.
pub fn write_map_server(
    grid: &OccupancyGrid,
    yaml_path: &Path,
) -> Result<MapServerMap, MapIoError> {
    if yaml_path.file_name().is_none() {
        return Err(MapIoError::BadPath(yaml_path.to_path_buf()));
    }
    let pgm = yaml_path.with_extension("pgm");
    let image_name = pgm
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| MapIoError::BadPath(yaml_path.to_path_buf()))?
        .to_string();
    if pgm == yaml_path {
        return Err(MapIoError::BadPath(yaml_path.to_path_buf()));
    }
    write_file(&pgm, &pgm_bytes(grid))?;
    write_file(yaml_path, yaml_text(grid, &image_name).as_bytes())?;
    Ok(MapServerMap {
        yaml: yaml_path.to_path_buf(),
        pgm,
    })
}
