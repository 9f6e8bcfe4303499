//! The smallest sufficient model: the cheapest point of the chart that meets an error budget and
//! keeps up with a step rate in real time.

use std::fmt::Write as _;

use super::chart::ChartPoint;
use crate::sim::press::Contact;

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

/// `value <= bound` (false for NaN: not scored).
fn within(value: f64, bound: f64) -> bool {
    value <= bound
}

/// The chosen point and a plain-text account of why, from the chart's data.
#[derive(Debug, Clone)]
pub struct Choice {
    /// The cheapest point meeting every budget, if any.
    pub chosen: Option<ChartPoint>,
    /// Every candidate with its verdict, cheapest first, and the reason for the choice.
    pub explanation: String,
}

/// What a model must meet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Budget {
    /// Largest touch force error on the validation set, percent (7: the force JND).
    pub max_force_error_pct: f64,
    /// Largest static error on the paper's cases, % of the paper's h, by `metric` (not bounded
    /// when `None`).
    pub max_error_pct: Option<f64>,
    /// Which static error `max_error_pct` bounds.
    pub metric: Metric,
    /// Largest period error of the fundamental (the integrator's, measured), percent (not
    /// bounded when `None`).
    pub max_period_error_pct: Option<f64>,
    /// Largest damping ratio error of the fundamental, percent of critical (not bounded when
    /// `None`).
    pub max_damping_error_pct: Option<f64>,
    /// Largest probe force error against the material on the validation presses, percent (not
    /// bounded when `None`): met with the model's own node contact, or else with the material's
    /// surface compliance as the probe's contact (whose time is added to the tick).
    pub max_probe_error_pct: Option<f64>,
    /// Real-time step rate, Hz.
    pub rate_hz: f64,
}

/// How a point meets the probe budget: the contact and the time it adds to a tick, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeContact {
    /// The model's own nodes or the material's surface compliance; none without a probe budget.
    pub contact: Option<crate::sim::press::Contact>,
    /// Time added to a tick, s.
    pub tick_s: f64,
}

impl Budget {
    /// Whether `p` is accurate enough: its validation force error (not scored: not accurate
    /// enough) and, where bounded, its static error.
    fn accurate(&self, p: &ChartPoint) -> bool {
        p.force_err_pct <= self.max_force_error_pct
            && self.max_error_pct.is_none_or(|m| self.metric.of(p) <= m)
            && self.max_period_error_pct.is_none_or(|m| p.period_err_pct <= m)
            && self.max_damping_error_pct.is_none_or(|m| p.damping_err_pct <= m)
    }

    /// The cheapest contact with which `p` meets the probe budget, or why none does.
    pub fn probe_contact(&self, p: &ChartPoint) -> Result<ProbeContact, String> {
        let Some(m) = self.max_probe_error_pct else { return Ok(ProbeContact { contact: None, tick_s: 0.0 }) };
        if within(p.probe_err_pct, m) {
            Ok(ProbeContact { contact: Some(Contact::Nodes), tick_s: 0.0 })
        } else if within(p.surface_probe_err_pct, m) && p.surface_probe_tick_s.is_finite() {
            Ok(ProbeContact { contact: Some(Contact::Surface), tick_s: p.surface_probe_tick_s })
        } else if p.probe_err_pct.is_nan() && p.surface_probe_err_pct.is_nan() {
            Err("no probe score".into())
        } else {
            Err(format!(
                "probe force error {:.1} % (nodes), {:.1} % (surface) > {m} %",
                p.probe_err_pct, p.surface_probe_err_pct
            ))
        }
    }

    /// Wall time of a tick of `p` with its probe contact, s (infinite when no contact meets the
    /// probe budget).
    pub fn tick_with_probe_s(&self, p: &ChartPoint) -> f64 {
        self.probe_contact(p).map_or(f64::INFINITY, |c| p.tick_s(self.rate_hz) + c.tick_s)
    }

    fn accuracy_text(&self) -> String {
        let mut s = format!(
            "touch force error <= {} % (validation set, vs the FEM on the same mesh)",
            self.max_force_error_pct
        );
        if let Some(m) = self.max_error_pct {
            s += &format!(
                ", {} nodal error <= {m} % of h (paper's cases, vs {}^3 FEM)",
                self.metric.name(),
                super::chart::REFERENCE_N
            );
        }
        if let Some(m) = self.max_period_error_pct {
            s += &format!(", fundamental period error <= {m} % (time stepping vs the model's own mode)");
        }
        if let Some(m) = self.max_damping_error_pct {
            s += &format!(", damping ratio error <= {m} % of critical");
        }
        if let Some(m) = self.max_probe_error_pct {
            s += &format!(
                ", probe force error <= {m} % (validation presses, vs the material; the model's node contact, or \
                 the material's surface compliance with its time added to the tick)"
            );
        }
        s
    }

    fn why_inaccurate(&self, p: &ChartPoint) -> String {
        if p.force_err_pct.is_nan() {
            "no touch score".to_owned()
        } else if p.force_err_pct > self.max_force_error_pct {
            format!("touch force error {:.1} % > {} %", p.force_err_pct, self.max_force_error_pct)
        } else if let Some(m) = self.max_period_error_pct.filter(|m| !within(p.period_err_pct, *m)) {
            format!("period error {:.2} % > {m} %", p.period_err_pct)
        } else if let Some(m) = self.max_damping_error_pct.filter(|m| !within(p.damping_err_pct, *m)) {
            format!("damping error {:.2} % > {m} % of critical", p.damping_err_pct)
        } else {
            format!("{} error {:.3} % > {} %", self.metric.name(), self.metric.of(p), self.max_error_pct.unwrap_or(0.0))
        }
    }
}

/// Picks, among the points of `object` whose step fits in a tick, the one with the least wall
/// time per real-time tick (`1 / rate_hz`; as many steps of the point's `dt_s` as a tick needs)
/// that meets `budget` and whose tick fits in `1 / rate_hz`. Ties go to less memory.
pub fn choose(points: &[ChartPoint], object: crate::mechanics::object::Object, budget: &Budget) -> Choice {
    let rate_hz = budget.rate_hz;
    let budget_s = 1.0 / rate_hz;
    let mut mine: Vec<&ChartPoint> = points.iter().filter(|p| p.object == object && p.fits_rate(rate_hz)).collect();
    mine.sort_by(|a, b| a.tick_s(rate_hz).total_cmp(&b.tick_s(rate_hz)).then(a.memory_bytes.cmp(&b.memory_bytes)));
    let ok = |p: &ChartPoint| {
        budget.accurate(p) && budget.probe_contact(p).is_ok() && budget.tick_with_probe_s(p) <= budget_s
    };
    let chosen = mine.iter().find(|p| ok(p)).map(|p| (*p).clone());
    let mut s = format!(
        "Budget for object {object}: {}; {rate_hz} Hz (wall time per tick <= {:.1} us, one thread).\n\n",
        budget.accuracy_text(),
        budget_s * 1e6
    );
    let _ = writeln!(
        s,
        "{:<18} {:>4} {:<9} {:>8} {:>8} {:>8} {:>9} {:>9} {:>9} {:>9} {:>9} {:>11} {:>10}  verdict",
        "model",
        "n",
        "stepper",
        "dt ms",
        "force %",
        "probe %",
        "avg %",
        "max %",
        "period %",
        "damping %",
        "substeps",
        "tick us",
        "memory kB"
    );
    for p in &mine {
        let contact = budget.probe_contact(p);
        let tick = p.tick_s(rate_hz) + contact.as_ref().map_or(0.0, |c| c.tick_s);
        let accurate = budget.accurate(p) && contact.is_ok();
        let verdict = match (accurate, tick <= budget_s) {
            (true, true) => match contact {
                Ok(ProbeContact { contact: Some(Contact::Surface), .. }) => {
                    "meets both (probe: the surface compliance)".to_owned()
                }
                _ => "meets both".to_owned(),
            },
            (false, true) if !budget.accurate(p) => format!("too inaccurate ({})", budget.why_inaccurate(p)),
            (false, true) => format!("too inaccurate ({})", contact.err().unwrap_or_default()),
            (true, false) => format!("too slow ({:.1} us > {:.1} us)", tick * 1e6, budget_s * 1e6),
            (false, false) => "too inaccurate and too slow".to_owned(),
        };
        let mark = if chosen.as_ref().is_some_and(|c| c == *p) { " <= chosen" } else { "" };
        let _ = writeln!(
            s,
            "{:<18} {:>4} {:<9} {:>8.4} {:>8.2} {:>8.1} {:>9.4} {:>9.4} {:>9.3} {:>9.3} {:>9} {:>11.2} {:>10.1}  \
             {verdict}{mark}",
            p.model.chart_name(),
            p.n,
            crate::study::chart::integrator_chart_name(p.integrator),
            p.dt_s * 1e3,
            p.force_err_pct,
            p.probe_err_pct,
            p.avg_err_pct,
            p.max_err_pct,
            p.period_err_pct,
            p.damping_err_pct,
            p.substeps(rate_hz),
            tick * 1e6,
            p.memory_bytes as f64 / 1e3
        );
    }
    let meeting = mine.iter().filter(|p| ok(p)).count();
    conclusion(&mut s, chosen.as_ref(), &mine, budget, meeting);
    Choice { chosen, explanation: s }
}

/// The last paragraph of the explanation: the choice, or why nothing meets the budgets and what
/// comes nearest.
fn conclusion(s: &mut String, chosen: Option<&ChartPoint>, mine: &[&ChartPoint], budget: &Budget, meeting: usize) {
    let rate_hz = budget.rate_hz;
    let budget_s = 1.0 / rate_hz;
    match chosen {
        Some(c) => {
            let probe = match budget.probe_contact(c) {
                Ok(ProbeContact { contact: Some(Contact::Nodes), .. }) => {
                    format!("probe force error {:.2} % with its own node contact, ", c.probe_err_pct)
                }
                Ok(ProbeContact { contact: Some(Contact::Surface), tick_s }) => format!(
                    "probe force error {:.2} % with the material's surface compliance as its contact ({:.2} us of \
                     the tick; {:.1} % with its own nodes), ",
                    c.surface_probe_err_pct,
                    tick_s * 1e6,
                    c.probe_err_pct
                ),
                _ => String::new(),
            };
            let _ = write!(
                s,
                "\nChosen: {} at {}^3 with the {} integrator at dt = {:.4} ms: touch force error {:.2} % (budget {} %), \
                 {probe}{} error {:.4} %, period error {:.3} %, damping error {:.3} % of critical, {:.2} us per tick ({} \
                 step(s) of {:.2} us; {:.0} % of the tick budget), {:.1} kB. It is the cheapest per tick of the {} \
                 points that meet both budgets.",
                c.model.chart_name(),
                c.n,
                crate::study::chart::integrator_chart_name(c.integrator),
                c.dt_s * 1e3,
                c.force_err_pct,
                budget.max_force_error_pct,
                budget.metric.name(),
                budget.metric.of(c),
                c.period_err_pct,
                c.damping_err_pct,
                budget.tick_with_probe_s(c) * 1e6,
                c.substeps(rate_hz),
                c.step_s * 1e6,
                100.0 * budget.tick_with_probe_s(c) / budget_s,
                c.memory_bytes as f64 / 1e3,
                meeting
            );
        }
        None => {
            let fast = mine
                .iter()
                .filter(|p| p.tick_s(rate_hz) <= budget_s && !p.force_err_pct.is_nan())
                .min_by(|a, b| a.force_err_pct.total_cmp(&b.force_err_pct));
            let accurate = mine.iter().find(|p| budget.accurate(p) && budget.probe_contact(p).is_ok());
            let _ = write!(s, "\nNo model meets both budgets.");
            if let Some(p) = fast {
                let _ = write!(
                    s,
                    " At {rate_hz} Hz the most accurate where the user touches is {} at {}^3 ({}): {:.2} % touch force \
                     error.",
                    p.model.chart_name(),
                    p.n,
                    crate::study::chart::integrator_chart_name(p.integrator),
                    p.force_err_pct
                );
            }
            if let Some(p) = accurate {
                let _ = write!(
                    s,
                    " Within the accuracy budget the cheapest is {} at {}^3 ({}): {:.1} us per tick against {:.1} us.",
                    p.model.chart_name(),
                    p.n,
                    crate::study::chart::integrator_chart_name(p.integrator),
                    budget.tick_with_probe_s(p) * 1e6,
                    budget_s * 1e6
                );
            }
            let _ = write!(s, " Loosen a budget or lower the rate.");
        }
    }
}

/// The default touch force budget, percent: people tell forces apart at about 7 %.
pub const DEFAULT_MAX_FORCE_ERROR_PCT: f64 = 7.0;

impl Budget {
    /// Checks the budget: positive percentages and a positive rate of at most 1e7 Hz (the
    /// messages name `choose`'s flags).
    pub fn check(&self) -> anyhow::Result<()> {
        let f = self.max_force_error_pct;
        if !(f.is_finite() && f > 0.0) {
            anyhow::bail!("--max-force-error must be a positive percentage, got {}", crate::io::num(f));
        }
        for (flag, value) in [
            ("--max-error", self.max_error_pct),
            ("--max-period-error", self.max_period_error_pct),
            ("--max-damping-error", self.max_damping_error_pct),
        ] {
            if let Some(v) = value
                && !(v.is_finite() && v > 0.0)
            {
                anyhow::bail!("{flag} must be a positive percentage, got {}", crate::io::num(v));
            }
        }
        if let Some(v) = self.max_probe_error_pct
            && !(v.is_finite() && v > 0.0)
        {
            anyhow::bail!("--max-probe-error must be a positive percentage, got {}", crate::io::num(v));
        }
        let rate = self.rate_hz;
        if !(rate.is_finite() && rate > 0.0 && rate <= 1e7) {
            anyhow::bail!("--rate must be a positive rate in Hz (at most 1e7), got {}", crate::io::num(rate));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::fem::dynamics::Formulation;
    use crate::mechanics::msm::Topology;
    use crate::sim::{Integrator, Model};

    // Stand-ins for the four kinds of model the test needs.
    const CHEAP_STIFF: Model = Model::Lattice(Topology::Axis);
    const IMPLICIT: Model = Model::Lattice(Topology::Shear);
    const COARSE: Model = Model::Lattice(Topology::Hex);
    const FINE: Model = Model::Fem(Formulation::Linear);

    fn point(model: Model, integrator: Integrator, step_s: f64, dt_max_s: f64, max_err_pct: f64) -> ChartPoint {
        let force_err_pct = max_err_pct * 3.0;
        let dt_s = if dt_max_s.is_finite() { 0.9 * dt_max_s } else { 1e-3 };
        ChartPoint {
            object: crate::mechanics::object::Object::A,
            model,
            n: 8,
            integrator,
            step_s,
            dt_max_s,
            dt_s,
            cost_per_sim_s: step_s / dt_s,
            dyn_err_pct: max_err_pct,
            tap_err_pct: max_err_pct,
            period_err_pct: max_err_pct / 2.0,
            damping_err_pct: max_err_pct / 4.0,
            pareto_dynamic: false,
            static_s: 0.0,
            memory_bytes: 1000,
            avg_err_pct: max_err_pct / 5.0,
            max_err_pct,
            force_err_pct,
            probe_err_pct: f64::NAN,
            surface_probe_err_pct: f64::NAN,
            surface_probe_tick_s: f64::NAN,
            pareto: false,
        }
    }

    fn budget(max_force_error_pct: f64, rate_hz: f64) -> Budget {
        Budget {
            max_force_error_pct,
            max_error_pct: None,
            metric: Metric::Max,
            rate_hz,
            max_period_error_pct: None,
            max_damping_error_pct: None,
            max_probe_error_pct: None,
        }
    }

    #[test]
    fn picks_the_cheapest_tick_that_meets_both_budgets() {
        let points = vec![
            // 1 us per step but dt_max 0.1 ms: 12 substeps per 1 ms tick = 12 us.
            point(CHEAP_STIFF, Integrator::Symplectic, 1e-6, 1e-4, 1.0),
            // 5 us per step, one step per tick.
            point(IMPLICIT, Integrator::Prefactored, 5e-6, f64::INFINITY, 1.0),
            // Cheapest of all but too inaccurate.
            point(COARSE, Integrator::Symplectic, 1e-7, 1e-2, 3.0),
            // Accurate but too slow.
            point(FINE, Integrator::Prefactored, 2e-3, f64::INFINITY, 0.1),
        ];
        assert_eq!(points[0].substeps(1000.0), 12.0);
        let c = choose(&points, crate::mechanics::object::Object::A, &budget(6.0, 1000.0));
        assert_eq!(c.chosen.map(|p| p.model), Some(IMPLICIT), "{}", c.explanation);
        let c = choose(&points, crate::mechanics::object::Object::A, &budget(1.5, 1000.0));
        assert!(c.chosen.is_none());
        assert!(c.explanation.contains(&format!("cheapest is {}", FINE.chart_name())), "{}", c.explanation);
        // At 10 Hz the fine model's 100 ms implicit step fits its tick.
        let mut points = points;
        points.push(ChartPoint { dt_s: 0.1, cost_per_sim_s: 2e-3 / 0.1, ..points[3].clone() });
        let c = choose(&points, crate::mechanics::object::Object::A, &budget(1.5, 10.0));
        assert_eq!(c.chosen.map(|p| p.model), Some(FINE), "{}", c.explanation);
        // A dynamic budget: the implicit point's period error of 0.5 % fails 0.4 %.
        let c = choose(
            &points,
            crate::mechanics::object::Object::A,
            &Budget { max_period_error_pct: Some(0.4), ..budget(6.0, 1000.0) },
        );
        assert_ne!(c.chosen.as_ref().map(|p| p.model), Some(IMPLICIT), "{}", c.explanation);
        assert!(c.explanation.contains("period error 0.50 % > 0.4 %"), "{}", c.explanation);
        let c = choose(
            &points,
            crate::mechanics::object::Object::A,
            &Budget { max_damping_error_pct: Some(0.2), ..budget(6.0, 1000.0) },
        );
        assert!(c.explanation.contains("damping error 0.25 % > 0.2 % of critical"), "{}", c.explanation);
        // A static bound on the paper's cases as well: the implicit point's 1 % fails 0.5 %.
        let c = choose(
            &points,
            crate::mechanics::object::Object::A,
            &Budget { max_error_pct: Some(0.5), ..budget(6.0, 10.0) },
        );
        assert_eq!(c.chosen.map(|p| p.model), Some(FINE), "{}", c.explanation);
        // A point without a touch score never meets a force budget.
        let mut unscored = points.clone();
        unscored[1].force_err_pct = f64::NAN;
        let c = choose(&unscored, crate::mechanics::object::Object::A, &budget(6.0, 1000.0));
        assert_ne!(c.chosen.map(|p| p.model), Some(IMPLICIT));
        // A probe budget: the implicit point's own contact misses it, the surface compliance
        // meets it for 3 us more per tick (8 us: still in the 1 ms tick) and is chosen so.
        let mut probed = points.clone();
        for p in &mut probed {
            (p.probe_err_pct, p.surface_probe_err_pct, p.surface_probe_tick_s) = (40.0, 5.0, 3e-6);
        }
        let b = Budget { max_probe_error_pct: Some(7.0), ..budget(6.0, 1000.0) };
        let c = choose(&probed, crate::mechanics::object::Object::A, &b);
        assert_eq!(c.chosen.as_ref().map(|p| p.model), Some(IMPLICIT), "{}", c.explanation);
        assert!(c.explanation.contains("surface compliance as its contact (3.00 us"), "{}", c.explanation);
        // A tighter probe budget than either contact meets: nothing is chosen, and it says why.
        probed[1].probe_err_pct = 8.0;
        let c = choose(&probed, crate::mechanics::object::Object::A, &Budget { max_probe_error_pct: Some(4.0), ..b });
        assert!(c.chosen.is_none() && c.explanation.contains("probe force error"), "{}", c.explanation);
    }
}
