//! SVG line charts (plotters) for the reproduction report.

use plotters::prelude::*;

/// One line: a label and its points.
pub struct Series<'a> {
    /// Legend label.
    pub label: &'a str,
    /// `(x, y)` points.
    pub points: Vec<(f64, f64)>,
}

const COLOURS: [RGBColor; 4] =
    [RGBColor(31, 119, 180), RGBColor(214, 39, 40), RGBColor(44, 160, 44), RGBColor(148, 103, 189)];

/// One figure in the two forms a report carries: SVG (scales) and PNG (shows anywhere).
pub struct Figure {
    /// The SVG text.
    pub svg: String,
    /// The PNG bytes, the same drawing in pixels.
    pub png: Vec<u8>,
}

/// Renders panels side by side (one `(title, y label, series)` each) as SVG and as PNG.
pub fn line_panels(title: &str, x_label: &str, panels: &[(&str, &str, Vec<Series<'_>>)]) -> anyhow::Result<Figure> {
    crate::study::font::register().map_err(anyhow::Error::msg)?;
    let size = (520 * panels.len().max(1) as u32, 420);
    let mut svg = String::new();
    draw(SVGBackend::with_string(&mut svg, size).into_drawing_area(), title, x_label, panels)?;
    let mut rgb = vec![255u8; 3 * (size.0 * size.1) as usize];
    draw(BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area(), title, x_label, panels)?;
    let png = crate::study::font::png(&rgb, size).map_err(anyhow::Error::msg)?;
    Ok(Figure { svg, png })
}

/// Draws the panels on `root`, whatever its backend.
fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    x_label: &str,
    panels: &[(&str, &str, Vec<Series<'_>>)],
) -> anyhow::Result<()> {
    {
        root.fill(&WHITE).map_err(|e| anyhow::anyhow!("plot: {e}"))?;
        let root = root.titled(title, ("sans-serif", 20)).map_err(|e| anyhow::anyhow!("plot: {e}"))?;
        let areas = root.split_evenly((1, panels.len().max(1)));
        for (area, (panel_title, y_label, series)) in areas.iter().zip(panels) {
            let all = series.iter().flat_map(|s| s.points.iter());
            let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
            for &(x, y) in all {
                if x.is_finite() && y.is_finite() {
                    (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
                }
            }
            if x0 > x1 {
                (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
            }
            let pad = ((y1 - y0) * 0.05).max(1e-12 * y1.abs().max(1e-300));
            let mut chart = ChartBuilder::on(area)
                .caption(*panel_title, ("sans-serif", 16))
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(70)
                .build_cartesian_2d(x0..x1.max(x0 + 1e-12), (y0 - pad)..(y1 + pad))
                .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
            chart
                .configure_mesh()
                .x_desc(x_label)
                .y_desc(*y_label)
                .y_label_formatter(&|v| format!("{v:.3e}"))
                .draw()
                .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
            for (i, s) in series.iter().enumerate() {
                let colour = COLOURS[i % COLOURS.len()];
                chart
                    .draw_series(LineSeries::new(s.points.iter().copied(), colour.stroke_width(2)))
                    .map_err(|e| anyhow::anyhow!("plot: {e}"))?
                    .label(s.label)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2)));
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
        }
        root.present().map_err(|e| anyhow::anyhow!("plot: {e}"))?;
    }
    Ok(())
}
