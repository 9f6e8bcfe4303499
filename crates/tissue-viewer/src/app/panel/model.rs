//! Panel section "Object and model": the object (a preset or a material file), the lattice, and
//! its parameters, edited live.

use crate::app::settings::Source;
use crate::app::state::{Request, Shown, ViewSettings};
use crate::gpu::Compute;
use crate::mechanics::fem::dynamics::Formulation;
use crate::mechanics::msm::Topology;
use crate::mechanics::object::Object;
use crate::sim::Model;

/// The touch force budget as a fraction (its one home: [`crate::study::choose`]).
const FORCE_BUDGET: f64 = crate::study::choose::DEFAULT_MAX_FORCE_ERROR_PCT / 100.0;

/// The running model's touch-benchmark scores on the validation set, against the force budget;
/// where it misses, the model that meets it is offered.
fn validation(ui: &mut egui::Ui, shown: &Shown, requests: &mut Vec<Request>) {
    match &shown.validation {
        None => {
            ui.label("touch validation: computing...");
        }
        Some(Err(e)) => {
            ui.label(format!("touch validation: {e}"));
        }
        Some(Ok(v)) => {
            ui.label(format!(
                "touch validation of the model's own nodes (held-out touches against the FEM; what a drag or a \
                 load case moves, not what the probe feels): force error worst {:.1} %, median {:.1} %; lowest six \
                 modes within {:.1} %",
                100.0 * v.worst_force_error,
                100.0 * v.median_force_error,
                100.0 * v.worst_frequency_error
            ));
            if v.worst_force_error > FORCE_BUDGET {
                ui.horizontal_wrapped(|ui| {
                    ui.colored_label(
                        egui::Color32::from_rgb(230, 200, 90),
                        format!(
                            "its nodes miss the {} % force budget by {:.1} points (the probe on the material's \
                             surface does not feel them); the FEM meets it",
                            crate::study::choose::DEFAULT_MAX_FORCE_ERROR_PCT,
                            100.0 * (v.worst_force_error - FORCE_BUDGET)
                        ),
                    );
                    if ui.button("run the FEM (corotational)").clicked() {
                        requests.push(Request::SelectFem(Formulation::Corotational));
                    }
                });
            } else {
                ui.label(format!(
                    "meets the {} % force budget on every validation touch",
                    crate::study::choose::DEFAULT_MAX_FORCE_ERROR_PCT
                ));
            }
        }
    }
}

/// For a material with inclusions: the running model against the material with them, over each.
fn inclusion_validation(ui: &mut egui::Ui, shown: &Shown) {
    match &shown.inclusion_validation {
        None if !shown.inclusions.is_empty() => {
            ui.label("with its inclusions: computing the material's answer...");
        }
        None => {}
        Some(Err(e)) => {
            ui.label(format!("with its inclusions: {e}"));
        }
        Some(Ok(r)) => {
            for c in r.cases.iter().filter(|c| c.id.ends_with("_over")) {
                ui.label(format!(
                    "{}: a {} N pressure over it sinks {:.1} % less with it, the material {:.1} % (field error {:.1} %)",
                    c.id.trim_start_matches("pressure_").trim_end_matches("_over"),
                    crate::validate::inclusions::PRESSURE_FORCE_N,
                    -100.0 * c.model_effect,
                    -100.0 * c.material_effect,
                    100.0 * c.field_error
                ));
            }
        }
    }
}

/// The resolution control: nodes per edge, applied when the slider is let go.
fn resolution(ui: &mut egui::Ui, settings: &mut ViewSettings, requests: &mut Vec<Request>) {
    let slider = ui.add(egui::Slider::new(&mut settings.nodes, 4..=24).text("nodes per edge"));
    if slider.drag_stopped() || (slider.changed() && !slider.dragged()) {
        requests.push(Request::SetResolution(settings.nodes));
    }
    ui.label(
        "Resolution of the model shown. The probe's force comes from the material's surface compliance at any \
         resolution; finer grids cost speed (the physics rates show it).",
    );
}

fn compute(ui: &mut egui::Ui, settings: &mut ViewSettings, requests: &mut Vec<Request>) {
    ui.horizontal(|ui| {
        ui.label("compute:");
        for c in [Compute::Cpu, Compute::CpuF32, Compute::Gpu] {
            if ui.radio_value(&mut settings.compute, c, c.name()).changed() {
                requests.push(Request::SetCompute);
            }
        }
    });
    match settings.compute {
        Compute::Gpu => ui.label(
            "Symplectic steps of the lattices and the linear FEM run as compute shaders in f32; implicit steps and \
             the corotational FEM stay on the CPU.",
        ),
        Compute::CpuF32 => ui.label(
            "The symplectic step of the lattices and the linear FEM sums its force in f32 on the CPU (1.5 to 2.6x \
             faster a tick at 24^3; after 20 ticks the nodes part from the f64 run by up to 2.3e-7 of the largest \
             displacement on the lattices, 3.5e-5 on the FEM, at 8^3 to 32^3); the corotational FEM refuses it.",
        ),
        Compute::Cpu => return,
    };
}

/// Draws the section.
pub fn show(ui: &mut egui::Ui, settings: &mut ViewSettings, shown: &Shown, requests: &mut Vec<Request>) {
    let mut reload = false;
    ui.horizontal(|ui| {
        for object in Object::ALL {
            reload |= ui.selectable_value(&mut settings.object, Source::Object(object), object.name()).changed();
        }
        reload |= ui.selectable_value(&mut settings.object, Source::File, "file").changed();
    });
    if settings.object == Source::File {
        ui.horizontal(|ui| {
            ui.text_edit_singleline(&mut settings.material_path);
            reload |= ui.button("Load").clicked();
        });
        reload &= !settings.material_path.trim().is_empty();
    }
    if reload {
        requests.push(Request::LoadObject);
    }
    let mut model = shown.model();
    ui.horizontal_wrapped(|ui| {
        let mut pick = |ui: &mut egui::Ui, m: Model, label: &str| {
            if ui.selectable_value(&mut model, m, label).changed() {
                requests.push(match m {
                    Model::Lattice(t) => Request::SelectTopology(t),
                    Model::Fem(f) => Request::SelectFem(f),
                });
            }
        };
        pick(ui, Model::Lattice(Topology::Hex), "hex lattice (default)");
        pick(ui, Model::Lattice(Topology::Shear), "shear springs");
        pick(ui, Model::Lattice(Topology::Axis), "paper: axis springs");
        pick(ui, Model::Fem(Formulation::Linear), "FEM linear");
        pick(ui, Model::Fem(Formulation::Corotational), "FEM corotational");
    });
    resolution(ui, settings, requests);
    compute(ui, settings, requests);
    validation(ui, shown, requests);
    inclusion_validation(ui, shown);
    if shown.fem.is_some() {
        ui.label(
            "The hex8 FEM (the reference itself): no spring parameters; damped by the ratio set under Integrator.",
        );
        return;
    }
    if shown.topology() == Topology::Axis {
        ui.colored_label(
            egui::Color32::from_rgb(230, 200, 90),
            "The paper's lattice has springs along the axes only: nothing resists shear. Drag a corner sideways to see it.",
        );
    }
    let mut p = shown.params;
    let ti = shown.material.is_transversely_isotropic();
    let mut changed = false;
    egui::Grid::new("params").num_columns(2).show(ui, |ui| {
        // An axis spring needs stiffness (the model refuses less than its range); diagonals may be 0.
        let mut row = |ui: &mut egui::Ui, name: &str, v: &mut f64, min: f64| {
            ui.label(name);
            changed |= ui.add(egui::DragValue::new(v).speed(5.0).range(min..=1e6).suffix(" N/m")).changed();
            ui.end_row();
        };
        row(ui, "k1", &mut p.k1, 1e-3);
        row(ui, "k2", &mut p.k2, 1e-3);
        if !ti {
            row(ui, "k3", &mut p.k3, 1e-3);
        }
        for (name, c) in [("c12", &mut p.c12), ("c13", &mut p.c13), ("c23", &mut p.c23), ("b", &mut p.b)] {
            if let Some(v) = c
                && !(ti && name == "c13")
            {
                row(ui, name, v, 0.0);
            }
        }
        // Only the paper's lattice is damped by its nodal d; the others by the damping ratio.
        if p.topology() == Topology::Axis {
            ui.label("d");
            changed |= ui.add(egui::DragValue::new(&mut p.d).speed(0.01).range(0.0..=1e4).suffix(" N s/m")).changed();
            ui.end_row();
        }
    });
    if changed {
        requests.push(Request::EditParams(p));
    }
}
