//! Panel section "Calibration (GA+SA)": settings, Calibrate / Cancel / Apply, progress and the
//! run's curves (best cost; mean and standard deviation of fitness).

use egui_plot::{Line, PlotPoints};

use crate::app::state::{Request, Shown, ViewSettings};
use crate::calibrate::{CaseSet, GenerationStats, Method};

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
    if let Some(p) = &shown.result {
        ui.label(format!("result: k = ({:.1}, {:.1}, {:.1}), d = {:.3}", p.k1, p.k2, p.k3, p.d));
    }
    if !shown.history.is_empty() {
        let pts = |f: &dyn Fn(&GenerationStats) -> f64| -> PlotPoints<'static> {
            PlotPoints::from(shown.history.iter().map(|s| [s.generation as f64, f(s)]).collect::<Vec<_>>())
        };
        let generations = shown.history.last().map_or(1, |s| s.generation).max(shown.calib_generations) as f64;
        super::fitted_plot(ui, "best", "generation", "best cost").include_x(generations).show(ui, |p| {
            p.line(Line::new("best cost", pts(&|s| s.best_cost)));
        });
        super::fitted_plot(ui, "fitness", "generation", "fitness (1 / cost)")
            .include_x(generations)
            .include_y(0.0)
            .show(ui, |p| {
                p.line(Line::new("mean fitness", pts(&|s| s.mean_fitness)));
                p.line(Line::new("std of fitness", pts(&|s| s.std_fitness)));
            });
    }
}
