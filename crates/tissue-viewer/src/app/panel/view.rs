//! Panel section "View": colour map, overlays and the camera.

use crate::app::state::ViewSettings;
use crate::render::camera::OrbitCamera;
use crate::render::scene::ColourMode;

/// Draws the section.
pub fn show(ui: &mut egui::Ui, settings: &mut ViewSettings, camera: &mut OrbitCamera) {
    ui.horizontal(|ui| {
        ui.selectable_value(&mut settings.colour, ColourMode::None, "plain");
        ui.selectable_value(&mut settings.colour, ColourMode::Displacement, "displacement");
        ui.selectable_value(&mut settings.colour, ColourMode::Error, "error vs FEM");
    });
    ui.checkbox(&mut settings.show_springs, "springs");
    ui.checkbox(&mut settings.show_nodes, "nodes");
    ui.checkbox(&mut settings.show_fixed, "fixed nodes");
    if ui.button("Reset camera").clicked() {
        *camera = OrbitCamera::default();
    }
}
