//! The local polish after the search: L-BFGS (argmin, More-Thuente line search) on the static
//! objective in `ln theta` of the free stiffness groups, with the objective's exact gradient
//! ([`super::Problem::objective_gradient`]). Working in logarithms keeps every stiffness positive
//! without a box, so the polish reaches an optimum that lies outside the search box and the
//! result reports it ([`super::PolishReport::left_box`]).

use std::cell::RefCell;

use argmin::core::{CostFunction, Executor, Gradient};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;

use crate::calibrate::fit::Groups;
use crate::mechanics::msm::MsmParams;
use crate::response::linear::{group_values, with_group_values};

/// L-BFGS iterations at most.
const MAX_ITERATIONS: u64 = 200;

/// The objective and its gradient by each of the seven stiffness groups.
pub type Objective<'a> = dyn FnMut(&MsmParams) -> Result<(f64, [f64; 7]), String> + 'a;

/// The result of a polish.
#[derive(Debug, Clone, PartialEq)]
pub struct Polished {
    /// The polished parameters (damping unchanged).
    pub params: MsmParams,
    /// Objective at the start.
    pub start_cost: f64,
    /// Objective at the end.
    pub cost: f64,
    /// L-BFGS iterations.
    pub iterations: u64,
}

struct LogProblem<'a, 'b> {
    objective: RefCell<&'b mut Objective<'a>>,
    groups: &'b Groups,
    start: MsmParams,
}

fn clamp_log(s: f64) -> f64 {
    let (lo, hi) = crate::mechanics::msm::model::STIFFNESS_RANGE;
    s.clamp(lo.ln(), hi.ln())
}

/// `start` with the free groups at `exp(s)` (and their ties).
fn params_of(start: &MsmParams, groups: &Groups, s: &[f64]) -> MsmParams {
    let values: Vec<f64> = s.iter().map(|v| clamp_log(*v).exp()).collect();
    with_group_values(start, &groups.expand(&values))
}

impl LogProblem<'_, '_> {
    fn params(&self, s: &[f64]) -> MsmParams {
        params_of(&self.start, self.groups, s)
    }

    fn eval(&self, s: &[f64]) -> Result<(f64, Vec<f64>), argmin::core::Error> {
        let p = self.params(s);
        let (f, g) = (self.objective.borrow_mut())(&p).map_err(argmin::core::Error::msg)?;
        let theta = group_values(&p);
        let reduced = self.groups.reduce(&g);
        Ok((f, reduced.iter().zip(&self.groups.free).map(|(g, &i)| g * theta[i]).collect()))
    }
}

impl CostFunction for LogProblem<'_, '_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, s: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        Ok(self.eval(s)?.0)
    }
}

impl Gradient for LogProblem<'_, '_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, s: &Vec<f64>) -> Result<Vec<f64>, argmin::core::Error> {
        Ok(self.eval(s)?.1)
    }
}

/// Minimises `objective` from `start` over its free stiffness groups (the ties of a transversely
/// isotropic material kept). A diagonal stiffness at zero starts at a thousandth of the
/// softest axis spring (a logarithm needs a positive start).
pub fn polish(
    start: &MsmParams,
    transversely_isotropic: bool,
    objective: &mut Objective<'_>,
) -> Result<Polished, String> {
    let groups = Groups::new(start.topology(), transversely_isotropic);
    let theta0 = group_values(start);
    let floor = theta0[..3].iter().copied().fold(f64::INFINITY, f64::min) * 1e-3;
    let s0: Vec<f64> = groups.free.iter().map(|&g| theta0[g].max(floor).ln()).collect();
    let problem = LogProblem { objective: RefCell::new(objective), groups: &groups, start: *start };
    let first = problem.params(&s0);
    let start_cost = problem.eval(&s0).map_err(|e| e.to_string())?.0;
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), 10)
        .with_tolerance_grad(1e-12)
        .and_then(|s| s.with_tolerance_cost(1e-14))
        .map_err(|e| e.to_string())?;
    let result = Executor::new(problem, solver)
        .configure(|s| s.param(s0).max_iters(MAX_ITERATIONS))
        .run()
        .map_err(|e| format!("L-BFGS: {e}"))?;
    let state = result.state();
    let best = state.best_param.clone();
    let iterations = state.iter;
    let cost = state.best_cost;
    let params = match best {
        Some(s) if cost <= start_cost => params_of(start, &groups, &s),
        _ => first,
    };
    Ok(Polished { params, start_cost, cost: cost.min(start_cost), iterations })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::msm::Topology;

    #[test]
    fn polish_finds_the_minimum_of_a_smooth_objective() {
        // A separable objective with its minimum at theta = (100, 200, 300, 10, 20, 30): the
        // polish gets there from far away, and keeps the transversely isotropic ties.
        let target = [100.0, 200.0, 300.0, 10.0, 20.0, 30.0, 0.0];
        let mut objective = |p: &MsmParams| {
            let t = group_values(p);
            let f = (0..6).map(|g| (t[g] / target[g]).ln().powi(2)).sum::<f64>();
            Ok((f, std::array::from_fn(|g| if g < 6 { 2.0 * (t[g] / target[g]).ln() / t[g] } else { 0.0 })))
        };
        let start = MsmParams::unit(Topology::Shear);
        let p = polish(&start, false, &mut objective).unwrap();
        let t = group_values(&p.params);
        for g in 0..6 {
            assert!((t[g] / target[g] - 1.0).abs() < 1e-6, "{g}: {}", t[g]);
        }
        assert!(p.cost < 1e-12 && p.start_cost > 1.0);
        let tied = polish(&start, true, &mut objective).unwrap().params;
        assert_eq!((tied.k3, tied.c13), (tied.k2, tied.c12));
    }
}
