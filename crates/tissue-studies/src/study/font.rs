//! The plots' font: plotters measures (and, in a PNG, draws) text with the font registered as
//! "sans-serif", here egui's own (Ubuntu Light), so a plot looks the same on every machine.

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
