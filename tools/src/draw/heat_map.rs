//! A labelled heat map of a square x–y grid of log-likelihoods (`beamfield score --grid`).

use crate::draw::plot::{register_fonts, PlotError};
use plotters::prelude::*;
use std::path::Path;

/// Nats below the maximum at which the colour scale saturates (darkest).
pub const RANGE_NATS: f64 = 30.0;

/// Draws `values` (row-major, x fastest, `n × n` cells, row 0 at the lowest y) over offsets
/// `[−half_m, half_m]²` from the centre: colour from dark (≤ max − 30 nats) to bright (max),
/// a white cross at the centre (the given pose), a black ring on the best cell. 800×760 px.
///
/// # Errors
/// [`PlotError`] when `values` is not `n × n`, holds no finite value, or the file cannot be
/// written.
pub fn heat_map(
    path: &Path,
    title: &str,
    n: usize,
    half_m: f64,
    values: &[f64],
) -> Result<(), PlotError> {
    let err = |e: &dyn std::fmt::Display| PlotError(e.to_string());
    if n == 0 || values.len() != n * n {
        return Err(PlotError(format!(
            "{} values for a {n}×{n} grid",
            values.len()
        )));
    }
    let max = values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(f64::NEG_INFINITY, f64::max);
    if !max.is_finite() {
        return Err(PlotError("no finite value to draw".into()));
    }
    register_fonts();
    let root = BitMapBackend::new(path, (800, 760)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let (plot, bar) = root.split_horizontally(680);
    let cell = if n > 1 {
        2.0 * half_m / (n - 1) as f64
    } else {
        1.0
    };
    let lim = half_m + cell / 2.0;
    let mut ctx = ChartBuilder::on(&plot)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(60)
        .build_cartesian_2d(-lim..lim, -lim..lim)
        .map_err(|e| err(&e))?;
    ctx.configure_mesh()
        .x_desc("x offset (m)")
        .y_desc("y offset (m)")
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .disable_mesh()
        .draw()
        .map_err(|e| err(&e))?;
    let colour = |v: f64| {
        let t = if v.is_finite() {
            ((v - max) / RANGE_NATS + 1.0).clamp(0.0, 1.0)
        } else {
            0.0
        };
        ramp(t)
    };
    let c0 = (n as f64 - 1.0) / 2.0;
    ctx.draw_series(values.iter().enumerate().map(|(i, &v)| {
        let (ix, iy) = ((i % n) as f64 - c0, (i / n) as f64 - c0);
        let (x, y) = (ix * cell, iy * cell);
        Rectangle::new(
            [
                (x - cell / 2.0, y - cell / 2.0),
                (x + cell / 2.0, y + cell / 2.0),
            ],
            colour(v).filled(),
        )
    }))
    .map_err(|e| err(&e))?;
    let arm = lim / 15.0;
    for seg in [[(-arm, 0.0), (arm, 0.0)], [(0.0, -arm), (0.0, arm)]] {
        ctx.draw_series(LineSeries::new(seg, WHITE.stroke_width(2)))
            .map_err(|e| err(&e))?;
    }
    if let Some((b, _)) = values
        .iter()
        .enumerate()
        .filter(|(_, v)| v.is_finite())
        .fold(None, |a: Option<(usize, f64)>, (i, &v)| match a {
            Some((_, m)) if m >= v => a,
            _ => Some((i, v)),
        })
    {
        let p = (((b % n) as f64 - c0) * cell, ((b / n) as f64 - c0) * cell);
        ctx.draw_series(std::iter::once(Circle::new(p, 7, BLACK.stroke_width(2))))
            .map_err(|e| err(&e))?;
    }
    // Colour bar: nats below the maximum.
    let mut cb = ChartBuilder::on(&bar)
        .margin_top(40)
        .margin_bottom(56)
        .margin_right(12)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..1.0, -RANGE_NATS..0.0)
        .map_err(|e| err(&e))?;
    cb.configure_mesh()
        .disable_x_axis()
        .disable_mesh()
        .y_desc("nats − max")
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 14))
        .draw()
        .map_err(|e| err(&e))?;
    let steps = 100;
    cb.draw_series((0..steps).map(|k| {
        let y0 = -RANGE_NATS + RANGE_NATS * k as f64 / steps as f64;
        let y1 = y0 + RANGE_NATS / steps as f64;
        Rectangle::new([(0.0, y0), (1.0, y1)], colour(max + y0).filled())
    }))
    .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// A perceptually ordered dark-blue → green → yellow ramp (viridis-like stops), `t` in [0, 1].
fn ramp(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let x = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let mix = |p: f64, q: f64| (p + (q - p) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}
