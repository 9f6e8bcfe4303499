//! The panel's speed-against-accuracy section: the chart (computed on a background thread or
//! read from a `chart.csv`), its Pareto front, and the choice of the smallest sufficient model.

use egui_plot::{Corner, Legend, MarkerShape, Plot, PlotPoints, Points};

use crate::app::worker::{Slot, State};
use crate::mechanics::object::Object;
use crate::sim::Integrator;
use crate::sim::Model;
use crate::study::chart::{ChartOptions, ChartPoint, compute};
use crate::study::choose::{Budget, Choice, Metric, choose};

const COLOURS: [egui::Color32; 5] = [
    egui::Color32::from_rgb(31, 119, 180),
    egui::Color32::from_rgb(255, 127, 14),
    egui::Color32::from_rgb(44, 160, 44),
    egui::Color32::from_rgb(214, 39, 40),
    egui::Color32::from_rgb(148, 103, 189),
];

enum Message {
    Progress(String),
    Done(Result<Vec<ChartPoint>, String>),
}

/// State of the section.
pub struct StudyPanel {
    points: Vec<ChartPoint>,
    job: Slot<Message>,
    status: String,
    csv_path: String,
    max_error: f64,
    max_force_error: f64,
    bound_static: bool,
    /// Dynamic budgets (period %, damping % of critical), bounded when `bound_dynamic`.
    dynamic: (f64, f64),
    bound_dynamic: bool,
    rate: f64,
    metric: Metric,
    choice: Option<Choice>,
}

impl Default for StudyPanel {
    fn default() -> Self {
        Self {
            points: Vec::new(),
            job: Slot::default(),
            status: String::new(),
            csv_path: "chart/chart.csv".into(),
            max_error: 1.5,
            max_force_error: crate::study::choose::DEFAULT_MAX_FORCE_ERROR_PCT,
            bound_static: false,
            dynamic: (
                100.0 * crate::sim::DEFAULT_DYNAMIC_BUDGET.period,
                100.0 * crate::sim::DEFAULT_DYNAMIC_BUDGET.damping,
            ),
            bound_dynamic: true,
            rate: 1000.0,
            metric: Metric::Max,
            choice: None,
        }
    }
}

impl StudyPanel {
    /// The accuracy budgets: touch force, the paper's cases, dynamics.
    fn budget_rows(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.label("touch force budget");
            ui.add(egui::DragValue::new(&mut self.max_force_error).speed(0.1).range(0.1..=100.0).suffix(" %"));
        });
        ui.horizontal(|ui| {
            ui.checkbox(&mut self.bound_static, "paper cases too");
            ui.add_enabled(
                self.bound_static,
                egui::DragValue::new(&mut self.max_error).speed(0.01).range(0.001..=100.0).suffix(" % of h"),
            );
            ui.selectable_value(&mut self.metric, Metric::Max, "max");
            ui.selectable_value(&mut self.metric, Metric::Avg, "avg");
        });
        ui.horizontal(|ui| {
            ui.checkbox(&mut self.bound_dynamic, "dynamics: period");
            ui.add_enabled(
                self.bound_dynamic,
                egui::DragValue::new(&mut self.dynamic.0).speed(0.1).range(0.01..=100.0).suffix(" %"),
            );
            ui.label("damping");
            ui.add_enabled(
                self.bound_dynamic,
                egui::DragValue::new(&mut self.dynamic.1).speed(0.1).range(0.01..=100.0).suffix(" % of critical"),
            );
        });
    }

    /// Draws the section for `object`; `wake` repaints the UI from the worker thread.
    pub fn ui(&mut self, ui: &mut egui::Ui, object: Object, wake: impl Fn() + Send + Sync + 'static) {
        self.poll();
        ui.horizontal(|ui| {
            let busy = self.job.busy();
            if ui
                .add_enabled(!busy, egui::Button::new("Compute chart"))
                .on_hover_text("every model at 4^3, 8^3 and 16^3 on a background thread (timings share the CPU with the physics thread)")
                .clicked()
            {
                self.start(object, wake);
            }
            if ui.add_enabled(!busy, egui::Button::new("Load CSV")).clicked() {
                match crate::study::read_chart_csv(std::path::Path::new(self.csv_path.trim())) {
                    Ok(p) => {
                        self.status = format!("{} points from {}", p.len(), self.csv_path.trim());
                        self.points = p;
                        self.choice = None;
                    }
                    Err(e) => self.status = format!("{e:#}"),
                }
            }
        });
        ui.horizontal(|ui| {
            ui.label("CSV");
            ui.add(egui::TextEdit::singleline(&mut self.csv_path).desired_width(220.0));
        });
        if !self.status.is_empty() {
            ui.label(&self.status);
        }
        let mine: Vec<&ChartPoint> = self.points.iter().filter(|p| p.object == object).collect();
        if mine.is_empty() {
            ui.label(format!("no chart for object {object} yet"));
            return;
        }
        speed_accuracy_plot(ui, &mine);
        self.budget_rows(ui);
        ui.horizontal(|ui| {
            ui.label("rate");
            ui.add(egui::DragValue::new(&mut self.rate).speed(10.0).range(1.0..=100_000.0).suffix(" Hz"));
            if ui.button("Choose").clicked() {
                let budget = Budget {
                    max_force_error_pct: self.max_force_error,
                    max_error_pct: self.bound_static.then_some(self.max_error),
                    metric: self.metric,
                    rate_hz: self.rate,
                    max_period_error_pct: self.bound_dynamic.then_some(self.dynamic.0),
                    max_damping_error_pct: self.bound_dynamic.then_some(self.dynamic.1),
                    max_probe_error_pct: Some(self.max_force_error),
                };
                self.choice = Some(choose(&self.points, object, &budget));
            }
        });
        if let Some(c) = &self.choice {
            let summary = c.explanation.lines().last().unwrap_or_default();
            ui.label(summary);
            egui::CollapsingHeader::new("all candidates").show(ui, |ui| {
                ui.label(egui::RichText::new(&c.explanation).monospace().size(9.0));
            });
        }
    }

    /// Whether the chart is being computed.
    pub fn busy(&self) -> bool {
        self.job.busy()
    }

    fn start(&mut self, object: Object, wake: impl Fn() + Send + Sync + 'static) {
        let started = self.job.start("chart", wake, move |ctx| {
            // Cancelled (the viewer closing) between points, so that dropping the job is quick.
            let opts = ChartOptions {
                objects: vec![object],
                resolutions: vec![4, 8, 16],
                timing_s: 0.05,
                cancel: Some(ctx.cancel_handle()),
            };
            let result = compute(&opts, &mut |m| {
                ctx.send(Message::Progress(m.to_owned()));
            });
            ctx.send(Message::Done(result.map(|r| r.0).map_err(|e| format!("{e:#}"))));
        });
        match started {
            Ok(()) => self.status = "computing the chart...".into(),
            Err(e) => self.status = format!("{e}"),
        }
    }

    fn poll(&mut self) {
        let (status, points, choice) = (&mut self.status, &mut self.points, &mut self.choice);
        let ended = self.job.poll(|m| match m {
            Message::Progress(m) => *status = m,
            Message::Done(Ok(p)) => {
                *status = format!("chart: {} points", p.len());
                *points = p;
                *choice = None;
            }
            Message::Done(Err(e)) => *status = format!("chart failed: {e}"),
        });
        if let Some(State::Stopped(why)) = ended {
            self.status = format!("the chart thread stopped unexpectedly ({why})");
        }
    }
}

/// The chart: log time per step against log average error, a colour per model, circles explicit,
/// triangles implicit, the Pareto points ringed.
fn speed_accuracy_plot(ui: &mut egui::Ui, mine: &[&ChartPoint]) {
    Plot::new("speed_accuracy")
        .height(240.0)
        .allow_scroll(false)
        .allow_zoom(false)
        .allow_drag(false)
        .legend(Legend::default().position(Corner::LeftBottom).background_alpha(0.6))
        .x_axis_label("log10 wall time per simulated s; circle explicit, triangle implicit")
        .y_axis_label("log10 avg error (% of h)")
        .show(ui, |plot| {
            for (i, kind) in Model::ALL.iter().enumerate() {
                let name = kind.chart_name();
                for (integrator, shape) in
                    [(Integrator::Symplectic, MarkerShape::Circle), (Integrator::Prefactored, MarkerShape::Up)]
                {
                    let pts: Vec<[f64; 2]> = mine
                        .iter()
                        .filter(|p| p.model == *kind && p.integrator == integrator)
                        .map(|p| [p.cost_per_sim_s.log10(), p.avg_err_pct.log10()])
                        .collect();
                    plot.points(
                        // One legend entry per model: circles explicit, triangles implicit.
                        Points::new(name.clone(), PlotPoints::from(pts))
                            .shape(shape)
                            .radius(4.0)
                            .color(COLOURS[i % COLOURS.len()]),
                    );
                }
            }
            // Rings around the Pareto points (a polyline's sharp corners render as spikes
            // without feathering on software adapters).
            let front: Vec<[f64; 2]> =
                mine.iter().filter(|p| p.pareto).map(|p| [p.cost_per_sim_s.log10(), p.avg_err_pct.log10()]).collect();
            plot.points(
                Points::new("Pareto front", PlotPoints::from(front))
                    .shape(MarkerShape::Circle)
                    .filled(false)
                    .radius(7.0)
                    .color(egui::Color32::LIGHT_GRAY),
            );
        });
}
