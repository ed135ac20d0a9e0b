//! A polar plot of one LiDAR scan: its end points in the sensor frame (x forward, y left).

use crate::draw::plot::{register_fonts, PlotError};
use beamfield::BeamLayout;
use std::path::Path;

/// Draws one scan's end points (sensor frame, x forward, y left) as a PNG.
///
/// # Errors
/// [`PlotError`].
pub fn polar_png<const N: usize>(
    path: &Path,
    layout: &BeamLayout<N>,
    ranges: &[f32],
    title: &str,
) -> Result<(), PlotError> {
    use plotters::prelude::*;
    let perr = |e: &dyn std::fmt::Display| PlotError(e.to_string());
    register_fonts();
    let pts: Vec<(f64, f64)> = layout
        .beams()
        .iter()
        .zip(ranges)
        .filter(|(_, r)| r.is_finite() && **r < layout.max_range_m())
        .map(|(b, &r)| (f64::from(r * b.cos), f64::from(r * b.sin)))
        .collect();
    let extent = pts
        .iter()
        .fold(1.0f64, |m, &(x, y)| m.max(x.abs()).max(y.abs()))
        * 1.05;
    let root = BitMapBackend::new(path, (700, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| perr(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(-extent..extent, -extent..extent)
        .map_err(|e| perr(&e))?;
    chart
        .configure_mesh()
        .x_desc("x forward (m)")
        .y_desc("y left (m)")
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(|e| perr(&e))?;
    chart
        .draw_series(
            pts.iter()
                .map(|&p| Circle::new(p, 2, RGBColor(31, 119, 180).filled())),
        )
        .map_err(|e| perr(&e))?;
    chart
        .draw_series(std::iter::once(Circle::new((0.0, 0.0), 4, RED.filled())))
        .map_err(|e| perr(&e))?;
    root.present().map_err(|e| perr(&e))?;
    Ok(())
}
