//! The smallest sufficient model: the cheapest point of the chart that meets an error budget and
//! keeps up with a step rate in real time.

use std::fmt::Write as _;

use super::chart::ChartPoint;

/// Which error the budget bounds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
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
    match &chosen {
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
                mine.iter().filter(|p| ok(p)).count()
            );
        }
        None => {
            let best = mine.iter().map(|p| metric.of(p)).fold(f64::INFINITY, f64::min);
            let _ = write!(
                s,
                "\nNo model meets both budgets. The most accurate point has {best:.4} % {} error; loosen the error \
                 budget or lower the rate.",
                metric.name()
            );
        }
    }
    Choice { chosen, explanation: s }
}
