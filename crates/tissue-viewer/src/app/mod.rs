//! Layer 8, the interactive viewer: a winit window with a wgpu view of the cube and an egui side
//! panel. May use every layer below it (render, study, calibrate, validate, gpu, sim, response,
//! mechanics, io); the physics loop runs on its own thread, never in the UI.
//!
//! - [`viewer`]: the event loop and the frame; [`surface`]: the window and its wgpu surface.
//! - [`recording`]: the hand's timeline in simulated time, and `view --record`.
//! - [`state`]: the window-free viewer state, which turns [`state::Request`]s into physics
//!   commands and background jobs, over what [`settings`] holds; [`panel`]: the side panel, a
//!   file per section; [`gestures`]: mouse gestures; [`overlay`]: colour scalar, legend and
//!   lines, once per frame; [`stats`]: frame rate and tool latency; [`exercise`]: find the lump; [`face_map`]: the palpation map's overlay.
//! - Threads, all [`worker::Worker`]s: [`physics`] (steps the simulation), [`calibration_job`],
//!   the chart of [`panel::study`], and the FEM answer of a load case. The UI thread only draws
//!   and forwards input.

pub mod calibration_job;
pub mod dent;
pub mod exercise;
pub mod face_map;
pub mod gestures;
pub mod overlay;
pub mod panel;
pub mod physics;
pub mod recording;
pub mod settings;
pub mod state;
pub mod stats;
pub mod surface;
pub mod viewer;
pub mod worker;

/// The headless commands, named when there is no display.
pub const HEADLESS_HINT: &str = "headless commands: render, simulate, palpate, fem, msm, errors, validate, calibrate, reproduce, dynamics, chart, choose, bench \
                                 (tissue-sim --help)";

/// True when an X11 or Wayland display is configured.
pub fn display_available() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"].iter().any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

/// Runs the viewer until its window closes. `frames` stops after that many frames (smoke tests)
/// and `screenshot` then saves the last frame there as PNG, the window as it showed it (the
/// panel included, the window's size), or the 3D view alone where the window cannot be read
/// back (or without `frames`).
pub fn run(options: ViewOptions) -> anyhow::Result<()> {
    if !display_available() {
        anyhow::bail!("no display (DISPLAY and WAYLAND_DISPLAY are unset), so the viewer cannot open; {HEADLESS_HINT}");
    }
    // A material's surface compliance is computed on one core: the physics and the drawing keep
    // the others.
    crate::sim::material_surface::set_compute_threads(1);
    viewer::run(options)
}

/// How the viewer starts.
#[derive(Debug, Clone, Default)]
pub struct ViewOptions {
    /// Close after this many frames (and print the rates once a second).
    pub frames: Option<u64>,
    /// After closing, save the final 3D view as PNG here.
    pub screenshot: Option<std::path::PathBuf>,
    /// The model to start with (the default tissue where `None`).
    pub model: Option<crate::sim::Model>,
    /// Where its steps are computed.
    pub compute: crate::gpu::Compute,
    /// Start with the probe pressed into the top face: `[x, y, depth]`, metres.
    pub press: Option<[f64; 3]>,
    /// Record what is done and write it here as a `simulate` script (on closing, on SIGINT or
    /// SIGTERM, and from the panel).
    pub record: Option<std::path::PathBuf>,
    /// Start with this material file (inclusions and all) instead of object A.
    pub material: Option<std::path::PathBuf>,
}
