//! Panel section "Integrator": which integrator and time step to ask for. The physics thread
//! applies the simulation's policy and publishes what runs, which is what the selector shows.

use crate::app::physics::Published;
use crate::app::state::{Request, Shown};
use crate::response::damping::Damping;
use crate::sim::Integrator;

/// The damping ratio slider and the running model's dynamic error on its fundamental.
fn dynamics(ui: &mut egui::Ui, shown: &Shown, published: &Published, requests: &mut Vec<Request>) {
    match published.damping {
        Some(damping @ Damping::Ratio { omega_1, .. }) => {
            let mut zeta = shown.damping_ratio;
            if ui
                .add(egui::Slider::new(&mut zeta, 0.0..=1.0).text("damping ratio"))
                .on_hover_text("at the fundamental, mass-proportional (Rayleigh): C = 2 zeta omega_1 M; 1 = critical")
                .changed()
            {
                requests.push(Request::SetDampingRatio(zeta));
            }
            let hz = omega_1 / (2.0 * std::f64::consts::PI);
            ui.label(format!("fundamental {hz:.2} Hz (face z = 0 clamped, the model's own modes)"));
            let budget = crate::sim::DEFAULT_DYNAMIC_BUDGET;
            if let Some((i, dt)) = published.integrator {
                match crate::sim::predicted_error(i, dt, damping) {
                    Some((p, d)) => {
                        let text = format!(
                            "dynamic error on the fundamental: period {:.2} %, damping {:.2} % of critical (budget {:.0} %, \
                             {:.0} %)",
                            100.0 * p,
                            100.0 * d,
                            100.0 * budget.period,
                            100.0 * budget.damping
                        );
                        let label = if p <= budget.period && d <= budget.damping {
                            egui::RichText::new(text)
                        } else {
                            egui::RichText::new(text).color(egui::Color32::from_rgb(230, 200, 90))
                        };
                        ui.label(label).on_hover_text(
                            "the integrator's closed form at this step, which time stepping measures to 1e-6 \
                             (`tissue-sim dynamics`)",
                        );
                    }
                    None => {
                        ui.colored_label(
                            egui::Color32::from_rgb(230, 120, 90),
                            "this step does not keep the fundamental",
                        );
                    }
                }
            }
        }
        Some(Damping::Nodal(d)) => {
            ui.label(format!(
                "damping: the paper's nodal d = {d:.3} N s/m (the axis lattice has no fundamental to set a ratio at)"
            ));
        }
        None => {}
    }
}

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
            .on_hover_text(
                "backward Euler with the rest tangent factorised once: one solve per step for the linear FEM; the \
                 lattices and the corotational FEM solve the step's equation by Newton, conjugate gradients on \
                 that factor. A drag is held inside the solve",
            )
            .changed()
        {
            ask = Some(Some(chosen));
        }
        if ui
            .selectable_value(&mut chosen, Integrator::Newmark, "Newmark, prefactored")
            .on_hover_text(
                "the trapezoidal rule with the rest tangent factorised once, no numerical damping: one solve per \
                 step for the linear FEM; the lattices and the corotational FEM solve the step's equation by \
                 Newton, conjugate gradients on that factor. A drag is held inside the solve",
            )
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
    ui.label(format!("explicit stability limit ~ {:.3} ms", published.limit.tissue * 1e3));
    if ui
        .button("auto (meets the dynamic budget)")
        .on_hover_text(
            "the fewest substeps of dt at which an integrator keeps the fundamental's period and damping within budget",
        )
        .clicked()
    {
        ask = Some(None);
    }
    dynamics(ui, shown, published, requests);
    if let Some(i) = ask {
        requests.push(Request::SetIntegrator(i, dt));
    }
    if ui.button("Reset to rest").clicked() {
        requests.push(Request::Reset);
    }
}
