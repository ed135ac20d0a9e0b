//! `beamfield field …`: build a distance-field blob from a map, query it, render it.

use crate::input::map::{load_map_limited, MapError, Occupancy, OccupancyMap};
use beamfield::field::{
    edt_scratch_len, emit_blob_from_squared_cells, emit_blob_tiled_clamped, squared_edt,
    tiled_max_len, tiled_scratch_len, BlobError, EdtError, EdtScratch, FieldHeader, FieldView,
    DEFAULT_MAX_DIST_M, EDT_INFINITY, ENCODING_TILED,
};
use beamfield::field::{emit_free_space, free_space_len, FreeSpaceError, FreeSpaceGrid};
use clap::{Args, Subcommand, ValueEnum};
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `beamfield field`: distance-field blobs (the likelihood field's map, for flash).
#[derive(Args, Debug)]
pub struct FieldArgs {
    #[command(subcommand)]
    command: FieldCommand,
}

/// How `field build` stores the codes (both give the same codes, so the same scores).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Encoding {
    /// Encoding 1: one byte per cell (every reader of the format reads it).
    Raw,
    /// Encoding 2: deduplicated 4 × 4 tiles, 0.28–0.48 bytes per cell on the shared maps;
    /// needs a reader that knows encoding 2.
    Tiled,
}

#[derive(Subcommand, Debug)]
enum FieldCommand {
    /// Build a blob from a ROS map_server map (YAML + PGM/PNG).
    ///
    /// Occupied cells seed an exact
    /// Euclidean distance transform; distances are coded as one byte per cell, in steps of
    /// d_max/255 and clamped at d_max, and stored raw (default) or in deduplicated tiles
    /// (--encoding tiled: the same codes, a quarter to a half of the bytes). The format is
    /// described in docs/blob-format.md.
    Build {
        /// The map's YAML file (map_server format: image, resolution, origin, negate,
        /// occupied_thresh, free_thresh).
        map: PathBuf,
        /// Where to write the blob.
        #[arg(short, long)]
        output: PathBuf,
        /// Clamp distance d_max in metres (AMCL's laser_likelihood_max_dist).
        #[arg(long = "max-dist", default_value_t = DEFAULT_MAX_DIST_M)]
        max_dist: f32,
        /// Append a free-space section (the map's known-free cells, p < free_thresh, for
        /// uniform particle sampling; docs/free-space-format.md) right after the blob.
        #[arg(long = "free-space")]
        free_space: bool,
        /// How the codes are stored. `raw` is the default because every reader (older
        /// firmware, other languages' parsers) reads it and its lookup is the cheapest;
        /// choose `tiled` when the blob must be small (flash), scores are identical.
        #[arg(long, value_enum, default_value_t = Encoding::Raw)]
        encoding: Encoding,
        /// Bounded-lossy clamp (needs --encoding tiled): distances up to D metres keep their
        /// codes (steps of d_max/255), distances beyond D are stored as D and read as "D or
        /// more" (recorded in the blob). Far from walls the tiles become uniform and are
        /// stored once. Choose D several σ_hit from a wall, where the likelihood no longer
        /// changes (docs/blob-format.md gives the bound); 0.5 m keeps every score of the
        /// Intel demo (σ_hit 0.0588 m) bit for bit.
        #[arg(long = "clamp-m", value_name = "D")]
        clamp_m: Option<f32>,
        /// Another state of the same map (doors open or closed; same size, resolution and
        /// origin), repeatable. The blob then stores, per cell, the smallest distance over MAP
        /// and every variant: one transform over the union of their occupied cells (Thrun et
        /// al., Probabilistic Robotics, chapter 6, exercises). Build one blob per variant to
        /// tell which one explains a scan (`beamfield score` with each).
        #[arg(long = "variant", value_name = "MAP.yaml")]
        variants: Vec<PathBuf>,
        /// Refuse a map image with more cells than this, checked from the image header before
        /// decoding (the build needs about 10 bytes per cell at its peak).
        #[arg(long = "max-cells", default_value_t = crate::input::map::DEFAULT_MAX_CELLS)]
        max_cells: u64,
    },
    /// Rewrite a blob in another encoding (same header, same codes, so the same scores).
    Encode {
        /// The blob to read (either encoding).
        blob: PathBuf,
        /// Where to write the re-encoded blob.
        #[arg(short, long)]
        output: PathBuf,
        /// The encoding to write. A clamped blob (--clamp-m) can only be written tiled.
        #[arg(long, value_enum)]
        encoding: Encoding,
        /// Clamp distances beyond D metres to D (tiled only; see `field build --clamp-m`).
        /// A blob that already has a clamp keeps the smaller of the two.
        #[arg(long = "clamp-m", value_name = "D")]
        clamp_m: Option<f32>,
    },
    /// Score one scan of a log against each state of a map (doors open or closed) and say
    /// which explains it.
    ///
    /// Builds one distance field per --variant map (one exact transform each), scores the
    /// scan at the logged pose (or --pose) against each, prints the log-likelihoods and names
    /// the variant that beats every other by more than --margin nats. The likelihood field
    /// only looks at where beams end: a door changes the scores only if the scan's endpoints
    /// land on or near it (docs/blob-format.md, map variants).
    ScoreVariants(crate::field_variants::ScoreVariantsArgs),
    /// Describe a blob: grid, encoding, bytes and bytes per cell (and tiles for a tiled blob).
    Info {
        /// The blob.
        blob: PathBuf,
    },
    /// Look up distances: "x,y" lines on stdin, "x,y,distance_m" on stdout.
    ///
    /// Reads "x,y" lines (metres, map frame) on stdin and prints
    /// "x,y,distance_m" (or one JSON object per line with --json). Points off the map are
    /// charged the extra distance to the map's edge. Bad lines are reported on stderr with
    /// their line number and skipped; the exit status is then 1.
    Query {
        /// The blob.
        blob: PathBuf,
    },
    /// Draw the field as a PNG a person can read.
    ///
    /// North up, with a title, axes in metres (map frame), a scale bar and a key: occupied
    /// cells red, distance as grey from black (0 m) to white (d_max), with a darker contour
    /// every 0.25 m.
    Render {
        /// The blob.
        blob: PathBuf,
        /// Where to write the PNG.
        #[arg(short, long)]
        output: PathBuf,
    },
}

/// Anything that can go wrong in a `field` command.
#[derive(Debug)]
pub enum FieldCmdError {
    /// Loading the map.
    Map(MapError),
    /// A file could not be read or written.
    Io(PathBuf, std::io::Error),
    /// A field file that is not a regular file, or larger than
    /// [`crate::input::limits::MAX_FIELD_FILE_BYTES`].
    Read(crate::input::limits::ReadError),
    /// A `field query` input line longer than [`crate::input::limits::MAX_QUERY_LINE_BYTES`] (its
    /// 1-based number); reading stops there.
    QueryLineTooLong(usize),
    /// `field encode` of a blob with more cells than [`MAX_DECODED_CELLS`] (the file, width,
    /// height).
    TooManyCells(PathBuf, u32, u32),
    /// The blob is invalid, or could not be written.
    Blob(PathBuf, BlobError),
    /// The distance transform refused the grid.
    Edt(EdtError),
    /// `--max-dist` not finite or ≤ 0.
    BadMaxDist(f32),
    /// The map cannot be represented in a blob (size or f32 origin).
    Header(BlobError),
    /// Writing the PNG failed.
    Png(PathBuf, String),
    /// Some query lines were malformed (count).
    BadLines(usize),
    /// The free-space section could not be built (e.g. the map has no free cell).
    FreeSpace(FreeSpaceError),
    /// A `--variant` map's size, resolution or origin differs from the map's.
    VariantMismatch(PathBuf),
    /// `--clamp-m` not finite, or not between half a code step and `d_max` (the value and
    /// `d_max`).
    BadClamp(f32, f32),
    /// A clamp (`--clamp-m`, or a clamped input blob) with the raw encoding, which cannot
    /// record it.
    ClampNeedsTiled,
    /// `field score-variants` failed.
    ScoreVariants(Box<crate::field_variants::ScoreVariantsError>),
}

impl std::fmt::Display for FieldCmdError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Map(e) => write!(f, "{e}"),
            Self::Io(p, e) => write!(f, "{}: {e}", p.display()),
            Self::Read(e) => write!(f, "{e}"),
            Self::TooManyCells(p, w, h) => write!(
                f,
                "{}: a field of {w} x {h} = {} cells, more than {MAX_DECODED_CELLS}, the most a \
                 field is decoded to",
                p.display(),
                u64::from(*w) * u64::from(*h)
            ),
            Self::QueryLineTooLong(n) => write!(
                f,
                "standard input line {n}: longer than {} bytes (stopped reading)",
                crate::input::limits::MAX_QUERY_LINE_BYTES
            ),
            Self::Blob(p, e) => write!(f, "{}: {e}", p.display()),
            Self::Edt(e) => write!(f, "distance transform: {e}"),
            Self::BadMaxDist(d) => write!(f, "--max-dist {d}: must be finite and > 0"),
            Self::Header(e) => write!(f, "map cannot be stored as a blob: {e}"),
            Self::Png(p, e) => write!(f, "{}: {e}", p.display()),
            Self::BadLines(n) => write!(f, "{n} malformed input line(s)"),
            Self::FreeSpace(e) => write!(f, "free-space section: {e}"),
            Self::BadClamp(d, max) => write!(
                f,
                "--clamp-m {d}: must be finite, at least half a code step ({} m) and below \
                 d_max ({max} m)",
                max / 510.0
            ),
            Self::ScoreVariants(e) => write!(f, "score-variants: {e}"),
            Self::ClampNeedsTiled => f.write_str(
                "a clamped field can only be stored tiled (--encoding tiled): the raw encoding \
                 cannot record the clamp",
            ),
            Self::VariantMismatch(p) => write!(
                f,
                "{}: a variant must have the map's size, resolution and origin",
                p.display()
            ),
        }
    }
}

impl std::error::Error for FieldCmdError {}

/// The transform's input for `map`: 0 on occupied cells (the seeds), [`EDT_INFINITY`] on free
/// and unknown ones, row-major from the lowest y.
pub fn edt_seeds(map: &OccupancyMap) -> Vec<u32> {
    map.cells
        .iter()
        .map(|c| {
            if *c == Occupancy::Occupied {
                0
            } else {
                EDT_INFINITY
            }
        })
        .collect()
}

/// Exact squared distances (cell units) of a map's cells to the nearest occupied cell, row 0 =
/// lowest y; [`EDT_INFINITY`] everywhere when nothing is occupied.
///
/// # Errors
/// [`FieldCmdError::Edt`] when the map is larger than the transform accepts.
pub fn squared_distances(map: &OccupancyMap) -> Result<Vec<u32>, FieldCmdError> {
    let (w, h) = (map.width as usize, map.height as usize);
    let mut grid = edt_seeds(map);
    let n = edt_scratch_len(w, h);
    let (mut sites, mut bounds, mut heights) = (vec![0u32; n], vec![0i64; n], vec![0u32; n]);
    squared_edt(
        &mut grid,
        w,
        h,
        EdtScratch {
            sites: &mut sites,
            bounds: &mut bounds,
            heights: &mut heights,
        },
    )
    .map_err(FieldCmdError::Edt)?;
    Ok(grid)
}

/// The blob header for a map (resolution and origin rounded to f32).
pub fn header_for(map: &OccupancyMap, max_dist_m: f32) -> FieldHeader {
    FieldHeader {
        width: map.width,
        height: map.height,
        cell_size_m: map.resolution_m as f32,
        origin_x_m: map.origin_x_m as f32,
        origin_y_m: map.origin_y_m as f32,
        max_dist_m,
    }
}

/// Builds a blob for a loaded map.
///
/// # Errors
/// [`FieldCmdError::BadMaxDist`], [`FieldCmdError::Edt`], [`FieldCmdError::Header`].
pub fn build_blob(map: &OccupancyMap, max_dist_m: f32) -> Result<Vec<u8>, FieldCmdError> {
    if !(max_dist_m.is_finite() && max_dist_m > 0.0) {
        return Err(FieldCmdError::BadMaxDist(max_dist_m));
    }
    let header = header_for(map, max_dist_m);
    let len = header.required_len().map_err(FieldCmdError::Header)?;
    let sq = squared_distances(map)?;
    let mut out = vec![0u8; len];
    emit_blob_from_squared_cells(&header, &sq, &mut out).map_err(FieldCmdError::Header)?;
    Ok(out)
}

/// The union of `map` and its variants: a cell is occupied when it is occupied in any of them
/// (otherwise it keeps `map`'s state). Its distance field is, per cell, the minimum of the
/// maps' fields.
///
/// # Errors
/// [`FieldCmdError::VariantMismatch`] naming the first variant (by its path in `variants`)
/// whose geometry differs from `map`'s.
pub fn union_map(
    map: &OccupancyMap,
    variants: &[(PathBuf, OccupancyMap)],
) -> Result<OccupancyMap, FieldCmdError> {
    let mut out = map.clone();
    for (path, v) in variants {
        if (v.width, v.height) != (map.width, map.height)
            || v.resolution_m != map.resolution_m
            || v.origin_x_m != map.origin_x_m
            || v.origin_y_m != map.origin_y_m
        {
            return Err(FieldCmdError::VariantMismatch(path.clone()));
        }
        for (c, &vc) in out.cells.iter_mut().zip(&v.cells) {
            if vc == Occupancy::Occupied {
                *c = Occupancy::Occupied;
            }
        }
    }
    Ok(out)
}

/// Builds a blob for a loaded map in the given encoding.
///
/// # Errors
/// As [`build_blob`]; [`FieldCmdError::Header`] with [`BlobError::TooManyTiles`] when the map
/// has more distinct tiles than encoding 2 holds.
pub fn build_blob_encoded(
    map: &OccupancyMap,
    max_dist_m: f32,
    encoding: Encoding,
) -> Result<Vec<u8>, FieldCmdError> {
    let raw = build_blob(map, max_dist_m)?;
    match encoding {
        Encoding::Raw => Ok(raw),
        Encoding::Tiled => tile_blob(&raw).map_err(FieldCmdError::Header),
    }
}

/// The clamp code of clamp distance `clamp_m` for a blob with `header`.
///
/// # Errors
/// [`FieldCmdError::BadClamp`] unless the code is between 1 and 254 (`clamp_m` finite, at least
/// half a code step, below `d_max`).
pub fn clamp_code_for(header: &FieldHeader, clamp_m: f32) -> Result<u8, FieldCmdError> {
    let code = header.encode_distance_m(f64::from(clamp_m));
    if clamp_m.is_finite() && (1..255).contains(&code) {
        Ok(code)
    } else {
        Err(FieldCmdError::BadClamp(clamp_m, header.max_dist_m))
    }
}

/// Builds a tiled blob for a loaded map with distances beyond `clamp_m` stored as `clamp_m`
/// (`field build --encoding tiled --clamp-m`).
///
/// # Errors
/// As [`build_blob`]; [`FieldCmdError::BadClamp`]; [`FieldCmdError::Header`] with
/// [`BlobError::TooManyTiles`].
pub fn build_blob_clamped(
    map: &OccupancyMap,
    max_dist_m: f32,
    clamp_m: f32,
) -> Result<Vec<u8>, FieldCmdError> {
    let raw = build_blob(map, max_dist_m)?;
    clamp_code_for(&header_for(map, max_dist_m), clamp_m)?;
    tile_blob_clamped(&raw, Some(clamp_m)).map_err(FieldCmdError::Header)
}

/// Re-encodes a blob (either encoding) as a raw blob (encoding 1) with the same header and
/// codes.
///
/// # Errors
/// Any [`BlobError`] of the input; [`BlobError::BadClamp`] for a clamped tiled blob (the raw
/// encoding cannot record the clamp).
pub fn untile_blob(blob: &[u8]) -> Result<Vec<u8>, BlobError> {
    let view = parse_field_file(blob)?;
    if !decodable(&view) {
        return Err(BlobError::TooLarge);
    }
    if view.clamp_code().is_some() {
        return Err(BlobError::BadClamp);
    }
    let header = *view.header();
    let codes = codes_of(&view);
    let mut out = vec![0u8; header.required_len()?];
    beamfield::field::emit_blob(&header, &codes, &mut out)?;
    Ok(out)
}

/// Most cells `field encode` decodes a blob to: as many as a raw blob within
/// [`crate::input::limits::MAX_FIELD_FILE_BYTES`] holds (134,217,728). A tiled blob stores 16 cells in
/// 2 bytes of tile index, so a tiled file within the limit could announce 8 times more; decoding
/// and re-encoding costs about 3 bytes per cell.
pub const MAX_DECODED_CELLS: u64 = crate::input::limits::MAX_FIELD_FILE_BYTES;

/// `view` has at most [`MAX_DECODED_CELLS`] cells.
fn decodable(view: &FieldView<'_>) -> bool {
    u64::from(view.width()) * u64::from(view.height()) <= MAX_DECODED_CELLS
}

/// Every code of a view, row-major from the lowest y.
fn codes_of(view: &FieldView<'_>) -> Vec<u8> {
    if let Some(raw) = view.raw_codes() {
        return raw.to_vec();
    }
    let (w, h) = (view.width(), view.height());
    (0..h)
        .flat_map(|iy| (0..w).map(move |ix| (ix, iy)))
        .map(|(ix, iy)| view.code(ix, iy).unwrap_or(255))
        .collect()
}

/// Re-encodes a blob (either encoding) as a tiled blob (encoding 2) with the same header and
/// codes.
///
/// # Errors
/// Any [`BlobError`] of the input, [`BlobError::TooManyTiles`].
pub fn tile_blob(blob: &[u8]) -> Result<Vec<u8>, BlobError> {
    tile_blob_clamped(blob, None)
}

/// As [`tile_blob`], clamping distances beyond `clamp_m` metres (if given) to it; a clamp the
/// input already has is kept (the smaller of the two wins).
///
/// # Errors
/// As [`tile_blob`]; [`BlobError::BadClamp`] for a clamp distance that is not finite, below
/// half a code step, or at or above `d_max` (see [`clamp_code_for`]).
pub fn tile_blob_clamped(blob: &[u8], clamp_m: Option<f32>) -> Result<Vec<u8>, BlobError> {
    let view = parse_field_file(blob)?;
    if !decodable(&view) {
        return Err(BlobError::TooLarge);
    }
    let header = *view.header();
    let codes = codes_of(&view);
    let asked = match clamp_m {
        Some(d) => Some(clamp_code_for(&header, d).map_err(|_| BlobError::BadClamp)?),
        None => None,
    };
    let clamp = match (asked, view.clamp_code()) {
        (Some(a), Some(b)) => a.min(b),
        (Some(c), None) | (None, Some(c)) => c,
        (None, None) => 0,
    };
    let mut scratch = vec![0u32; tiled_scratch_len(&header)?];
    let mut out = vec![0u8; tiled_max_len(&header)?];
    let n = emit_blob_tiled_clamped(&header, &codes, clamp, &mut scratch, &mut out)?;
    out.truncate(n);
    Ok(out)
}

/// What `field info` reports about a blob.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlobInfo {
    /// The header.
    pub header: FieldHeader,
    /// Distance encoding (1 raw, 2 tiled).
    pub encoding: u8,
    /// Blob length, bytes (without a free-space section that follows it).
    pub bytes: usize,
    /// Length of the free-space section after the blob, bytes (0 without one).
    pub free_space_bytes: usize,
    /// Tiles in the pool (tiled blobs only).
    pub pool_tiles: Option<usize>,
    /// The clamp distance, metres (clamped tiled blobs only): distances at or beyond it are
    /// stored as it.
    pub clamp_m: Option<f32>,
}

impl BlobInfo {
    /// Parses `blob` and summarizes it.
    ///
    /// # Errors
    /// Any [`BlobError`].
    pub fn of(blob: &[u8]) -> Result<Self, BlobError> {
        let view = parse_field_file(blob)?;
        let (_, rest) = FieldView::parse_prefix(blob)?;
        Ok(Self {
            header: *view.header(),
            encoding: view.encoding(),
            bytes: blob.len() - rest.len(),
            free_space_bytes: rest.len(),
            pool_tiles: view.pool_tiles(),
            clamp_m: view.clamp_m(),
        })
    }

    /// Cells of the grid.
    pub fn cells(&self) -> u64 {
        u64::from(self.header.width) * u64::from(self.header.height)
    }

    /// Bytes per cell, header included.
    pub fn bytes_per_cell(&self) -> f64 {
        self.bytes as f64 / self.cells() as f64
    }

    /// The encoding's name as `--encoding` spells it.
    pub fn encoding_name(&self) -> &'static str {
        if self.encoding == ENCODING_TILED {
            "tiled"
        } else {
            "raw"
        }
    }
}

/// What `field query` did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct QueryReport {
    /// Lines answered.
    pub answered: usize,
    /// Malformed lines reported (not numbers, not UTF-8).
    pub bad: usize,
    /// The 1-based number of a line longer than [`crate::input::limits::MAX_QUERY_LINE_BYTES`], where
    /// reading stopped (the rest of such a line may never end: `/dev/zero`).
    pub too_long: Option<usize>,
}

/// Answers "x,y" lines from `input` on `out`; reports malformed lines (1-based line numbers,
/// the line quoted as an escaped prefix of at most [`crate::input::limits::QUOTE_CHARS`] characters)
/// on `err`. Blank lines and lines starting with `#` are ignored. A line longer than
/// [`crate::input::limits::MAX_QUERY_LINE_BYTES`] stops the reading ([`QueryReport::too_long`]):
/// nothing of it past the limit is read or kept.
///
/// # Errors
/// I/O errors of the streams.
pub fn run_query(
    view: &FieldView<'_>,
    mut input: impl BufRead,
    mut out: impl Write,
    mut err: impl Write,
    json: bool,
) -> std::io::Result<QueryReport> {
    use crate::input::limits::{escaped_prefix, read_bounded_line, BoundedLine, QUOTE_CHARS};
    let mut report = QueryReport::default();
    let mut buf = Vec::new();
    let mut number = 0usize;
    while let Some(line) = read_bounded_line(
        &mut input,
        &mut buf,
        crate::input::limits::MAX_QUERY_LINE_BYTES,
    )? {
        number += 1;
        let t = match line {
            BoundedLine::Text(t) => t.trim(),
            BoundedLine::TooLong => {
                report.too_long = Some(number);
                break;
            }
            BoundedLine::NotUtf8 => {
                report.bad += 1;
                if json {
                    writeln!(
                        err,
                        "{}",
                        serde_json::json!({ "line": number, "error": "not UTF-8 text" })
                    )?;
                } else {
                    writeln!(err, "line {number}: not UTF-8 text")?;
                }
                continue;
            }
        };
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        match parse_xy(t) {
            Ok((x, y)) => {
                let d = view.distance_m(x, y);
                if json {
                    writeln!(
                        out,
                        "{}",
                        serde_json::json!({ "x": x, "y": y, "distance_m": d })
                    )?;
                } else {
                    writeln!(out, "{x},{y},{d}")?;
                }
                report.answered += 1;
            }
            Err(why) => {
                report.bad += 1;
                let quoted = escaped_prefix(t, QUOTE_CHARS);
                if json {
                    writeln!(
                        err,
                        "{}",
                        serde_json::json!({ "line": number, "error": why, "text": quoted })
                    )?;
                } else {
                    writeln!(err, "line {number}: {why}: \"{quoted}\"")?;
                }
            }
        }
    }
    Ok(report)
}

fn parse_xy(t: &str) -> Result<(f32, f32), &'static str> {
    let mut it = t.split(',');
    let (Some(a), Some(b), None) = (it.next(), it.next(), it.next()) else {
        return Err("expected two comma-separated numbers x,y");
    };
    let x: f32 = a.trim().parse().map_err(|_| "x is not a number")?;
    let y: f32 = b.trim().parse().map_err(|_| "y is not a number")?;
    if !(x.is_finite() && y.is_finite()) {
        return Err("x and y must be finite");
    }
    Ok((x, y))
}

/// The free-space section of `map` (docs/free-space-format.md): its free cells (map_server's
/// `p < free_thresh`), on the grid of the blob [`build_blob`] writes for it.
///
/// # Errors
/// [`FieldCmdError::Header`] when the map cannot be a blob, [`FieldCmdError::FreeSpace`]
/// when it has no free cell.
pub fn build_free_space(map: &OccupancyMap) -> Result<Vec<u8>, FieldCmdError> {
    let h = header_for(map, DEFAULT_MAX_DIST_M);
    h.validate().map_err(FieldCmdError::Header)?;
    let grid = FreeSpaceGrid {
        width: h.width,
        height: h.height,
        cell_size_m: h.cell_size_m,
        origin_x_m: h.origin_x_m,
        origin_y_m: h.origin_y_m,
    };
    let free: Vec<bool> = map.cells.iter().map(|c| *c == Occupancy::Free).collect();
    let n = free_space_len(&grid, &free).map_err(FieldCmdError::FreeSpace)?;
    let mut out = vec![0u8; n];
    emit_free_space(&grid, &free, &mut out).map_err(FieldCmdError::FreeSpace)?;
    Ok(out)
}

/// Parses a field file as the tool writes it: a blob, optionally followed by its free-space
/// section (`field build --free-space`, docs/free-space-format.md). Any other trailing bytes are
/// rejected as [`FieldView::parse`] rejects them.
///
/// # Errors
/// The [`BlobError`] of the blob, or [`BlobError::TrailingBytes`] when what follows the blob is
/// not a free-space section.
pub fn parse_field_file(bytes: &[u8]) -> Result<FieldView<'_>, BlobError> {
    let (view, rest) = FieldView::parse_prefix(bytes)?;
    if rest.is_empty() || beamfield::field::FreeSpace::parse(rest).is_ok() {
        Ok(view)
    } else {
        FieldView::parse(bytes)
    }
}

/// Reads a field file (blob and optional free-space section): a regular file of at most
/// [`crate::input::limits::MAX_FIELD_FILE_BYTES`].
///
/// # Errors
/// [`FieldCmdError::Read`].
pub fn read_field_file(path: &Path) -> Result<Vec<u8>, FieldCmdError> {
    crate::input::limits::read_regular_file(
        path,
        crate::input::limits::MAX_FIELD_FILE_BYTES,
        "field file",
    )
    .map_err(FieldCmdError::Read)
}

/// Runs a `field` subcommand; prints a summary (JSON with `json`).
///
/// # Errors
/// [`FieldCmdError`], with the file concerned.
pub fn run(args: FieldArgs, json: bool) -> Result<(), FieldCmdError> {
    match args.command {
        FieldCommand::Build {
            map,
            output,
            max_dist,
            free_space,
            encoding,
            clamp_m,
            variants,
            max_cells,
        } => {
            if clamp_m.is_some() && encoding != Encoding::Tiled {
                return Err(FieldCmdError::ClampNeedsTiled);
            }
            let t0 = Instant::now();
            let mut m = load_map_limited(&map, max_cells).map_err(FieldCmdError::Map)?;
            // One variant at a time: memory does not grow with the number of variants.
            for p in &variants {
                let v = load_map_limited(p, max_cells).map_err(FieldCmdError::Map)?;
                m = union_map(&m, &[(p.clone(), v)])?;
            }
            let t1 = Instant::now();
            let mut blob = match clamp_m {
                Some(d) => build_blob_clamped(&m, max_dist, d)?,
                None => build_blob_encoded(&m, max_dist, encoding)?,
            };
            let blob_len = blob.len();
            if free_space {
                blob.extend(build_free_space(&m)?);
            }
            let t2 = Instant::now();
            std::fs::write(&output, &blob).map_err(|e| FieldCmdError::Io(output.clone(), e))?;
            let cells = u64::from(m.width) * u64::from(m.height);
            if json {
                println!(
                    "{}",
                    serde_json::json!({
                        "output": output.display().to_string(),
                        "width": m.width, "height": m.height,
                        "resolution_m": m.resolution_m,
                        "origin_m": [m.origin_x_m, m.origin_y_m],
                        "occupied_cells": m.occupied_count(),
                        "variants": variants.len(),
                        "max_dist_m": max_dist,
                        "clamp_m": clamp_m,
                        "encoding": BlobInfo::of(&blob[..blob_len]).map(|i| i.encoding_name()).unwrap_or("?"),
                        "bytes": blob.len(),
                        "free_space_bytes": blob.len() - blob_len,
                        "bytes_per_cell": blob_len as f64 / cells as f64,
                        "load_ms": (t1 - t0).as_secs_f64() * 1e3,
                        "build_ms": (t2 - t1).as_secs_f64() * 1e3,
                    })
                );
            } else {
                println!(
                    "{}: {} × {} cells of {} m, origin ({}, {}), {} occupied, d_max {} m \
                     (step {:.4} m){}; {} encoding, {} bytes ({:.4} bytes/cell){}; load {:.1} ms, \
                     transform+encode {:.1} ms",
                    output.display(),
                    m.width,
                    m.height,
                    m.resolution_m,
                    m.origin_x_m,
                    m.origin_y_m,
                    m.occupied_count(),
                    max_dist,
                    max_dist / 255.0,
                    clamp_m
                        .map(|d| format!(", clamped at {d} m"))
                        .unwrap_or_default(),
                    BlobInfo::of(&blob[..blob_len])
                        .map(|i| i.encoding_name())
                        .unwrap_or("?"),
                    blob_len,
                    blob_len as f64 / cells as f64,
                    if free_space {
                        format!(" + {} bytes of free space", blob.len() - blob_len)
                    } else {
                        String::new()
                    },
                    (t1 - t0).as_secs_f64() * 1e3,
                    (t2 - t1).as_secs_f64() * 1e3,
                );
            }
            Ok(())
        }
        FieldCommand::Encode {
            blob,
            output,
            encoding,
            clamp_m,
        } => {
            let bytes = read_field_file(&blob)?;
            let view =
                parse_field_file(&bytes).map_err(|e| FieldCmdError::Blob(blob.clone(), e))?;
            if !decodable(&view) {
                return Err(FieldCmdError::TooManyCells(
                    blob,
                    view.width(),
                    view.height(),
                ));
            }
            if encoding == Encoding::Raw && (clamp_m.is_some() || view.clamp_code().is_some()) {
                return Err(FieldCmdError::ClampNeedsTiled);
            }
            if let Some(d) = clamp_m {
                clamp_code_for(view.header(), d)?;
            }
            let mut out = match encoding {
                Encoding::Raw => untile_blob(&bytes),
                Encoding::Tiled => tile_blob_clamped(&bytes, clamp_m),
            }
            .map_err(|e| FieldCmdError::Blob(blob.clone(), e))?;
            // A free-space section after the blob is carried over unchanged.
            let (_, rest) = FieldView::parse_prefix(&bytes)
                .map_err(|e| FieldCmdError::Blob(blob.clone(), e))?;
            out.extend_from_slice(rest);
            std::fs::write(&output, &out).map_err(|e| FieldCmdError::Io(output.clone(), e))?;
            let info = BlobInfo::of(&out).map_err(|e| FieldCmdError::Blob(output.clone(), e))?;
            if json {
                println!(
                    "{}",
                    serde_json::json!({
                        "input": blob.display().to_string(),
                        "output": output.display().to_string(),
                        "input_bytes": bytes.len(),
                        "encoding": info.encoding_name(),
                        "bytes": info.bytes,
                        "bytes_per_cell": info.bytes_per_cell(),
                    })
                );
            } else {
                println!(
                    "{}: {} encoding, {} bytes ({:.4} bytes/cell; {} was {} bytes)",
                    output.display(),
                    info.encoding_name(),
                    info.bytes,
                    info.bytes_per_cell(),
                    blob.display(),
                    bytes.len()
                );
            }
            Ok(())
        }
        FieldCommand::ScoreVariants(a) => {
            let out = crate::field_variants::run_score_variants(&a, json)
                .map_err(|e| FieldCmdError::ScoreVariants(Box::new(e)))?;
            println!("{out}");
            Ok(())
        }
        FieldCommand::Info { blob } => {
            let bytes = read_field_file(&blob)?;
            let info = BlobInfo::of(&bytes).map_err(|e| FieldCmdError::Blob(blob.clone(), e))?;
            let h = info.header;
            if json {
                println!(
                    "{}",
                    serde_json::json!({
                        "blob": blob.display().to_string(),
                        "width": h.width, "height": h.height,
                        "cell_size_m": h.cell_size_m,
                        "origin_m": [h.origin_x_m, h.origin_y_m],
                        "max_dist_m": h.max_dist_m,
                        "clamp_m": info.clamp_m,
                        "encoding": info.encoding_name(),
                        "bytes": info.bytes,
                        "free_space_bytes": info.free_space_bytes,
                        "cells": info.cells(),
                        "bytes_per_cell": info.bytes_per_cell(),
                        "pool_tiles": info.pool_tiles,
                    })
                );
            } else {
                let tiles = info
                    .pool_tiles
                    .map(|p| format!(", {p} distinct tiles"))
                    .unwrap_or_default()
                    + &info
                        .clamp_m
                        .map(|d| {
                            format!(", distances clamped at {d} m (stored as {d} m when farther)")
                        })
                        .unwrap_or_default();
                let free = if info.free_space_bytes > 0 {
                    format!(
                        "; then a free-space section of {} bytes",
                        info.free_space_bytes
                    )
                } else {
                    String::new()
                };
                println!(
                    "{}: {} × {} cells of {} m, origin ({}, {}), d_max {} m; {} encoding{}; \
                     {} bytes, {:.4} bytes/cell{}",
                    blob.display(),
                    h.width,
                    h.height,
                    h.cell_size_m,
                    h.origin_x_m,
                    h.origin_y_m,
                    h.max_dist_m,
                    info.encoding_name(),
                    tiles,
                    info.bytes,
                    info.bytes_per_cell(),
                    free,
                );
            }
            Ok(())
        }
        FieldCommand::Query { blob } => {
            let bytes = read_field_file(&blob)?;
            let view = parse_field_file(&bytes).map_err(|e| FieldCmdError::Blob(blob, e))?;
            let stdin = std::io::stdin();
            let report = run_query(
                &view,
                stdin.lock(),
                std::io::stdout().lock(),
                std::io::stderr().lock(),
                json,
            )
            .map_err(|e| FieldCmdError::Io(PathBuf::from("<stdio>"), e))?;
            if let Some(n) = report.too_long {
                Err(FieldCmdError::QueryLineTooLong(n))
            } else if report.bad > 0 {
                Err(FieldCmdError::BadLines(report.bad))
            } else {
                Ok(())
            }
        }
        FieldCommand::Render { blob, output } => {
            let bytes = read_field_file(&blob)?;
            let view =
                parse_field_file(&bytes).map_err(|e| FieldCmdError::Blob(blob.clone(), e))?;
            let name = blob.file_name().map_or_else(
                || blob.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            let title = format!("distance field of {name}");
            let fig = crate::draw::field_figure::draw_field(&output, &view, &title)
                .map_err(|e| FieldCmdError::Png(output.clone(), e.to_string()))?;
            if json {
                println!(
                    "{}",
                    serde_json::json!({ "output": output.display().to_string(),
                        "width_px": fig.width_px, "height_px": fig.height_px,
                        "px_per_cell": fig.px_per_cell, "scale_bar_m": fig.scale_bar_m,
                        "width_cells": view.width(), "height_cells": view.height() })
                );
            } else {
                println!(
                    "{}: {} × {} px, {} px per cell, scale bar {} m",
                    output.display(),
                    fig.width_px,
                    fig.height_px,
                    fig.px_per_cell,
                    fig.scale_bar_m
                );
            }
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xy_parsing_table() {
        let ok = [("1,2", (1.0, 2.0)), (" -3.5 , 4e-1 ", (-3.5, 0.4))];
        for (s, want) in ok {
            assert_eq!(parse_xy(s), Ok(want), "{s}");
        }
        for bad in ["1", "1,2,3", "a,2", "1,", "nan,1", "inf,0"] {
            assert!(parse_xy(bad).is_err(), "{bad}");
        }
    }
}
