//! PNG charts for the reports a person would rather look at than read (coverage against κ,
//! score profiles). Fonts are embedded (DejaVu Sans), so rendering needs nothing from the system.

use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// Errors from rendering a chart.
#[derive(Debug)]
pub struct PlotError(pub String);

impl std::fmt::Display for PlotError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "cannot draw chart: {}", self.0)
    }
}

impl std::error::Error for PlotError {}

fn err<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError(e.to_string())
}

/// Registers the embedded DejaVu Sans as "sans-serif" for plotters (once per process).
pub fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // Registration fails only on a corrupt font, which would be a build defect.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

/// One named curve of a line chart.
pub struct Series {
    /// Legend text.
    pub name: String,
    /// Points `(x, y)` in drawing order.
    pub points: Vec<(f64, f64)>,
}

/// A line chart description.
pub struct LineChart<'a> {
    /// Title above the plot.
    pub title: &'a str,
    /// x-axis label (with unit).
    pub x_label: &'a str,
    /// y-axis label (with unit).
    pub y_label: &'a str,
    /// Logarithmic x axis.
    pub x_log: bool,
    /// Horizontal reference lines `(y, label)`.
    pub h_lines: Vec<(f64, String)>,
    /// Vertical reference lines `(x, label)`.
    pub v_lines: Vec<(f64, String)>,
    /// The curves.
    pub series: Vec<Series>,
}

const COLORS: [RGBColor; 5] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
];

/// Renders `chart` to a PNG file of 900×560 pixels.
///
/// # Errors
/// When the chart has no finite point or the file cannot be written.
pub fn line_chart(path: &Path, chart: &LineChart<'_>) -> Result<(), PlotError> {
    register_fonts();
    let pts = chart.series.iter().flat_map(|s| s.points.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in pts.filter(|(x, y)| x.is_finite() && y.is_finite()) {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    for (y, _) in &chart.h_lines {
        y0 = y0.min(*y);
        y1 = y1.max(*y);
    }
    if x0 > x1 {
        return Err(PlotError("no finite point to draw".into()));
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    let pad = ((y1 - y0) * 0.05).max(1e-9);
    let (y0, y1) = (y0 - pad, y1 + pad);
    let root = BitMapBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let mut builder = ChartBuilder::on(&root);
    builder
        .caption(chart.title, ("sans-serif", 22))
        .margin(14)
        // The last tick label of the x axis is centred on the plot's right end: room for its half.
        .margin_right(44)
        .x_label_area_size(46)
        .y_label_area_size(64);
    macro_rules! draw {
        ($ctx:expr) => {{
            let mut ctx = $ctx;
            ctx.configure_mesh()
                .x_desc(chart.x_label)
                .y_desc(chart.y_label)
                .label_style(("sans-serif", 15))
                .axis_desc_style(("sans-serif", 17))
                .draw()
                .map_err(err)?;
            for (i, s) in chart.series.iter().enumerate() {
                let c = COLORS[i % COLORS.len()];
                ctx.draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2)))
                    .map_err(err)?
                    .label(s.name.as_str())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2))
                    });
                ctx.draw_series(s.points.iter().map(|&p| Circle::new(p, 3, c.filled())))
                    .map_err(err)?;
            }
            for (y, label) in &chart.h_lines {
                let grey = RGBColor(120, 120, 120);
                ctx.draw_series(LineSeries::new(vec![(x0, *y), (x1, *y)], grey))
                    .map_err(err)?
                    .label(label.as_str())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], grey));
            }
            for (x, label) in &chart.v_lines {
                let black = RGBColor(0, 0, 0);
                ctx.draw_series(LineSeries::new(
                    vec![(*x, y0), (*x, y1)],
                    black.stroke_width(1),
                ))
                .map_err(err)?
                .label(label.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], black));
            }
            ctx.configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 15))
                .position(SeriesLabelPosition::LowerRight)
                .draw()
                .map_err(err)?;
        }};
    }
    if chart.x_log {
        let x0 = x0.max(1e-12);
        draw!(builder
            .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
            .map_err(err)?);
    } else {
        draw!(builder.build_cartesian_2d(x0..x1, y0..y1).map_err(err)?);
    }
    root.present().map_err(err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_a_png() {
        let dir = std::env::temp_dir().join(format!("bf-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("c.png");
        let chart = LineChart {
            title: "test",
            x_label: "kappa",
            y_label: "coverage",
            x_log: true,
            h_lines: vec![(0.95, "target".into())],
            v_lines: vec![(3.0, "chosen".into())],
            series: vec![Series {
                name: "coverage".into(),
                points: vec![(1.0, 0.5), (2.0, 0.8), (4.0, 0.97)],
            }],
        };
        line_chart(&p, &chart).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        assert!(line_chart(
            &dir.join("e.png"),
            &LineChart {
                series: vec![],
                ..chart
            }
        )
        .is_err());
    }

    /// The calibration plot's shape (log x axis from 1 to 1000): no label may run into the
    /// picture's edges, so the outermost columns and rows stay white.
    #[test]
    fn tick_labels_stay_inside_the_picture() {
        let dir = std::env::temp_dir().join(format!("bf-plot-edge-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("k.png");
        let points = (0..=36)
            .map(|i| {
                let k = 10f64.powf(f64::from(i) / 12.0);
                (k, 1.0 - 0.75 / k)
            })
            .collect();
        let chart = LineChart {
            title: "coverage of the credible set against tempering κ",
            x_label: "κ",
            y_label: "fraction of logged poses inside",
            x_log: true,
            h_lines: vec![(0.95, "requested 0.95".into())],
            v_lines: vec![(15.0, "κ = 15.000".into())],
            series: vec![Series {
                name: "60 scans".into(),
                points,
            }],
        };
        line_chart(&p, &chart).unwrap();
        let img = image::open(&p).unwrap().to_rgb8();
        let (w, h) = img.dimensions();
        let white = |x: u32, y: u32| img.get_pixel(x, y).0 == [255, 255, 255];
        for y in 0..h {
            for x in [0, 1, 2, w - 3, w - 2, w - 1] {
                assert!(
                    white(x, y),
                    "pixel ({x}, {y}) at the left or right edge is drawn"
                );
            }
        }
        for x in 0..w {
            for y in [0, 1, h - 2, h - 1] {
                assert!(
                    white(x, y),
                    "pixel ({x}, {y}) at the top or bottom edge is drawn"
                );
            }
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}
