//! SVG charts of the study (plotters): static and dynamic error against cost per simulated
//! second with their Pareto fronts, and
//! the measured against the analytic critical time step.

use crate::mechanics::object::Object;
use plotters::prelude::*;

use super::ChartPoint;
use crate::sim::{Integrator, Model};
use crate::study::stability::StabilityPoint;

const COLOURS: [RGBColor; 5] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
];

fn err(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("plot: {e}")
}

fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (mut lo, mut hi) = (f64::MAX, f64::MIN_POSITIVE);
    for v in values.filter(|v| v.is_finite() && *v > 0.0) {
        (lo, hi) = (lo.min(v), hi.max(v));
    }
    if lo > hi {
        (lo, hi) = (1e-6, 1.0);
    }
    (lo / 1.5)..(hi * 1.5)
}

/// Which error a speed-accuracy chart plots, and its Pareto front.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// Static error on the paper's cases (average, % of h).
    Static,
    /// Dynamic error: the trajectory error against the FEM's transients (%, 8^3 only).
    Dynamic,
}

impl Axis {
    fn of(self, p: &ChartPoint) -> f64 {
        match self {
            Axis::Static => p.avg_err_pct,
            Axis::Dynamic => p.dyn_err_pct,
        }
    }

    fn on_front(self, p: &ChartPoint) -> bool {
        match self {
            Axis::Static => p.pareto,
            Axis::Dynamic => p.pareto_dynamic,
        }
    }

    fn describe(self) -> (&'static str, &'static str) {
        match self {
            Axis::Static => (
                "Cost per simulated second against static error (circle: explicit at 0.9 of its critical step, \
                 triangle: implicit; label: nodes per axis or step)",
                "average static error vs fine FEM, % of h",
            ),
            Axis::Dynamic => (
                "Cost per simulated second against dynamic error (8^3; circle: explicit at 0.9 of its critical step, \
                 triangle: implicit, label: step in ms)",
                "trajectory error vs converged FEM transients, %",
            ),
        }
    }
}

/// `axis`'s error (log) against wall time per simulated second (log), one panel per object:
/// colour = model, circle = explicit, triangle = implicit, the Pareto front joined.
pub fn speed_accuracy_svg(points: &[ChartPoint], models: &[Model], axis: Axis) -> anyhow::Result<String> {
    let points: Vec<ChartPoint> = points.iter().filter(|p| axis.of(p).is_finite()).cloned().collect();
    let points = &points[..];
    let (title, y_desc) = axis.describe();
    let mut objects: Vec<Object> = points.iter().map(|p| p.object).collect();
    objects.dedup();
    crate::study::font::register().map_err(anyhow::Error::msg)?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (620 * objects.len().max(1) as u32, 520)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let root = root.titled(title, ("sans-serif", 14)).map_err(err)?;
        let x_range = log_range(points.iter().map(|p| p.cost_per_sim_s));
        let y_range = log_range(points.iter().map(|p| axis.of(p)));
        for (area, object) in root.split_evenly((1, objects.len().max(1))).iter().zip(&objects) {
            let mut chart = ChartBuilder::on(area)
                .caption(format!("object {object}"), ("sans-serif", 16))
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(70)
                .build_cartesian_2d(x_range.clone().log_scale(), y_range.clone().log_scale())
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("wall time per simulated second, s (one thread)")
                .y_desc(y_desc)
                .x_label_formatter(&|v| format!("{v:.0e}"))
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .draw()
                .map_err(err)?;
            let mine: Vec<&ChartPoint> = points.iter().filter(|p| p.object == *object).collect();
            let mut front: Vec<(f64, f64)> =
                mine.iter().filter(|p| axis.on_front(p)).map(|p| (p.cost_per_sim_s, axis.of(p))).collect();
            front.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(front, BLACK.stroke_width(1)))
                .map_err(err)?
                .label("Pareto front")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(1)));
            for (i, model) in models.iter().enumerate() {
                let colour = COLOURS[i % COLOURS.len()];
                let of_model: Vec<&&ChartPoint> = mine.iter().filter(|p| p.model == *model).collect();
                chart
                    .draw_series(of_model.iter().map(|p| {
                        let at = (p.cost_per_sim_s, axis.of(p));
                        let style = if axis.on_front(p) { colour.filled() } else { colour.stroke_width(2) };
                        let marker: DynElement<'_, SVGBackend<'_>, (f64, f64)> =
                            if p.integrator == Integrator::Symplectic {
                                Circle::new(at, 5, style).into_dyn()
                            } else {
                                TriangleMarker::new(at, 6, style).into_dyn()
                            };
                        marker
                    }))
                    .map_err(err)?
                    .label(model.chart_name())
                    .legend(move |(x, y)| Circle::new((x + 8, y), 5, colour.filled()));
                chart
                    .draw_series(of_model.iter().map(|p| {
                        let label = match (axis, p.integrator) {
                            (Axis::Static, Integrator::Symplectic) => format!("{}", p.n),
                            (Axis::Static, Integrator::Prefactored | Integrator::Implicit | Integrator::Newmark) => {
                                String::new()
                            }
                            (Axis::Dynamic, _) => format!("{:.2}", p.dt_s * 1e3),
                        };
                        Text::new(label, (p.cost_per_sim_s, axis.of(p)), ("sans-serif", 10).into_font())
                    }))
                    .map_err(err)?;
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerLeft)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(err)?;
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// Measured critical dt against `2 / omega_max`, log-log, with the line of equality.
pub fn stability_svg(points: &[StabilityPoint]) -> anyhow::Result<String> {
    crate::study::font::register().map_err(anyhow::Error::msg)?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (640, 520)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let range = log_range(points.iter().flat_map(|p| [p.dt_analytic_s, p.dt_measured_s]));
        let mut chart = ChartBuilder::on(&root)
            .caption("Explicit critical time step: bisection vs 2 / omega_max", ("sans-serif", 17))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(range.clone().log_scale(), range.clone().log_scale())
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("2 / omega_max, s (Lanczos on M^-1 K)")
            .y_desc("measured dt_crit, s (bisection)")
            .x_label_formatter(&|v| format!("{v:.0e}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(err)?;
        chart
            .draw_series(LineSeries::new([(range.start, range.start), (range.end, range.end)], BLACK.stroke_width(1)))
            .map_err(err)?
            .label("equal")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(1)));
        let mut models: Vec<Model> = points.iter().map(|p| p.model).collect();
        models.dedup();
        for (i, model) in models.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            chart
                .draw_series(
                    points
                        .iter()
                        .filter(|p| p.model == *model)
                        .map(|p| Circle::new((p.dt_analytic_s, p.dt_measured_s), 5, colour.filled())),
                )
                .map_err(err)?
                .label(model.chart_name())
                .legend(move |(x, y)| Circle::new((x + 8, y), 5, colour.filled()));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}
