//! The interactive viewer: a winit window with a wgpu view of the cube and an egui side panel.
//! Physics runs on its own thread ([`physics`]); calibration runs on a background thread
//! ([`calibration`]); the UI thread only draws and forwards input.

pub mod calibration;
pub mod physics;
pub mod study_panel;
pub mod viewer;

/// The headless commands, named when there is no display.
pub const HEADLESS_HINT: &str = "headless commands: render, simulate, fem, msm, errors, calibrate, reproduce, chart, choose, bench \
                                 (tissue-sim --help)";

/// True when an X11 or Wayland display is configured.
pub fn display_available() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"].iter().any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

/// Runs the viewer until its window closes. `frames` stops after that many frames (smoke tests)
/// and `screenshot` then saves the last 3D view there as PNG.
pub fn run(frames: Option<u64>, screenshot: Option<std::path::PathBuf>) -> anyhow::Result<()> {
    if !display_available() {
        anyhow::bail!("no display (DISPLAY and WAYLAND_DISPLAY are unset), so the viewer cannot open; {HEADLESS_HINT}");
    }
    viewer::run(frames, screenshot)
}
