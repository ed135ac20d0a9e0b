//! A picture of scans over the distance field around a pose (`beamfield score --overlay`):
//! where a scan's endpoints land on the map at the pose it is given, and at another pose
//! (the grid's best), so a person can see which one lines up with the walls.

use crate::draw::plot::{register_fonts, PlotError};
use beamfield::field::FieldView;
use plotters::prelude::*;
use std::path::Path;

/// One set of scan endpoints to draw, with the pose they were projected from.
pub struct OverlayScan {
    /// Legend text.
    pub name: String,
    /// Colour of its dots and of its pose marker.
    pub color: RGBColor,
    /// Sensor pose in the map frame: x, y (metres), θ (radians).
    pub pose: (f64, f64, f64),
    /// Endpoints in the map frame, metres.
    pub points: Vec<(f64, f64)>,
}

/// What [`draw_overlay`] draws: a square window of the field and the scans over it.
pub struct Overlay<'a> {
    /// Title line.
    pub title: &'a str,
    /// Centre of the window, map frame, metres.
    pub center: (f64, f64),
    /// Half-width of the window, metres.
    pub half_m: f64,
    /// Scans, drawn in order (the last on top).
    pub scans: Vec<OverlayScan>,
}

/// Endpoints in the map frame of the readings below `max_range_m` (metres) of a scan with
/// ranges `ranges_m` at bearings `bearings_rad`, seen from the sensor pose `(x, y, θ)`.
pub fn endpoints(
    pose: (f64, f64, f64),
    bearings_rad: &[f32],
    ranges_m: &[f32],
    max_range_m: f32,
) -> Vec<(f64, f64)> {
    bearings_rad
        .iter()
        .zip(ranges_m)
        .filter(|&(_, &r)| r.is_finite() && r >= 0.0 && r < max_range_m)
        .map(|(&b, &r)| {
            let a = pose.2 + f64::from(b);
            let r = f64::from(r);
            (pose.0 + r * a.cos(), pose.1 + r * a.sin())
        })
        .collect()
}

/// Draws the field (grey from black at 0 m to white at `d_max`, occupied cells dark red) in
/// the window, the scans' endpoints as rings and each scan's pose as a larger ring with a
/// heading tick (what lies outside the window is left out). Axes in metres (map frame), north up, 900×900 px.
///
/// # Errors
/// [`PlotError`] when the window is empty or not finite, or the file cannot be written.
pub fn draw_overlay(path: &Path, view: &FieldView<'_>, ov: &Overlay<'_>) -> Result<(), PlotError> {
    let err = |e: &dyn std::fmt::Display| PlotError(e.to_string());
    let (cx, cy, h) = (ov.center.0, ov.center.1, ov.half_m);
    if !(cx.is_finite() && cy.is_finite() && h.is_finite() && h > 0.0) {
        return Err(PlotError(format!(
            "window ({cx}, {cy}) ± {h} m is not a finite, non-empty square"
        )));
    }
    register_fonts();
    let root = BitMapBackend::new(path, (900, 900)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(ov.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d((cx - h)..(cx + h), (cy - h)..(cy + h))
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .draw()
        .map_err(|e| err(&e))?;
    // The cells of the window, as filled squares.
    let hd = view.header();
    let cell = f64::from(hd.cell_size_m);
    let (ox, oy) = (f64::from(hd.origin_x_m), f64::from(hd.origin_y_m));
    let first = |lo: f64, o: f64| ((lo - o) / cell).floor().max(0.0) as u32;
    let last = |hi: f64, o: f64, n: u32| (((hi - o) / cell).ceil().max(0.0) as u32).min(n);
    let (x0, x1) = (first(cx - h, ox), last(cx + h, ox, view.width()));
    let (y0, y1) = (first(cy - h, oy), last(cy + h, oy, view.height()));
    let d_max = view.max_dist_m();
    let step = view.step_m();
    let cells = (y0..y1).flat_map(|iy| (x0..x1).map(move |ix| (ix, iy)));
    chart
        .draw_series(cells.filter_map(|(ix, iy)| {
            let code = view.code(ix, iy)?;
            let color = if code == 0 {
                RGBColor(150, 0, 0)
            } else {
                let g = (f32::from(code) * step / d_max).sqrt() * 200.0 + 55.0;
                let g = g as u8;
                RGBColor(g, g, g)
            };
            let (x, y) = (ox + f64::from(ix) * cell, oy + f64::from(iy) * cell);
            Some(Rectangle::new(
                [(x, y), (x + cell, y + cell)],
                color.filled(),
            ))
        }))
        .map_err(|e| err(&e))?;
    let inside = |&(x, y): &(f64, f64)| (x - cx).abs() <= h && (y - cy).abs() <= h;
    for s in &ov.scans {
        let color = s.color;
        chart
            .draw_series(
                s.points
                    .iter()
                    .filter(|p| inside(p))
                    .map(|&p| Circle::new(p, 3, color.stroke_width(2))),
            )
            .map_err(|e| err(&e))?
            .label(s.name.as_str())
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
        let (px, py, th) = s.pose;
        if !inside(&(px, py)) {
            continue;
        }
        let tick = h / 25.0;
        chart
            .draw_series([PathElement::new(
                vec![(px, py), (px + tick * th.cos(), py + tick * th.sin())],
                color.stroke_width(3),
            )])
            .map_err(|e| err(&e))?;
        chart
            .draw_series([Circle::new((px, py), 6, color.stroke_width(2))])
            .map_err(|e| err(&e))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .label_font(("sans-serif", 16))
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::endpoints;

    #[test]
    fn endpoints_turn_with_the_pose_and_skip_max_range() {
        let b = [0.0f32, std::f32::consts::FRAC_PI_2];
        let pts = endpoints(
            (1.0, 2.0, std::f64::consts::FRAC_PI_2),
            &b,
            &[3.0, 10.0],
            10.0,
        );
        assert_eq!(pts.len(), 1);
        // Bearing 0 at heading 90°: straight up from (1, 2).
        assert!((pts[0].0 - 1.0).abs() < 1e-6 && (pts[0].1 - 5.0).abs() < 1e-6);
        let pts = endpoints((0.0, 0.0, 0.0), &b, &[1.0, 2.0], 10.0);
        assert!((pts[1].0).abs() < 1e-6 && (pts[1].1 - 2.0).abs() < 1e-6);
    }
}
