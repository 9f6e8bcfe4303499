//! Panel section "Calibration (GA+SA)": settings, Calibrate / Cancel / Apply, progress and the
//! run's curves (best cost; mean and standard deviation of fitness).

use egui_plot::{Line, PlotPoints};

use crate::app::state::{Request, Shown, ViewSettings};
use crate::calibrate::{CalibrationResult, CaseSet, GeneSpace, GenerationStats, Method};

/// Draws the section.
pub fn show(ui: &mut egui::Ui, settings: &mut ViewSettings, shown: &Shown, requests: &mut Vec<Request>) {
    ui.horizontal(|ui| {
        ui.selectable_value(&mut settings.calib_method, Method::Hybrid, "hybrid");
        ui.selectable_value(&mut settings.calib_method, Method::Ga, "GA");
        ui.selectable_value(&mut settings.calib_method, Method::Sa, "SA");
        ui.selectable_value(&mut settings.calib_method, Method::StiffnessFit, "stiffness fit");
    });
    ui.horizontal(|ui| {
        ui.label("training cases");
        ui.selectable_value(&mut settings.calib_cases, CaseSet::Touch, "touch");
        ui.selectable_value(&mut settings.calib_cases, CaseSet::Paper, "paper");
        ui.selectable_value(&mut settings.calib_cases, CaseSet::Both, "both");
        ui.selectable_value(&mut settings.calib_cases, CaseSet::Presses, "material presses");
    });
    ui.horizontal(|ui| {
        ui.label("seed");
        ui.add(egui::DragValue::new(&mut settings.calib_seed));
        ui.label("population");
        ui.add(egui::DragValue::new(&mut settings.calib_population).range(2..=500));
        ui.label("generations");
        ui.add(egui::DragValue::new(&mut settings.calib_generations).range(1..=1000));
    });
    ui.horizontal(|ui| {
        if ui.button("Calibrate").clicked() {
            requests.push(Request::StartCalibration);
        }
        if ui.add_enabled(shown.calibrating, egui::Button::new("Cancel")).clicked() {
            requests.push(Request::CancelCalibration);
        }
        if ui.add_enabled(shown.result.is_some(), egui::Button::new("Apply")).clicked() {
            requests.push(Request::ApplyCalibration);
        }
    });
    if shown.calibrating {
        let done = shown.history.last().map_or(0, |s| s.generation);
        ui.add(egui::ProgressBar::new(done as f32 / shown.calib_generations.max(1) as f32).show_percentage());
    }
    if let Some(r) = &shown.calibration {
        result(ui, r, shown);
    }
    if let Some(a) = &shown.applied {
        applied(ui, a, shown);
    }
    if !shown.history.is_empty() {
        let pts = |f: &dyn Fn(&GenerationStats) -> f64| -> PlotPoints<'static> {
            PlotPoints::from(shown.history.iter().map(|s| [s.generation as f64, f(s)]).collect::<Vec<_>>())
        };
        let generations = shown.history.last().map_or(1, |s| s.generation).max(shown.calib_generations) as f64;
        let polished = shown.calibration.as_ref().and_then(|r| r.polish.as_ref().map(|_| r.cost));
        let (unit, _) = crate::calibrate::cost_meaning(shown.calib_cases, crate::calibrate::CostMode::Static);
        let (cost_axis, fitness_axis) = if unit.is_empty() {
            ("best cost".to_owned(), "fitness (1 / cost)".to_owned())
        } else {
            (format!("best cost ({unit})"), format!("fitness (1 / cost, 1/{unit})"))
        };
        super::fitted_plot(ui, "best", "generation", &cost_axis).include_x(generations).show(ui, |p| {
            p.line(Line::new("best cost of the search", pts(&|s| s.best_cost)));
            if let Some(c) = polished {
                p.hline(egui_plot::HLine::new("after the gradient polish", c));
            }
        });
        super::fitted_plot(ui, "fitness", "generation", &fitness_axis).include_x(generations).include_y(0.0).show(
            ui,
            |p| {
                p.line(Line::new("mean fitness", pts(&|s| s.mean_fitness)));
                p.line(Line::new("std of fitness", pts(&|s| s.std_fitness)));
            },
        );
    }
}

/// The result: every gene beside the running model's, the cost it minimised with its unit, and a
/// gene on its bound.
fn result(ui: &mut egui::Ui, r: &CalibrationResult, shown: &Shown) {
    let (unit, meaning) = crate::calibrate::cost_meaning(r.cases, r.cost_mode);
    ui.label(format!(
        "result{}: cost {}{}{unit} ({meaning}), {} evaluations, {:.1} s",
        if r.cancelled { " (cancelled: the best so far)" } else { "" },
        crate::io::num(r.cost),
        if unit.is_empty() { "" } else { " " },
        r.evaluations,
        r.wall_s
    ));
    let bounds = r.bounds.on_bounds(&r.params);
    egui::Grid::new("calibrated_genes").striped(true).show(ui, |ui| {
        ui.label("gene");
        ui.label("result");
        ui.label("running");
        ui.label("");
        ui.end_row();
        for name in r.bounds.names.iter().filter(|n| r.d_identified || n.as_str() != "d") {
            let (Some(v), running) = (GeneSpace::value(&r.params, name), GeneSpace::value(&shown.params, name)) else {
                continue;
            };
            let unit = if name == "d" { "N s/m" } else { "N/m" };
            ui.label(name.as_str());
            ui.label(format!("{} {unit}", crate::io::num(v)));
            ui.label(running.map_or("-".into(), |x| format!("{} {unit}", crate::io::num(x))));
            match bounds.iter().find(|(n, _, _)| n == name) {
                Some((_, _, side)) => {
                    ui.colored_label(egui::Color32::from_rgb(230, 200, 90), format!("on its {side} bound"))
                }
                None => ui.label(""),
            };
            ui.end_row();
        }
    });
    if !r.d_identified {
        ui.label(format!("d: {}", r.d_note));
    }
}

/// After Apply: what changed, the touch validation before and after.
fn applied(ui: &mut egui::Ui, a: &crate::app::state::Applied, shown: &Shown) {
    let score = |s: &crate::sim::shipped::RecordedScores| {
        format!("worst {:.1} %, median {:.1} %", 100.0 * s.worst_force_error, 100.0 * s.median_force_error)
    };
    let before = a.before.as_ref().map_or("not computed".to_owned(), score);
    let after = match (&shown.validation, shown.params == a.to) {
        (_, false) => "edited since".to_owned(),
        (None, true) => "computing...".to_owned(),
        (Some(Ok(s)), true) => score(s),
        (Some(Err(e)), true) => e.clone(),
    };
    let changed: Vec<String> = ["k1", "k2", "k3", "c12", "c13", "c23", "b", "d"]
        .into_iter()
        .filter_map(|n| {
            let (x, y) = (GeneSpace::value(&a.from, n)?, GeneSpace::value(&a.to, n)?);
            (x != y).then(|| format!("{n} {} -> {}", crate::io::num(x), crate::io::num(y)))
        })
        .collect();
    let changed = if changed.is_empty() { "nothing changed".to_owned() } else { changed.join(", ") };
    ui.label(format!(
        "applied ({changed}): the running model's touch validation (its own nodes) before {before}, after {after}"
    ));
}
