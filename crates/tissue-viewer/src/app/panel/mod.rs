//! The side panel: a status header, then one section a file. Sections edit the pure view
//! settings directly and return [`Request`]s for everything else; none calls the physics thread.
//!
//! One file per section: [`model`] (object, model, resolution, compute), [`integrator`], [`tools`],
//! [`view`], [`find_lump`], [`calibration`] and [`study`] (speed vs accuracy).

pub mod calibration;
pub mod find_lump;
pub mod integrator;
pub mod model;
pub mod study;
pub mod tools;
pub mod view;

use super::physics::Published;
use super::settings::Source;
use super::state::{Request, Shown, ViewSettings};
use crate::render::camera::OrbitCamera;
use study::StudyPanel;

/// What the panel reads and edits besides the viewer state.
pub struct PanelContext<'a> {
    /// The physics thread's latest state.
    pub published: &'a Published,
    /// Frames per second.
    pub fps: f64,
    /// Tool input-to-screen latency: mean and max, s.
    pub latency: (f64, f64),
    /// The physics thread's end, if it ended.
    pub physics_stopped: Option<&'a str>,
    /// Rest positions (f32), for the error readout.
    pub rest: &'a [[f32; 3]],
    /// The model's grid.
    pub grid: crate::mechanics::grid::Grid,
}

/// Draws the whole panel.
pub fn show(
    ui: &mut egui::Ui,
    settings: &mut ViewSettings,
    shown: &Shown,
    ctx: &PanelContext<'_>,
    camera: &mut OrbitCamera,
    study: &mut StudyPanel,
    requests: &mut Vec<Request>,
) {
    header(ui, shown, ctx);
    // The left-button tool first, where it is always in view (keys p, d, c).
    tools::tool_picker(ui, settings);
    tools::recording(ui, settings, requests);
    ui.separator();
    egui::CollapsingHeader::new("Object and model")
        .default_open(true)
        .show(ui, |ui| model::show(ui, settings, shown, requests));
    egui::CollapsingHeader::new("Integrator")
        .default_open(true)
        .show(ui, |ui| integrator::show(ui, shown, ctx.published, requests));
    egui::CollapsingHeader::new("Tools")
        .default_open(true)
        .show(ui, |ui| tools::show(ui, settings, shown, ctx, requests));
    egui::CollapsingHeader::new("View").default_open(true).show(ui, |ui| view::show(ui, settings, camera));
    egui::CollapsingHeader::new("Find the lump")
        .default_open(!shown.inclusions.is_empty() || shown.exercise.is_some())
        .show(ui, |ui| find_lump::show(ui, settings, shown, requests));
    egui::CollapsingHeader::new("Speed vs accuracy").default_open(false).show(ui, |ui| {
        let repaint = ui.ctx().clone();
        match settings.object {
            Source::Object(object) => study.ui(ui, object, move || repaint.request_repaint()),
            Source::File => {
                ui.label("The chart covers the objects A and B.");
            }
        }
    });
    egui::CollapsingHeader::new("Calibration (GA+SA)")
        .default_open(true)
        .show(ui, |ui| calibration::show(ui, settings, shown, requests));
}

fn header(ui: &mut egui::Ui, shown: &Shown, ctx: &PanelContext<'_>) {
    let r = ctx.published.rates;
    ui.heading("tissue-sim");
    ui.label(format!(
        "{:.0} fps | physics {:.0} ticks/s ({:.0} steps/s, {:.1} us/step, x{:.2} real time)",
        ctx.fps, r.ticks_per_s, r.steps_per_s, r.step_us, r.realtime
    ));
    if ctx.latency.0 > 0.0 {
        ui.label(format!(
            "tool input to screen: mean {:.0} ms, max {:.0} ms",
            ctx.latency.0 * 1e3,
            ctx.latency.1 * 1e3
        ));
    }
    let red = egui::Color32::from_rgb(255, 120, 90);
    let amber = egui::Color32::from_rgb(230, 200, 90);
    if let Some(m) = ctx.physics_stopped {
        ui.colored_label(red, m);
    }
    if let Some(m) = &ctx.published.message {
        ui.colored_label(red, m);
    }
    if let Some(n) = &ctx.published.note {
        ui.colored_label(amber, n);
    }
    if let Some(n) = &shown.note {
        ui.colored_label(amber, n);
    }
}

/// A plot that fits the side panel's width and always shows all its data: labelled axes, bounds
/// fitted to the curves every frame (no drag or zoom to leave them stale).
pub(crate) fn fitted_plot(ui: &egui::Ui, id: &str, x: &str, y: &str) -> egui_plot::Plot<'static> {
    egui_plot::Plot::new(id.to_owned())
        .width(ui.available_width())
        .height(120.0)
        .x_axis_label(x.to_owned())
        .y_axis_label(y.to_owned())
        .auto_bounds(egui::Vec2b::TRUE)
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .allow_boxed_zoom(false)
        .allow_double_click_reset(false)
}
