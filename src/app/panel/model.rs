//! Panel section "Object and model": the object (a preset or a material file), the lattice, and
//! its parameters, edited live.

use crate::app::state::{Request, Shown, ViewSettings};
use crate::msm::Topology;

/// Draws the section.
pub fn show(ui: &mut egui::Ui, settings: &mut ViewSettings, shown: &Shown, requests: &mut Vec<Request>) {
    let mut reload = false;
    ui.horizontal(|ui| {
        for o in ["A", "B", "file"] {
            reload |= ui.selectable_value(&mut settings.object, o.to_owned(), o).changed();
        }
    });
    if settings.object == "file" {
        ui.horizontal(|ui| {
            ui.text_edit_singleline(&mut settings.material_path);
            reload |= ui.button("Load").clicked();
        });
        reload &= !settings.material_path.trim().is_empty();
    }
    if reload {
        requests.push(Request::LoadObject);
    }
    let mut topology = shown.topology();
    ui.horizontal_wrapped(|ui| {
        let mut pick = |ui: &mut egui::Ui, t: Topology, label: &str| {
            if ui.selectable_value(&mut topology, t, label).changed() {
                requests.push(Request::SelectTopology(t));
            }
        };
        pick(ui, Topology::Shear, "shear springs (default)");
        pick(ui, Topology::Hex, "hex lattice");
        pick(ui, Topology::Axis, "paper: axis springs");
    });
    if topology == Topology::Axis {
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
        ui.label("d");
        changed |= ui.add(egui::DragValue::new(&mut p.d).speed(0.01).range(0.0..=1e4).suffix(" N s/m")).changed();
        ui.end_row();
    });
    if changed {
        requests.push(Request::EditParams(p));
    }
}
