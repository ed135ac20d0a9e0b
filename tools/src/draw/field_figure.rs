//! The picture `beamfield field render` writes: the field's cells (north up) with a title, axes
//! in metres (map frame) and a scale bar.

use crate::draw::plot::{register_fonts, PlotError};
use beamfield::field::FieldView;
use plotters::element::BitMapElement;
use plotters::prelude::*;
use std::path::Path;

/// What was drawn, for the command's report.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldFigure {
    /// Picture width, pixels.
    pub width_px: u32,
    /// Picture height, pixels.
    pub height_px: u32,
    /// Screen pixels per map cell (the field is drawn with square cells).
    pub px_per_cell: u32,
    /// Length of the scale bar, metres.
    pub scale_bar_m: f64,
}

/// The largest "round" length (1, 2 or 5 × 10^k metres) not longer than `max_m`.
pub fn scale_bar_length(max_m: f64) -> f64 {
    if !(max_m.is_finite() && max_m > 0.0) {
        return 0.0;
    }
    let decade = 10f64.powf(max_m.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * decade)
        .find(|&l| l <= max_m * (1.0 + 1e-12))
        .unwrap_or(decade)
}

/// Screen pixels per cell: the field fills about 800 pixels on its longer side, at least one
/// pixel per cell and at most eight.
pub fn px_per_cell(width_cells: u32, height_cells: u32) -> u32 {
    let side = width_cells.max(height_cells).max(1);
    (800 / side).clamp(1, 8)
}

/// Colour of a cell: occupied dark red; otherwise grey from black (0 m) to white (`d_max`),
/// darker where the distance crosses a multiple of 0.25 m from the cell below or to the left.
fn cell_rgb(view: &FieldView<'_>, ix: u32, iy: u32) -> [u8; 3] {
    let step = view.step_m();
    let contour = 0.25f32;
    let code = view.code(ix, iy).unwrap_or(255);
    if code == 0 {
        return [170, 0, 0];
    }
    let d = f32::from(code) * step;
    let mut g = (f32::from(code) / 255.0).sqrt() * 235.0 + 20.0;
    let below = view
        .code(ix, iy.saturating_sub(1))
        .map_or(d, |c| f32::from(c) * step);
    let left = view
        .code(ix.saturating_sub(1), iy)
        .map_or(d, |c| f32::from(c) * step);
    let k = (d / contour).floor();
    if code < 255 && ((below / contour).floor() != k || (left / contour).floor() != k) {
        g *= 0.6;
    }
    let g = g as u8;
    [g, g, g]
}

/// The field as an RGB image, one pixel per cell, north up, in the colours of [`draw_field`]
/// (without title, axes or key): the background of other pictures, such as `track`'s.
pub fn field_image(view: &FieldView<'_>) -> image::RgbImage {
    let h = view.height();
    image::RgbImage::from_fn(view.width(), h, |x, row| {
        image::Rgb(cell_rgb(view, x, h - 1 - row))
    })
}

/// Largest picture drawn, pixels: 2²⁵ (33.5 M, about 100 MB of RGB). The field of a map within
/// `field build`'s default `--max-cells` (4096 × 4096) is drawn one pixel per cell in
/// 4228 × 4244 pixels; a blob of 2²⁴ × 1 cells would need 2.5 G pixels.
pub const MAX_PICTURE_PIXELS: u64 = 1 << 25;

/// Refuses a picture of more than [`MAX_PICTURE_PIXELS`].
///
/// # Errors
/// [`PlotError`] naming the size and the limit.
pub fn check_picture_size(width_px: u32, height_px: u32) -> Result<(), PlotError> {
    let px = u64::from(width_px) * u64::from(height_px);
    if px > MAX_PICTURE_PIXELS {
        return Err(PlotError(format!(
            "a picture of {width_px} x {height_px} = {px} pixels is over the limit of \
             {MAX_PICTURE_PIXELS}"
        )));
    }
    Ok(())
}

/// Draws `view` to the PNG `path` with the title `title`.
///
/// # Errors
/// [`PlotError`] when the file cannot be written.
pub fn draw_field(
    path: &Path,
    view: &FieldView<'_>,
    title: &str,
) -> Result<FieldFigure, PlotError> {
    let err = |e: &dyn std::fmt::Display| PlotError(e.to_string());
    let (w, h) = (view.width(), view.height());
    let k = px_per_cell(w, h);
    let (plot_w, plot_h) = (w * k, h * k);
    // Room for the title, the axes' labels and the key line under the x axis.
    let (left, right, top, bottom) = (92u32, 40u32, 58u32, 90u32);
    let (width_px, height_px) = (plot_w + left + right, plot_h + top + bottom);
    check_picture_size(width_px, height_px)?;
    let hd = view.header();
    let cell = f64::from(hd.cell_size_m);
    let (ox, oy) = (f64::from(hd.origin_x_m), f64::from(hd.origin_y_m));
    let (x1, y1) = (ox + f64::from(w) * cell, oy + f64::from(h) * cell);

    register_fonts();
    let root = BitMapBackend::new(path, (width_px, height_px)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let (upper, lower) = root.split_vertically(top + plot_h + 45);
    let mut chart = ChartBuilder::on(&upper)
        .caption(title, ("sans-serif", 20))
        .margin_right(right)
        .margin_left(12)
        .margin_top(8)
        .x_label_area_size(45)
        .y_label_area_size(left)
        .build_cartesian_2d(ox..x1, oy..y1)
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(|e| err(&e))?;

    // The cells as one bitmap, resized (nearest cell) to the plotting area's pixels.
    let (area_w, area_h) = chart.plotting_area().dim_in_pixel();
    let mut buf = Vec::with_capacity(area_w as usize * area_h as usize * 3);
    for py in 0..area_h {
        // Row 0 of the picture is the map's top (largest y).
        let iy = h - 1 - (u64::from(py) * u64::from(h) / u64::from(area_h.max(1))) as u32;
        for px in 0..area_w {
            let ix = (u64::from(px) * u64::from(w) / u64::from(area_w.max(1))) as u32;
            buf.extend_from_slice(&cell_rgb(view, ix, iy));
        }
    }
    if let Some(bitmap) = BitMapElement::with_owned_buffer((ox, y1), (area_w, area_h), buf) {
        chart
            .draw_series(std::iter::once(bitmap))
            .map_err(|e| err(&e))?;
    }

    // Scale bar, lower right: at most a quarter of the map's width, on a white box.
    let bar = scale_bar_length((x1 - ox) / 4.0);
    let pad = (y1 - oy) * 0.04;
    let (bx1, by) = (x1 - (x1 - ox) * 0.04, oy + pad * 1.5);
    let bx0 = bx1 - bar;
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [
                (bx0 - pad * 0.5, oy + pad * 0.4),
                (bx1 + pad * 0.5, by + pad * 1.6),
            ],
            WHITE.mix(0.85).filled(),
        )))
        .map_err(|e| err(&e))?;
    chart
        .draw_series(std::iter::once(PathElement::new(
            vec![(bx0, by), (bx1, by)],
            BLACK.stroke_width(4),
        )))
        .map_err(|e| err(&e))?;
    let label = if bar >= 1.0 {
        format!("{bar} m")
    } else {
        format!("{} cm", (bar * 100.0).round())
    };
    chart
        .draw_series(std::iter::once(Text::new(
            label,
            (bx0, by + pad * 0.9),
            ("sans-serif", 15).into_font().color(&BLACK),
        )))
        .map_err(|e| err(&e))?;

    // The key, under the chart.
    let key = [
        format!(
            "red: occupied cell; grey: distance to the nearest occupied cell, black 0 m to white {:.2} m (d_max)",
            view.max_dist_m()
        ),
        format!(
            "contours every 0.25 m; {w} × {h} cells of {} m",
            hd.cell_size_m
        ),
    ];
    for (i, line) in key.into_iter().enumerate() {
        lower
            .draw(&Text::new(
                line,
                (12, 8 + 20 * i as i32),
                ("sans-serif", 14).into_font().color(&BLACK),
            ))
            .map_err(|e| err(&e))?;
    }
    root.present().map_err(|e| err(&e))?;
    Ok(FieldFigure {
        width_px,
        height_px,
        px_per_cell: k,
        scale_bar_m: bar,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_bars_are_round_and_fit() {
        for (max, want) in [
            (4.8, 2.0),
            (5.0, 5.0),
            (9.99, 5.0),
            (10.0, 10.0),
            (0.3, 0.2),
            (1.0, 1.0),
            (23.0, 20.0),
        ] {
            assert!((scale_bar_length(max) - want).abs() < 1e-12, "{max}");
        }
    }

    #[test]
    fn cells_fill_about_800_pixels() {
        assert_eq!(px_per_cell(384, 384), 2);
        assert_eq!(px_per_cell(50, 20), 8);
        assert_eq!(px_per_cell(1165, 945), 1);
    }
}
