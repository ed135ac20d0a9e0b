//! A built map as a PNG picture for people: free white, occupied black, unknown grey, with a
//! path (the robot's trajectory) in red.

use crate::mapping::{Cell, MapIoError, OccupancyGrid};
use std::path::Path;

/// Writes a PNG picture of the grid for people: free white, occupied black, unknown grey, top
/// of the image = +y, and `path_m` (world points, metres, for example the robot's trajectory)
/// drawn in red over it.
///
/// # Errors
/// [`MapIoError::Image`] when the PNG cannot be encoded or written.
pub fn write_png(
    grid: &OccupancyGrid,
    path_m: &[(f64, f64)],
    png: &Path,
) -> Result<(), MapIoError> {
    let g = grid.geometry();
    let (w, h) = (g.width as u32, g.height as u32);
    let mut img = image::RgbImage::new(w, h);
    for (i, &c) in grid.cells().iter().enumerate() {
        let (col, row) = ((i % g.width) as u32, (i / g.width) as u32);
        let v = match c {
            Cell::Occupied => [0, 0, 0],
            Cell::Free => [255, 255, 255],
            Cell::Unknown => [170, 170, 170],
        };
        img.put_pixel(col, h - 1 - row, image::Rgb(v));
    }
    for &(x, y) in path_m {
        if let Some((c, r)) = g.cell_of(x, y) {
            img.put_pixel(c as u32, h - 1 - r as u32, image::Rgb([220, 30, 30]));
        }
    }
    img.save_with_format(png, image::ImageFormat::Png)
        .map_err(|source| MapIoError::Image {
            path: png.to_path_buf(),
            source,
        })
}
