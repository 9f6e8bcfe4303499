//! `map.png`: the palpation map as a heat map of the force over the face, with a colour bar in
//! newtons, each inclusion's outline dashed (its widest circle seen through the face) and a dot
//! on every point where the force passes the background's by more than a hand tells apart.

use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;

use super::{Face, PalpationMap};
use crate::mechanics::grid::CUBE_SIDE_M;

/// The picture's size, pixels.
const SIZE: (u32, u32) = (900, 760);
/// The colour bar's width, pixels.
const BAR: u32 = 150;

/// The map drawn as PNG bytes.
pub fn png(map: &PalpationMap) -> Result<Vec<u8>, String> {
    crate::study::font::register()?;
    let (w, h) = SIZE;
    let mut rgb = vec![255u8; (3 * w * h) as usize];
    draw(map, &mut rgb).map_err(|e| format!("cannot draw the map: {e}"))?;
    crate::study::font::png(&rgb, SIZE)
}

/// Draws `map` into the RGB buffer of [`SIZE`].
fn draw<'a>(map: &PalpationMap, rgb: &'a mut [u8]) -> Result<(), Box<dyn std::error::Error + 'a>> {
    let face = Face::parse(&map.face)?;
    let [u, v] = face.across();
    let names = ["x", "y", "z"];
    let side = CUBE_SIDE_M * 1e3;
    let low = map.forces.iter().copied().fold(f64::INFINITY, f64::min);
    let high = map.forces.iter().copied().fold(f64::NEG_INFINITY, f64::max).max(low + 1e-9);
    let colour = |f: f64| ViridisRGB::get_color_normalized(f, low, high);

    let root = BitMapBackend::with_buffer(rgb, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(SIZE.0 - BAR);
    let title = format!(
        "{}: face {}, probe {} pressed {}",
        map.material,
        map.face,
        crate::io::length(map.radius_m),
        crate::io::length(map.depth_m)
    );
    let mut chart = ChartBuilder::on(&left)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0..side, 0.0..side)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(format!("{} (mm)", names[u]))
        .y_desc(format!("{} (mm)", names[v]))
        .label_style(("sans-serif", 15))
        .draw()?;
    let cell = side / map.grid as f64;
    let across = |p: &[f64; 3]| (p[u] * 1e3, p[v] * 1e3);
    chart.draw_series(map.points.iter().zip(&map.forces).map(|(p, &f)| {
        let (a, b) = across(p);
        Rectangle::new([(a - 0.5 * cell, b - 0.5 * cell), (a + 0.5 * cell, b + 0.5 * cell)], colour(f).filled())
    }))?;
    let felt = map.points.iter().zip(&map.contrast).filter(|(_, c)| c.abs() > map.felt_contrast);
    chart
        .draw_series(felt.map(|(p, _)| Circle::new(across(p), 3, WHITE.filled())))?
        .label(format!("contrast against the background beyond {:.0} %", 100.0 * map.felt_contrast))
        .legend(|(x, y)| {
            Circle::new((x + 8, y), 3, ShapeStyle { color: BLACK.into(), filled: false, stroke_width: 1 })
        });
    for (k, inclusion) in map.inclusions.iter().enumerate() {
        let (a, b) = (inclusion.centre[u] * 1e3, inclusion.centre[v] * 1e3);
        let r = inclusion.radius * 1e3;
        let outline = (0..=120).map(|t| {
            let angle = std::f64::consts::TAU * t as f64 / 120.0;
            (a + r * angle.cos(), b + r * angle.sin())
        });
        let drawn = chart.draw_series(DashedLineSeries::new(outline, 6, 4, RED.stroke_width(2)))?;
        if k == 0 {
            drawn
                .label("inclusion (outline)")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], RED.stroke_width(2)));
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .position(SeriesLabelPosition::LowerLeft)
        .draw()?;

    let mut bar = ChartBuilder::on(&right)
        .margin_top(46)
        .margin_bottom(52)
        .margin_right(12)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..1.0, low..high)?;
    bar.configure_mesh().disable_mesh().disable_x_axis().y_desc("force (N)").label_style(("sans-serif", 15)).draw()?;
    let steps = 200;
    bar.draw_series((0..steps).map(|s| {
        let f0 = low + (high - low) * s as f64 / steps as f64;
        let f1 = low + (high - low) * (s + 1) as f64 / steps as f64;
        Rectangle::new([(0.0, f0), (1.0, f1)], colour(0.5 * (f0 + f1)).filled())
    }))?;
    root.present()?;
    Ok(())
}
