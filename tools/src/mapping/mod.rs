//! Occupancy-grid mapping with known poses (Thrun, Burgard & Fox, Table 9.1, "occupancy grid
//! mapping"), from a CARMEN log whose poses are already corrected, written out as a ROS
//! map_server map.
//!
//! # The update, per scan
//! For every beam, with the FLASER (laser) pose as the sensor origin and beam `i` at
//! `−90° + i·s` (`s` = [`crate::input::carmen::carmen_beam_step_rad`]: 180°/n, or
//! 180°/(n − 1) for an odd n):
//! - a reading `0 ≤ z < max_range` is a **hit**: the cell holding its end point gets occupied
//!   evidence, and every cell the segment from the sensor to the end point crosses before it
//!   (exact grid traversal, [`traverse`]) gets free evidence;
//! - a max-range reading (`z ≥ max_range`, "no return") gives free evidence along the beam up to
//!   [`MappingOptions::max_range_free_m`] (default 8 m) and no occupied evidence. No return means
//!   nothing reflected within the sensor's reach, so the first metres are almost certainly free;
//!   but glass, black or very oblique surfaces also return nothing, so the claim is capped rather
//!   than carried to the full 81.83 m. `None` gives max-range readings no weight at all;
//! - NaN or negative readings are skipped and counted.
//!
//! Within one scan, each cell is updated at most once, and a hit wins over a pass-through: a
//! cell holding an end point of this scan gets no free evidence from the scan's other beams
//! (neighbouring beams graze the same wall at shallow incidence; without this rule walls seen
//! at a shallow angle are eaten away by their own scan).
//!
//! # Log-odds
//! `L ← clamp(L + l, l_min, l_max)` with `l_hit = ln(0.7/0.3) ≈ +0.847`, `l_miss = ln(0.4/0.6)
//! ≈ −0.405`, `l_min = −2.0`, `l_max = +3.5` (probabilities 0.12 … 0.97), prior `L = 0`
//! (p = 0.5). The clamps keep the map able to change its mind after a few contrary scans.
//!
//! # Trinary output
//! With map_server's thresholds: `p > 0.65` occupied, `p < 0.196` free, else unknown, where
//! `p = 1 − 1/(1 + e^L)`. A cell never observed stays at p = 0.5: unknown. So one hit makes a
//! cell occupied; a cell needs four net misses to become free.

mod error;
pub mod grid;
pub mod raycast;
pub mod writer;

use error::f64_spacing;
pub use error::{MappingError, MAX_CELLS, MAX_COORDINATE_ULP_CELLS};

pub use grid::{Cell, GridError, GridGeometry, OccupancyGrid, OccupiedCells};
pub use raycast::{ray_cast_grid, traverse};
pub use writer::{pgm_bytes, write_map_server, yaml_text, MapIoError, MapServerMap};

use crate::input::carmen::{CarmenLog, Extent, LaserScan};
use beamfield::Reading;
use std::ops::ControlFlow;

/// map_server's default `occupied_thresh`.
pub const OCCUPIED_THRESH: f64 = 0.65;
/// map_server's default `free_thresh`.
pub const FREE_THRESH: f64 = 0.196;

/// How to build a map from a log.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MappingOptions {
    /// Cell side, metres (default 0.05).
    pub resolution_m: f64,
    /// Margin added around the data's extent, metres (default 1.0).
    pub margin_m: f64,
    /// Log-odds added to a cell holding an end point (default `ln(0.7/0.3)`).
    pub hit_log_odds: f32,
    /// Log-odds added to a cell a beam passes through (default `ln(0.4/0.6)`, negative).
    pub miss_log_odds: f32,
    /// Lower clamp of the log-odds (default −2.0).
    pub min_log_odds: f32,
    /// Upper clamp of the log-odds (default +3.5).
    pub max_log_odds: f32,
    /// How far a max-range reading clears space, metres; `None`: not at all (default 8.0).
    pub max_range_free_m: Option<f64>,
    /// Readings at or above this are max-range readings, metres (normally the log's value).
    pub max_range_m: f32,
    /// Largest grid built, cells (default [`crate::input::map::DEFAULT_MAX_CELLS`], 2²⁴, what
    /// `field build` takes by default; at most [`MAX_CELLS`]). The builder needs about 13 bytes
    /// per cell, and two poses 300 m apart already span 36 M cells at 5 cm.
    pub max_cells: u64,
}

impl MappingOptions {
    /// The defaults above, with the log's max-range value.
    pub fn new(max_range_m: f32) -> Self {
        Self {
            resolution_m: 0.05,
            margin_m: 1.0,
            hit_log_odds: (0.7f32 / 0.3).ln(),
            miss_log_odds: (0.4f32 / 0.6).ln(),
            min_log_odds: -2.0,
            max_log_odds: 3.5,
            max_range_free_m: Some(8.0),
            max_range_m,
            max_cells: crate::input::map::DEFAULT_MAX_CELLS,
        }
    }

    fn validate(&self) -> Result<(), MappingError> {
        let ok = self.resolution_m.is_finite()
            && self.resolution_m > 0.0
            && self.margin_m.is_finite()
            && self.margin_m >= 0.0
            && self.hit_log_odds.is_finite()
            && self.hit_log_odds > 0.0
            && self.miss_log_odds.is_finite()
            && self.miss_log_odds < 0.0
            && self.min_log_odds.is_finite()
            && self.max_log_odds.is_finite()
            && self.min_log_odds < 0.0
            && self.max_log_odds > 0.0
            && self.max_range_m.is_finite()
            && self.max_range_m > 0.0
            && (1..=MAX_CELLS).contains(&self.max_cells)
            && self
                .max_range_free_m
                .is_none_or(|m| m.is_finite() && m >= 0.0);
        if ok {
            Ok(())
        } else {
            Err(MappingError::BadOptions)
        }
    }
}

/// Counters of what the builder did with the readings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct MappingStats {
    /// Scans integrated.
    pub scans: usize,
    /// Readings that gave a hit.
    pub hits: usize,
    /// Max-range readings (free space up to the cap, or nothing).
    pub max_range: usize,
    /// NaN or negative readings, skipped.
    pub invalid: usize,
}

/// A log-odds occupancy grid (row 0 at the bottom).
#[derive(Clone, Debug, PartialEq)]
pub struct LogOddsGrid {
    geometry: GridGeometry,
    log_odds: Vec<f32>,
}

impl LogOddsGrid {
    /// The geometry.
    pub fn geometry(&self) -> GridGeometry {
        self.geometry
    }

    /// The log-odds, row-major, row 0 at the bottom.
    pub fn log_odds(&self) -> &[f32] {
        &self.log_odds
    }

    /// Occupancy probability of a log-odds value: `1 − 1/(1 + e^L)`.
    pub fn probability(log_odds: f32) -> f64 {
        1.0 - 1.0 / (1.0 + f64::from(log_odds).exp())
    }

    /// The trinary grid under map_server's thresholds (probabilities).
    pub fn to_occupancy(&self, occupied_thresh: f64, free_thresh: f64) -> OccupancyGrid {
        let cells = self
            .log_odds
            .iter()
            .map(|&l| {
                let p = Self::probability(l);
                if p > occupied_thresh {
                    Cell::Occupied
                } else if p < free_thresh {
                    Cell::Free
                } else {
                    Cell::Unknown
                }
            })
            .collect();
        // The geometry came from `build_from_log`, validated; the count matches by construction.
        OccupancyGrid::from_parts(self.geometry, cells)
    }
}

/// Removes the rounding noise of `k·res` (−20.900000000000002 → −20.9) so that the YAML reads
/// well; moves the lattice by less than 1 nm.
fn snap(v: f64) -> f64 {
    let s = (v * 1e6).round() / 1e6;
    if (s - v).abs() < 1e-9 {
        s
    } else {
        v
    }
}

/// A beam's segment for the update: sensor origin, end point (world metres), and whether the
/// end point is a hit.
type Segment = ((f64, f64), (f64, f64), bool);

/// The segment of beam `i`, or `None` for a skipped reading.
fn beam_segment(scan: &LaserScan, i: usize, options: &MappingOptions) -> Option<Segment> {
    let z = *scan.ranges_m.get(i)?;
    let n = scan.ranges_m.len();
    let p = scan.pose_f64;
    let a = p.theta_rad + crate::input::carmen::carmen_bearing_rad(i, n);
    let (s, c) = a.sin_cos();
    let start = (p.x_m, p.y_m);
    let (length, hit) = match Reading::classify(z, options.max_range_m) {
        Reading::Range(z) => (f64::from(z), true),
        Reading::MaxRange => (options.max_range_free_m?, false),
        Reading::Invalid => return None,
    };
    Some((start, (start.0 + length * c, start.1 + length * s), hit))
}

/// Builds a log-odds grid from a log with known poses. `progress(done, total)` is called every
/// few scans (for a progress indication).
///
/// # Errors
/// [`MappingError::BadOptions`], [`MappingError::NoData`] when no scan has a valid reading,
/// [`MappingError::TooLarge`].
pub fn build_from_log(
    log: &CarmenLog,
    options: &MappingOptions,
    mut progress: impl FnMut(usize, usize),
) -> Result<(LogOddsGrid, MappingStats), MappingError> {
    options.validate()?;
    // Extent: every pose, every end point and every capped max-range ray end.
    let mut extent = Extent::default();
    for scan in &log.scans {
        extent.add(scan.pose_f64.x_m, scan.pose_f64.y_m);
        for i in 0..scan.ranges_m.len() {
            if let Some((_, end, _)) = beam_segment(scan, i, options) {
                extent.add(end.0, end.1);
            }
        }
    }
    let b = extent.finish().ok_or(MappingError::NoData)?;
    let res = options.resolution_m;
    // Origin on a multiple of the resolution, so that maps of one log at one resolution share
    // a lattice whatever the margin.
    let origin_x_m = snap(((b.x_min - options.margin_m) / res).floor() * res);
    let origin_y_m = snap(((b.y_min - options.margin_m) / res).floor() * res);
    let width = ((b.x_max + options.margin_m - origin_x_m) / res)
        .ceil()
        .max(1.0) as u64;
    let height = ((b.y_max + options.margin_m - origin_y_m) / res)
        .ceil()
        .max(1.0) as u64;
    if width.saturating_mul(height) > options.max_cells {
        return Err(MappingError::TooLarge {
            width,
            height,
            max_cells: options.max_cells,
        });
    }
    let magnitude_m = [
        b.x_min - options.margin_m,
        b.x_max + options.margin_m,
        b.y_min - options.margin_m,
        b.y_max + options.margin_m,
        origin_x_m,
        origin_y_m,
    ]
    .iter()
    .fold(0.0f64, |m, v| m.max(v.abs()));
    let spacing_m = f64_spacing(magnitude_m);
    if spacing_m > res * MAX_COORDINATE_ULP_CELLS {
        return Err(MappingError::Imprecise {
            magnitude_m,
            spacing_m,
            resolution_m: res,
        });
    }
    let geometry = GridGeometry {
        width: width as usize,
        height: height as usize,
        resolution_m: res,
        origin_x_m,
        origin_y_m,
    };
    let cells = geometry.cells();
    let mut log_odds = vec![0.0f32; cells];
    // Per-scan stamps (scan index + 1): hit this scan / already updated this scan.
    let mut hit_stamp = vec![0u32; cells];
    let mut seen_stamp = vec![0u32; cells];
    let mut hits_this_scan: Vec<usize> = Vec::new();
    let mut stats = MappingStats::default();
    let total = log.scans.len();
    let clamp = |l: f32| l.clamp(options.min_log_odds, options.max_log_odds);
    for (k, scan) in log.scans.iter().enumerate() {
        let stamp = (k as u32).wrapping_add(1);
        hits_this_scan.clear();
        // Hits first, so that free-space rays of this scan leave them alone.
        for i in 0..scan.ranges_m.len() {
            match beam_segment(scan, i, options) {
                Some((_, end, true)) => {
                    stats.hits += 1;
                    if let Some(idx) = geometry
                        .cell_of(end.0, end.1)
                        .and_then(|(c, r)| geometry.index(c, r))
                    {
                        if let Some(h) = hit_stamp.get_mut(idx) {
                            if *h != stamp {
                                *h = stamp;
                                hits_this_scan.push(idx);
                            }
                        }
                    }
                }
                Some((_, _, false)) => stats.max_range += 1,
                None => {
                    let valid = scan.ranges_m.get(i).is_some_and(|&z| {
                        matches!(Reading::classify(z, options.max_range_m), Reading::MaxRange)
                    });
                    if valid {
                        // A max-range reading with no free-space claim.
                        stats.max_range += 1;
                    } else {
                        stats.invalid += 1;
                    }
                }
            }
        }
        for i in 0..scan.ranges_m.len() {
            let Some((start, end, _)) = beam_segment(scan, i, options) else {
                continue;
            };
            traverse(&geometry, start.0, start.1, end.0, end.1, |c, r, _| {
                let Some(idx) = geometry.index(c, r) else {
                    return ControlFlow::Continue(());
                };
                let is_hit = hit_stamp.get(idx) == Some(&stamp);
                if let (false, Some(seen), Some(l)) =
                    (is_hit, seen_stamp.get_mut(idx), log_odds.get_mut(idx))
                {
                    if *seen != stamp {
                        *seen = stamp;
                        *l = clamp(*l + options.miss_log_odds);
                    }
                }
                ControlFlow::Continue(())
            });
        }
        for &idx in &hits_this_scan {
            if let Some(l) = log_odds.get_mut(idx) {
                *l = clamp(*l + options.hit_log_odds);
            }
        }
        stats.scans += 1;
        if (k + 1) % 50 == 0 || k + 1 == total {
            progress(k + 1, total);
        }
    }
    Ok((LogOddsGrid { geometry, log_odds }, stats))
}

/// For one scan: how many valid (non-max-range) end points fall on the grid, and how many of
/// those lie in an occupied cell or next to one (8-neighbourhood).
pub fn endpoint_agreement(
    grid: &OccupancyGrid,
    scan: &LaserScan,
    max_range_m: f32,
) -> (usize, usize) {
    let g = grid.geometry();
    let (mut on_grid, mut near) = (0, 0);
    for (i, &z) in scan.ranges_m.iter().enumerate() {
        if !matches!(Reading::classify(z, max_range_m), Reading::Range(_)) {
            continue;
        }
        let Some((x, y)) = scan.endpoint(i) else {
            continue;
        };
        if let Some((c, r)) = g.cell_of(x, y) {
            on_grid += 1;
            if grid.occupied_within_one_cell(c, r) {
                near += 1;
            }
        }
    }
    (on_grid, near)
}

#[cfg(test)]
mod tests;
