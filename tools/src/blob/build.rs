//! Building a blob from a map: the exact Euclidean distance transform of its occupied cells, the
//! distances coded once ([`FieldCodes`]), and the blob written raw or tiled from those codes;
//! the union of map variants; the free-space section.

use super::encode::{clamp_code_for, raw_from_codes, tiled_from_codes};
use super::{Encoding, FieldError};
use crate::input::map::{Occupancy, OccupancyMap};
use beamfield::field::{
    edt_scratch_len, emit_free_space, free_space_len, squared_edt, EdtScratch, FieldHeader,
    FreeSpaceGrid, DEFAULT_MAX_DIST_M, EDT_INFINITY,
};
use std::path::PathBuf;

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
/// [`FieldError::Edt`] when the map is larger than the transform accepts.
pub fn squared_distances(map: &OccupancyMap) -> Result<Vec<u32>, FieldError> {
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
    .map_err(FieldError::Edt)?;
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

/// A map's distance field as codes: the blob header and one code per cell (steps of
/// d_max/255, 255 at and beyond d_max), row-major from the lowest y. Computed once; every
/// encoding is written from it.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldCodes {
    /// The header of every blob written from these codes.
    pub header: FieldHeader,
    /// One code per cell.
    pub codes: Vec<u8>,
}

impl FieldCodes {
    /// Transforms `map` and codes its distances with clamp distance `max_dist_m`.
    ///
    /// # Errors
    /// [`FieldError::BadMaxDist`], [`FieldError::Header`] (the map cannot be a blob),
    /// [`FieldError::Edt`].
    pub fn of_map(map: &OccupancyMap, max_dist_m: f32) -> Result<Self, FieldError> {
        if !(max_dist_m.is_finite() && max_dist_m > 0.0) {
            return Err(FieldError::BadMaxDist(max_dist_m));
        }
        let header = header_for(map, max_dist_m);
        header.required_len().map_err(FieldError::Header)?;
        let codes = squared_distances(map)?
            .into_iter()
            .map(|s| header.encode_squared_cells(s))
            .collect();
        Ok(Self { header, codes })
    }

    /// The codes as a blob in `encoding`, tiled ones clamped at `clamp_m` metres if given.
    ///
    /// # Errors
    /// [`FieldError::ClampNeedsTiled`] for a clamp with [`Encoding::Raw`];
    /// [`FieldError::BadClamp`]; [`FieldError::Header`] (e.g. [`BlobError::TooManyTiles`]).
    ///
    /// [`BlobError::TooManyTiles`]: beamfield::field::BlobError::TooManyTiles
    pub fn blob(&self, encoding: Encoding, clamp_m: Option<f32>) -> Result<Vec<u8>, FieldError> {
        match (encoding, clamp_m) {
            (Encoding::Raw, Some(_)) => Err(FieldError::ClampNeedsTiled),
            (Encoding::Raw, None) => {
                raw_from_codes(&self.header, &self.codes).map_err(FieldError::Header)
            }
            (Encoding::Tiled, clamp) => {
                let code = match clamp {
                    Some(d) => clamp_code_for(&self.header, d)?,
                    None => 0,
                };
                tiled_from_codes(&self.header, &self.codes, code).map_err(FieldError::Header)
            }
        }
    }
}

/// Builds a raw blob for a loaded map.
///
/// # Errors
/// As [`FieldCodes::of_map`].
pub fn build_blob(map: &OccupancyMap, max_dist_m: f32) -> Result<Vec<u8>, FieldError> {
    FieldCodes::of_map(map, max_dist_m)?.blob(Encoding::Raw, None)
}

/// Builds a blob for a loaded map in the given encoding.
///
/// # Errors
/// As [`build_blob`]; [`FieldError::Header`] with
/// [`BlobError::TooManyTiles`](beamfield::field::BlobError::TooManyTiles) when the map has more
/// distinct tiles than encoding 2 holds.
pub fn build_blob_encoded(
    map: &OccupancyMap,
    max_dist_m: f32,
    encoding: Encoding,
) -> Result<Vec<u8>, FieldError> {
    FieldCodes::of_map(map, max_dist_m)?.blob(encoding, None)
}

/// Builds a tiled blob for a loaded map with distances beyond `clamp_m` stored as `clamp_m`
/// (`field build --encoding tiled --clamp-m`).
///
/// # Errors
/// As [`build_blob_encoded`]; [`FieldError::BadClamp`].
pub fn build_blob_clamped(
    map: &OccupancyMap,
    max_dist_m: f32,
    clamp_m: f32,
) -> Result<Vec<u8>, FieldError> {
    FieldCodes::of_map(map, max_dist_m)?.blob(Encoding::Tiled, Some(clamp_m))
}

/// The union of `map` and its variants: a cell is occupied when it is occupied in any of them
/// (otherwise it keeps `map`'s state). Its distance field is, per cell, the minimum of the
/// maps' fields.
///
/// # Errors
/// [`FieldError::VariantMismatch`] naming the first variant (by its path in `variants`)
/// whose geometry differs from `map`'s.
pub fn union_map(
    map: &OccupancyMap,
    variants: &[(PathBuf, OccupancyMap)],
) -> Result<OccupancyMap, FieldError> {
    let mut out = map.clone();
    for (path, v) in variants {
        if !same_geometry(map, v) {
            return Err(FieldError::VariantMismatch(path.clone()));
        }
        for (c, &vc) in out.cells.iter_mut().zip(&v.cells) {
            if vc == Occupancy::Occupied {
                *c = Occupancy::Occupied;
            }
        }
    }
    Ok(out)
}

/// `a` and `b` have the same size, resolution and origin (variants of one map).
pub fn same_geometry(a: &OccupancyMap, b: &OccupancyMap) -> bool {
    (a.width, a.height) == (b.width, b.height)
        && a.resolution_m == b.resolution_m
        && a.origin_x_m == b.origin_x_m
        && a.origin_y_m == b.origin_y_m
}

/// The free-space section of `map` (docs/free-space-format.md): its free cells (map_server's
/// `p < free_thresh`), on the grid of the blob [`build_blob`] writes for it.
///
/// # Errors
/// [`FieldError::Header`] when the map cannot be a blob, [`FieldError::FreeSpace`]
/// when it has no free cell.
pub fn build_free_space(map: &OccupancyMap) -> Result<Vec<u8>, FieldError> {
    let h = header_for(map, DEFAULT_MAX_DIST_M);
    h.validate().map_err(FieldError::Header)?;
    let grid = FreeSpaceGrid {
        width: h.width,
        height: h.height,
        cell_size_m: h.cell_size_m,
        origin_x_m: h.origin_x_m,
        origin_y_m: h.origin_y_m,
    };
    let free: Vec<bool> = map.cells.iter().map(|c| *c == Occupancy::Free).collect();
    let n = free_space_len(&grid, &free).map_err(FieldError::FreeSpace)?;
    let mut out = vec![0u8; n];
    emit_free_space(&grid, &free, &mut out).map_err(FieldError::FreeSpace)?;
    Ok(out)
}
