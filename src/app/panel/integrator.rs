//! Panel section "Integrator": which integrator and time step to ask for. The physics thread
//! applies the simulation's policy and publishes what runs, which is what the selector shows.

use crate::app::physics::Published;
use crate::app::state::{Request, Shown};
use crate::sim::Integrator;

/// Draws the section.
pub fn show(ui: &mut egui::Ui, shown: &Shown, published: &Published, requests: &mut Vec<Request>) {
    let running = published.integrator.map_or(Integrator::Symplectic, |(i, _)| i);
    let mut chosen = running;
    let mut dt = shown.dt;
    let mut ask: Option<Option<Integrator>> = None;
    ui.horizontal_wrapped(|ui| {
        if ui.selectable_value(&mut chosen, Integrator::Symplectic, "symplectic Euler").changed() {
            ask = Some(Some(chosen));
        }
        if ui
            .selectable_value(&mut chosen, Integrator::Prefactored, "implicit, prefactored")
            .on_hover_text("backward Euler with the rest tangent factorised once: one solve per step")
            .changed()
        {
            ask = Some(Some(chosen));
        }
        if ui
            .selectable_value(&mut chosen, Integrator::Implicit, "implicit, full tangent")
            .on_hover_text("backward Euler refactorising the current tangent every step")
            .changed()
        {
            ask = Some(Some(chosen));
        }
    });
    let mut dt_ms = dt * 1e3;
    if ui.add(egui::Slider::new(&mut dt_ms, 0.01..=5.0).logarithmic(true).text("dt (ms)")).changed() {
        dt = dt_ms * 1e-3;
        ask = Some(ask.unwrap_or(Some(running)));
    }
    ui.label(format!("explicit stability limit ~ {:.3} ms", published.dt_limit * 1e3));
    if ui.button("auto (explicit when safe)").clicked() {
        ask = Some(None);
    }
    if let Some(i) = ask {
        requests.push(Request::SetIntegrator(i, dt));
    }
    if ui.button("Reset to rest").clicked() {
        requests.push(Request::Reset);
    }
}
