//! A rendered picture made readable on its own: a colour bar with its quantity, unit and scale
//! down the right edge, and a caption (what is drawn, the shape's magnification) along the bottom,
//! drawn into the picture's pixels with the plots' font.

use plotters::prelude::*;

/// Width of the strip the colour bar takes on the right, pixels.
const BAR_STRIP: u32 = 150;
/// Height of the caption's strip at the bottom, pixels.
const CAPTION_STRIP: u32 = 34;

/// The colour bar of a picture's colour map.
pub struct ColourBar<'a> {
    /// The quantity and its unit, e.g. `displacement (mm)`.
    pub title: String,
    /// The value the top of the map stands for, in the title's unit (the bottom is 0).
    pub max: f64,
    /// The map's colour at a fraction in [0, 1] of `max`, 8-bit sRGB.
    pub colour: &'a dyn Fn(f64) -> [u8; 3],
}

/// The picture `rgba` (`size`, 8-bit RGBA rows) with `bar` (where given) and `caption`, as PNG
/// bytes; the picture grows by the strips they take, its own pixels unchanged.
pub fn annotated_png(
    rgba: &[u8],
    size: (u32, u32),
    bar: Option<&ColourBar<'_>>,
    caption: &str,
) -> Result<Vec<u8>, String> {
    let (w, h) = size;
    if rgba.len() != 4 * (w as usize) * (h as usize) {
        return Err(format!("a {w} x {h} picture needs {} bytes, got {}", 4 * w * h, rgba.len()));
    }
    crate::study::font::register()?;
    let out = (w + if bar.is_some() { BAR_STRIP } else { 0 }, h + CAPTION_STRIP);
    let mut rgb = vec![255u8; 3 * (out.0 as usize) * (out.1 as usize)];
    for y in 0..h as usize {
        for x in 0..w as usize {
            let (from, to) = (4 * (y * w as usize + x), 3 * (y * out.0 as usize + x));
            rgb[to..to + 3].copy_from_slice(&rgba[from..from + 3]);
        }
    }
    draw(&mut rgb, out, (w, h), bar, caption).map_err(|e| format!("cannot draw the colour bar: {e}"))?;
    crate::study::font::png(&rgb, out)
}

fn draw<'a>(
    rgb: &'a mut [u8],
    out: (u32, u32),
    picture: (u32, u32),
    bar: Option<&ColourBar<'_>>,
    caption: &str,
) -> Result<(), Box<dyn std::error::Error + 'a>> {
    let root = BitMapBackend::with_buffer(rgb, out).into_drawing_area();
    let (top, bottom) = root.split_vertically(picture.1);
    bottom.draw_text(caption, &("sans-serif", 17).into_font().color(&BLACK), (10, 8))?;
    if let Some(bar) = bar {
        let (_, strip) = top.split_horizontally(picture.0);
        let max = if bar.max > 0.0 { bar.max } else { 1.0 };
        let mut chart = ChartBuilder::on(&strip)
            .margin_top(40)
            .margin_bottom(40)
            .margin_right(20)
            .margin_left(10)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..1.0, 0.0..max)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_desc(bar.title.as_str())
            .label_style(("sans-serif", 15))
            .draw()?;
        let steps = 200;
        chart.draw_series((0..steps).map(|s| {
            let (a, b) = (s as f64 / steps as f64, (s + 1) as f64 / steps as f64);
            let [r, g, bl] = (bar.colour)(0.5 * (a + b));
            Rectangle::new([(0.0, a * max), (1.0, b * max)], RGBColor(r, g, bl).filled())
        }))?;
    }
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bar_and_caption_are_added_beside_the_picture_which_is_kept() {
        let (w, h) = (120, 240);
        let rgba: Vec<u8> = (0..w * h).flat_map(|i| [(i % 251) as u8, 7, 9, 255]).collect();
        let colour = |t: f64| [(255.0 * t) as u8, 0, 0];
        let bar = ColourBar { title: "displacement (mm)".into(), max: 2.5, colour: &colour };
        let png = annotated_png(&rgba, (w, h), Some(&bar), "object A, shape x 1").expect("a picture");
        let img = image::load_from_memory(&png).expect("a PNG").to_rgb8();
        assert_eq!(img.dimensions(), (w + BAR_STRIP, h + CAPTION_STRIP));
        for (x, y) in [(0, 0), (13, 5), (w - 1, h - 1)] {
            let i = (4 * (y * w + x)) as usize;
            assert_eq!(img.get_pixel(x, y).0, [rgba[i], rgba[i + 1], rgba[i + 2]], "pixel ({x}, {y}) kept");
        }
        // Something is drawn in the caption's strip and in the bar's.
        let ink = |x0: u32, y0: u32, x1: u32, y1: u32| {
            (y0..y1).flat_map(|y| (x0..x1).map(move |x| (x, y))).any(|(x, y)| img.get_pixel(x, y).0 != [255, 255, 255])
        };
        assert!(ink(0, h, w, h + CAPTION_STRIP), "the caption");
        assert!(ink(w, 0, w + BAR_STRIP, h), "the bar");
        assert!(annotated_png(&rgba[1..], (w, h), None, "x").is_err());
    }
}
