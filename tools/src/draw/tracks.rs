//! The track picture: trajectories over the rendered field.

use crate::draw::field_figure::field_image;
use crate::track::{RunResult, TrackError, TrackInput};
use beamfield::Pose;
use std::path::Path;

/// Draws the true (blue: the logged poses, or the reference poses joined) and estimated (green) trajectories over the rendered field, one pixel
/// per cell, north up.
pub fn draw_track(
    path: &Path,
    input: &TrackInput,
    r: &RunResult,
    scans: usize,
) -> Result<(), TrackError> {
    let (view, _) = input.views()?;
    crate::draw::field_figure::check_picture_size(view.width(), view.height())
        .map_err(|e| TrackError::Png(path.to_path_buf(), e.0))?;
    let base = field_image(&view);
    let scale = 1u32;
    let img = image::imageops::resize(
        &base,
        base.width() * scale,
        base.height() * scale,
        image::imageops::FilterType::Nearest,
    );
    let mut img = img;
    let h = view.header();
    let (w_px, h_px) = (img.width() as i64, img.height() as i64);
    let to_px = |p: &Pose| {
        let gx = (f64::from(p.x_m) - f64::from(h.origin_x_m)) / f64::from(h.cell_size_m);
        let gy = (f64::from(p.y_m) - f64::from(h.origin_y_m)) / f64::from(h.cell_size_m);
        (
            (gx * f64::from(scale)) as i64,
            h_px - 1 - (gy * f64::from(scale)) as i64,
        )
    };
    let mut line = |a: (i64, i64), b: (i64, i64), color: [u8; 3]| {
        let n = (b.0 - a.0).abs().max((b.1 - a.1).abs()).max(1);
        for i in 0..=n {
            let x = a.0 + (b.0 - a.0) * i / n;
            let y = a.1 + (b.1 - a.1) * i / n;
            for (ox, oy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let (px, py) = (x + ox, y + oy);
                if (0..w_px).contains(&px) && (0..h_px).contains(&py) {
                    img.put_pixel(px as u32, py as u32, image::Rgb(color));
                }
            }
        }
    };
    let truth: Vec<Pose> = (r.start..scans).filter_map(|k| input.truth(k)).collect();
    for pair in truth.windows(2) {
        line(to_px(&pair[0]), to_px(&pair[1]), [30, 80, 230]);
    }
    for pair in r.estimates.windows(2) {
        line(to_px(&pair[0]), to_px(&pair[1]), [0, 170, 0]);
    }
    img.save_with_format(path, image::ImageFormat::Png)
        .map_err(|e| TrackError::Png(path.to_path_buf(), e.to_string()))
}
