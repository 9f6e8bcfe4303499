//! The smallest sufficient model: the cheapest point of the chart that meets an error budget and
//! keeps up with a step rate in real time.

use std::fmt::Write as _;

use super::chart::ChartPoint;

/// Which error the budget bounds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Metric {
    /// The worst node (the default: a budget holds everywhere).
    Max,
    /// The average over nodes (the paper's headline figure).
    Avg,
}

impl Metric {
    fn of(self, p: &ChartPoint) -> f64 {
        match self {
            Metric::Max => p.max_err_pct,
            Metric::Avg => p.avg_err_pct,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Metric::Max => "maximum",
            Metric::Avg => "average",
        }
    }
}

/// The chosen point and a plain-text account of why, from the chart's data.
#[derive(Debug, Clone)]
pub struct Choice {
    /// The cheapest point meeting both budgets, if any.
    pub chosen: Option<ChartPoint>,
    /// Every candidate with its verdict, cheapest first, and the reason for the choice.
    pub explanation: String,
}

/// Picks, among the points of `object`, the one with the least wall time per real-time tick
/// (`1 / rate_hz`; explicit integrators take as many steps of `0.9 dt_max` as a tick needs) whose
/// error (by `metric`, % of the paper's h) is at most `max_error_pct` and whose tick fits in
/// `1 / rate_hz`. Ties go to less memory.
pub fn choose(points: &[ChartPoint], object: &str, max_error_pct: f64, rate_hz: f64, metric: Metric) -> Choice {
    let budget_s = 1.0 / rate_hz;
    let mut mine: Vec<&ChartPoint> = points.iter().filter(|p| p.object == object).collect();
    mine.sort_by(|a, b| a.tick_s(rate_hz).total_cmp(&b.tick_s(rate_hz)).then(a.memory_bytes.cmp(&b.memory_bytes)));
    let ok = |p: &ChartPoint| metric.of(p) <= max_error_pct && p.tick_s(rate_hz) <= budget_s;
    let chosen = mine.iter().find(|p| ok(p)).map(|p| (*p).clone());
    let mut s = format!(
        "Budget for object {object}: {} nodal error <= {max_error_pct} % of h (vs {}^3 FEM), {rate_hz} Hz \
         (wall time per tick <= {:.1} us, one thread).\n\n",
        metric.name(),
        super::chart::REFERENCE_N,
        budget_s * 1e6
    );
    let _ = writeln!(
        s,
        "{:<18} {:>4} {:<9} {:>9} {:>9} {:>9} {:>11} {:>10}  verdict",
        "model", "n", "stepper", "avg %", "max %", "substeps", "tick us", "memory kB"
    );
    for p in &mine {
        let err = metric.of(p);
        let tick = p.tick_s(rate_hz);
        let verdict = match (err <= max_error_pct, tick <= budget_s) {
            (true, true) => "meets both".to_owned(),
            (false, true) => format!("too inaccurate ({err:.3} % > {max_error_pct} %)"),
            (true, false) => format!("too slow ({:.1} us > {:.1} us)", tick * 1e6, budget_s * 1e6),
            (false, false) => "too inaccurate and too slow".to_owned(),
        };
        let mark = if chosen.as_ref().is_some_and(|c| c == *p) { " <= chosen" } else { "" };
        let _ = writeln!(
            s,
            "{:<18} {:>4} {:<9} {:>9.4} {:>9.4} {:>9} {:>11.2} {:>10.1}  {verdict}{mark}",
            p.model,
            p.n,
            p.integrator,
            p.avg_err_pct,
            p.max_err_pct,
            p.substeps(rate_hz),
            tick * 1e6,
            p.memory_bytes as f64 / 1e3
        );
    }
    let meeting = mine.iter().filter(|p| ok(p)).count();
    conclusion(&mut s, chosen.as_ref(), &mine, (max_error_pct, rate_hz, metric), meeting);
    Choice { chosen, explanation: s }
}

/// The last paragraph of the explanation: the choice, or why nothing meets the budgets and what
/// comes nearest.
fn conclusion(
    s: &mut String,
    chosen: Option<&ChartPoint>,
    mine: &[&ChartPoint],
    (max_error_pct, rate_hz, metric): (f64, f64, Metric),
    meeting: usize,
) {
    let budget_s = 1.0 / rate_hz;
    match chosen {
        Some(c) => {
            let _ = write!(
                s,
                "\nChosen: {} at {}^3 with the {} integrator: {} error {:.4} % (budget {max_error_pct} %), {:.2} us per tick \
                 ({} step(s) of {:.2} us; {:.0} % of the tick budget), {:.1} kB. It is the cheapest per tick of the {} \
                 points that meet both budgets.",
                c.model,
                c.n,
                c.integrator,
                metric.name(),
                metric.of(c),
                c.tick_s(rate_hz) * 1e6,
                c.substeps(rate_hz),
                c.step_s * 1e6,
                100.0 * c.tick_s(rate_hz) / budget_s,
                c.memory_bytes as f64 / 1e3,
                meeting
            );
        }
        None => {
            let fast = mine
                .iter()
                .filter(|p| p.tick_s(rate_hz) <= budget_s)
                .min_by(|a, b| metric.of(a).total_cmp(&metric.of(b)));
            let accurate = mine.iter().find(|p| metric.of(p) <= max_error_pct);
            let _ = write!(s, "\nNo model meets both budgets.");
            if let Some(p) = fast {
                let _ = write!(
                    s,
                    " At {rate_hz} Hz the most accurate is {} at {}^3 ({}): {:.4} % {} error.",
                    p.model,
                    p.n,
                    p.integrator,
                    metric.of(p),
                    metric.name()
                );
            }
            if let Some(p) = accurate {
                let _ = write!(
                    s,
                    " Within {max_error_pct} % the cheapest is {} at {}^3 ({}): {:.1} us per tick against {:.1} us.",
                    p.model,
                    p.n,
                    p.integrator,
                    p.tick_s(rate_hz) * 1e6,
                    budget_s * 1e6
                );
            }
            let _ = write!(s, " Loosen the error budget or lower the rate.");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::dynamics::Formulation;
    use crate::msm::Topology;
    use crate::study::chart::{ChartIntegrator, ModelKind};

    // Stand-ins for the four kinds of model the test needs.
    const CHEAP_STIFF: ModelKind = ModelKind::Msm(Topology::Axis);
    const IMPLICIT: ModelKind = ModelKind::Msm(Topology::Shear);
    const COARSE: ModelKind = ModelKind::Msm(Topology::Hex);
    const FINE: ModelKind = ModelKind::Fem(Formulation::Linear);

    fn point(
        model: ModelKind,
        integrator: ChartIntegrator,
        step_s: f64,
        dt_max_s: f64,
        max_err_pct: f64,
    ) -> ChartPoint {
        ChartPoint {
            object: "A".into(),
            model,
            n: 8,
            integrator,
            step_s,
            dt_max_s,
            static_s: 0.0,
            memory_bytes: 1000,
            avg_err_pct: max_err_pct / 5.0,
            max_err_pct,
            pareto: false,
        }
    }

    #[test]
    fn picks_the_cheapest_tick_that_meets_both_budgets() {
        let points = vec![
            // 1 us per step but dt_max 0.1 ms: 12 substeps per 1 ms tick = 12 us.
            point(CHEAP_STIFF, ChartIntegrator::Explicit, 1e-6, 1e-4, 1.0),
            // 5 us per step, one step per tick.
            point(IMPLICIT, ChartIntegrator::Implicit, 5e-6, f64::INFINITY, 1.0),
            // Cheapest of all but too inaccurate.
            point(COARSE, ChartIntegrator::Explicit, 1e-7, 1e-2, 3.0),
            // Accurate but too slow.
            point(FINE, ChartIntegrator::Implicit, 2e-3, f64::INFINITY, 0.1),
        ];
        assert_eq!(points[0].substeps(1000.0), 12.0);
        let c = choose(&points, "A", 2.0, 1000.0, Metric::Max);
        assert_eq!(c.chosen.map(|p| p.model), Some(IMPLICIT), "{}", c.explanation);
        let c = choose(&points, "A", 0.5, 1000.0, Metric::Max);
        assert!(c.chosen.is_none());
        assert!(c.explanation.contains(&format!("cheapest is {FINE}")), "{}", c.explanation);
        // At 10 Hz the fine model fits its tick.
        let c = choose(&points, "A", 0.5, 10.0, Metric::Max);
        assert_eq!(c.chosen.map(|p| p.model), Some(FINE));
    }
}
