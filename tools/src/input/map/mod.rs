//! ROS map_server maps (YAML + PGM or PNG), read with map_server's semantics exactly.
//!
//! For each pixel, `v` is its grey level (the mean of the colour channels, alpha ignored),
//! `v ← 255 − v` when `negate` is set, and `p = (255 − v) / 255` (in f64, as map_server does).
//! `p > occupied_thresh` is occupied, `p < free_thresh` free, anything else unknown (trinary;
//! `scale` mode classifies occupied and free cells the same way, which is all the distance field
//! needs). A pixel of 205 gives `p = 0.196078…`, above the usual `free_thresh` of 0.196: unknown.
//!
//! Image row 0 is the **top** of the map; the grid this module returns has row 0 at the
//! **bottom** (lowest y), the map frame's and the blob's order. `origin` is the lower-left corner
//! of the lower-left cell; its yaw must be 0 (map_server ignores it too; we refuse it rather than
//! silently drop a rotation).

mod error;
pub use error::{MapError, DEFAULT_MAX_CELLS};

use serde::Deserialize;

use std::path::Path;

/// What one cell of a map is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Occupancy {
    /// `p > occupied_thresh`.
    Occupied,
    /// `p < free_thresh`.
    Free,
    /// Neither.
    Unknown,
}

/// A loaded occupancy grid.
#[derive(Clone, Debug)]
pub struct OccupancyMap {
    /// Cells per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Cell size, metres.
    pub resolution_m: f64,
    /// Lower-left corner of cell (0, 0), metres.
    pub origin_x_m: f64,
    /// Lower-left corner of cell (0, 0), metres.
    pub origin_y_m: f64,
    /// Row-major, row 0 = lowest y (the image's bottom row).
    pub cells: Vec<Occupancy>,
}

impl OccupancyMap {
    /// A mapping grid (`beamfield map from-log`'s trinary cells) as a loaded map: same cells,
    /// same geometry. The blob builder's input.
    pub fn from_grid(grid: &crate::mapping::OccupancyGrid) -> Self {
        use crate::mapping::Cell;
        let g = grid.geometry();
        Self {
            width: g.width as u32,
            height: g.height as u32,
            resolution_m: g.resolution_m,
            origin_x_m: g.origin_x_m,
            origin_y_m: g.origin_y_m,
            cells: grid
                .cells()
                .iter()
                .map(|c| match c {
                    Cell::Occupied => Occupancy::Occupied,
                    Cell::Free => Occupancy::Free,
                    Cell::Unknown => Occupancy::Unknown,
                })
                .collect(),
        }
    }

    /// The cell at column `ix`, row `iy` (row 0 = lowest y).
    pub fn get(&self, ix: u32, iy: u32) -> Option<Occupancy> {
        if ix >= self.width || iy >= self.height {
            return None;
        }
        self.cells
            .get(iy as usize * self.width as usize + ix as usize)
            .copied()
    }

    /// Number of occupied cells.
    pub fn occupied_count(&self) -> usize {
        self.cells
            .iter()
            .filter(|c| **c == Occupancy::Occupied)
            .count()
    }
}

/// The keys of a map_server YAML file.
#[derive(Debug, Deserialize)]
struct MapYaml {
    image: String,
    resolution: f64,
    origin: Vec<f64>,
    #[serde(default)]
    negate: Negate,
    occupied_thresh: f64,
    free_thresh: f64,
    #[serde(default)]
    mode: Option<String>,
}

/// map_server reads `negate` as an int; accept `0`/`1` and `true`/`false`.
#[derive(Debug, Default, Deserialize)]
#[serde(untagged)]
enum Negate {
    #[default]
    Absent,
    Int(i64),
    Bool(bool),
}

impl Negate {
    fn is_set(&self) -> bool {
        match self {
            Self::Absent => false,
            Self::Int(i) => *i != 0,
            Self::Bool(b) => *b,
        }
    }
}

/// Classifies one grey level (0..=255) with map_server's rule.
pub fn classify_pixel(
    grey: f64,
    negate: bool,
    occupied_thresh: f64,
    free_thresh: f64,
) -> Occupancy {
    let v = if negate { 255.0 - grey } else { grey };
    let p = (255.0 - v) / 255.0;
    if p > occupied_thresh {
        Occupancy::Occupied
    } else if p < free_thresh {
        Occupancy::Free
    } else {
        Occupancy::Unknown
    }
}

/// Loads a map_server map from its YAML file with the default cell limit
/// ([`DEFAULT_MAX_CELLS`]); see [`load_map_limited`].
///
/// # Errors
/// As [`load_map_limited`].
pub fn load_map(yaml_path: &Path) -> Result<OccupancyMap, MapError> {
    load_map_limited(yaml_path, DEFAULT_MAX_CELLS)
}

/// The longest map YAML read, bytes (a map_server YAML is a few hundred bytes).
const MAX_YAML_BYTES: u64 = 1 << 20;

/// Loads a map_server map from its YAML file; the image path is relative to the YAML's folder
/// (an absolute path is taken as it is, as map_server does) and must name a regular file. The
/// image's dimensions are read from its header first: more than `max_cells` cells is refused
/// before anything is decoded, and the image is streamed from the file, never read whole.
///
/// # Errors
/// [`MapError`]: a missing or unreadable file, malformed YAML (or over 1 MiB), an image that
/// is not a regular file, too large or undecodable, bad thresholds, resolution or origin, an
/// unsupported mode.
pub fn load_map_limited(yaml_path: &Path, max_cells: u64) -> Result<OccupancyMap, MapError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| MapError::Io { path, source }
    };
    let mut bytes = Vec::new();
    {
        use std::io::Read;
        std::fs::File::open(yaml_path)
            .map_err(io(yaml_path))?
            .take(MAX_YAML_BYTES + 1)
            .read_to_end(&mut bytes)
            .map_err(io(yaml_path))?;
    }
    // The map's image (or a blob) where its YAML goes: said as such, not as a YAML or UTF-8
    // error about its bytes.
    if let Some(kind) = crate::input::kind::file_kind(&bytes) {
        return Err(MapError::NotYaml {
            path: yaml_path.to_path_buf(),
            kind,
        });
    }
    let text = String::from_utf8(bytes).map_err(|_| MapError::Yaml {
        path: yaml_path.to_path_buf(),
        message: "not UTF-8 text; pass the map's YAML (map_server's: image, resolution, \
                  origin, thresholds)"
            .into(),
    })?;
    if text.len() as u64 > MAX_YAML_BYTES {
        return Err(MapError::Yaml {
            path: yaml_path.to_path_buf(),
            message: format!("longer than {MAX_YAML_BYTES} bytes"),
        });
    }
    let y: MapYaml = serde_yaml::from_str(&text).map_err(|e| MapError::Yaml {
        path: yaml_path.to_path_buf(),
        message: e.to_string(),
    })?;
    if let Some(mode) = &y.mode {
        if mode != "trinary" && mode != "scale" {
            return Err(MapError::UnsupportedMode(mode.clone()));
        }
    }
    let (occ, free) = (y.occupied_thresh, y.free_thresh);
    if !(occ.is_finite() && free.is_finite() && 0.0 <= free && free < occ && occ <= 1.0) {
        return Err(MapError::BadThresholds {
            occupied: occ,
            free,
        });
    }
    if !(y.resolution.is_finite() && y.resolution > 0.0) {
        return Err(MapError::BadResolution(y.resolution));
    }
    let (ox, oy) = match y.origin.as_slice() {
        [x, y_, rest @ ..] if rest.len() <= 1 => {
            let yaw = rest.first().copied().unwrap_or(0.0);
            if !(x.is_finite() && y_.is_finite()) {
                return Err(MapError::BadOrigin("not finite".into()));
            }
            if yaw != 0.0 {
                return Err(MapError::BadOrigin(format!(
                    "yaw {yaw} is not supported (must be 0)"
                )));
            }
            (*x, *y_)
        }
        _ => {
            return Err(MapError::BadOrigin(
                "expected [x, y, yaw] with 2 or 3 numbers".into(),
            ))
        }
    };
    let image_path = yaml_path
        .parent()
        .unwrap_or_else(|| Path::new("."))
        .join(&y.image);
    let meta = std::fs::metadata(&image_path).map_err(io(&image_path))?;
    if !meta.is_file() {
        return Err(MapError::NotAFile(image_path));
    }
    let decode_err = |e: image::ImageError| MapError::Image {
        path: image_path.clone(),
        message: e.to_string(),
    };
    let open = || -> Result<_, MapError> {
        image::ImageReader::open(&image_path)
            .map_err(io(&image_path))?
            .with_guessed_format()
            .map_err(io(&image_path))
    };
    let (w, h) = open()?.into_dimensions().map_err(decode_err)?;
    if w == 0 || h == 0 {
        return Err(MapError::EmptyImage(image_path));
    }
    if u64::from(w) * u64::from(h) > max_cells {
        return Err(MapError::TooLarge {
            path: image_path,
            width: w,
            height: h,
            max_cells,
        });
    }
    let mut reader = open()?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(w);
    limits.max_image_height = Some(h);
    reader.limits(limits);
    let img = reader.decode().map_err(decode_err)?;
    if (img.width(), img.height()) != (w, h) {
        return Err(MapError::Image {
            path: image_path,
            message: "decoded size differs from the header's".into(),
        });
    }
    let negate = y.negate.is_set();
    let mut cells = vec![Occupancy::Unknown; w as usize * h as usize];
    // Grey as the mean of the colour channels, alpha dropped (map_server's averaging). Read
    // as 16 bits: an 8-bit value v arrives as 257·v, and dividing the exact integer sum by 257
    // gives back v (or the channel sum) exactly, so 8-bit images are classified bit for bit as
    // map_server does.
    let rgba = img.to_rgba16();
    let has_colour = img.color().has_color();
    for (x, row_img, px) in rgba.enumerate_pixels() {
        let [r, g, b, _a] = px.0;
        let grey = if has_colour {
            (f64::from(r) + f64::from(g) + f64::from(b)) / 257.0 / 3.0
        } else {
            f64::from(r) / 257.0
        };
        let iy = h - 1 - row_img;
        if let Some(c) = cells.get_mut(iy as usize * w as usize + x as usize) {
            *c = classify_pixel(grey, negate, occ, free);
        }
    }
    Ok(OccupancyMap {
        width: w,
        height: h,
        resolution_m: y.resolution,
        origin_x_m: ox,
        origin_y_m: oy,
        cells,
    })
}

#[cfg(test)]
mod tests;
