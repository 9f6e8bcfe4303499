//! The plots' font: plotters measures (and, in a PNG, draws) text with the font registered as
//! "sans-serif", here egui's own (Ubuntu Light), so a plot looks the same on every machine; and
//! the one encoder of a plot's pixels as PNG ([`png`]).

/// Registers the font (once); `Err` where it cannot be read.
pub fn register() -> Result<(), String> {
    static REGISTERED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(
            "sans-serif",
            plotters::style::FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        )
        .is_ok()
    });
    if ok { Ok(()) } else { Err("the plots' font cannot be read".into()) }
}

/// An 8-bit RGB picture (`size`, rows top to bottom) as PNG bytes.
pub fn png(rgb: &[u8], size: (u32, u32)) -> Result<Vec<u8>, String> {
    let mut out = std::io::Cursor::new(Vec::new());
    image::write_buffer_with_format(
        &mut out,
        rgb,
        size.0,
        size.1,
        image::ExtendedColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .map_err(|e| format!("cannot encode the picture as PNG: {e}"))?;
    Ok(out.into_inner())
}
