//! The local polish after the search: L-BFGS (argmin, More-Thuente line search) on the static
//! objective in `ln theta` of the free stiffness groups, with the objective's exact gradient
//! ([`super::Problem::objective_gradient`]), inside a box: the search's ([`polish_within`]), or
//! the whole stiffness range ([`polish`]).
//!
//! The box is kept by projection. An iterate `s` is clamped into the box, `P(s)`, the objective is
//! evaluated there, and outside the box a quadratic wall `mu |s - P(s)|^2` is added (`mu` the
//! starting cost); the gradient stays exact, since a clamped coordinate does not move the
//! objective. Inside the box this is the objective itself, so an optimum inside is reached as
//! without a box. The answer is the clamped best iterate: inside the box by construction. A gene
//! that then lies within [`HOLD`] of a bound, with the gradient pointing out of the box, is set on
//! that bound and held there while the others are polished again (an active set), until the held
//! genes stop changing. [`super::PolishReport::at_bound`] lists the bounds the result lies on.

use std::cell::RefCell;

use argmin::core::{CostFunction, Executor, Gradient};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;

use crate::calibrate::fit::Groups;
use crate::mechanics::msm::MsmParams;
use crate::mechanics::msm::model::STIFFNESS_RANGE;
use crate::response::linear::{group_values, with_group_values};

/// L-BFGS iterations at most, per round of the active set.
const MAX_ITERATIONS: u64 = 200;

/// Distance in `ln k` from a bound within which a gene that the gradient pushes out of the box is
/// set on the bound and held there.
pub const HOLD: f64 = 1e-3;

/// Distance in `ln k` from a bound within which a gene counts as on it (one that the polish set
/// there is on it to rounding).
pub const ON_BOUND: f64 = 1e-9;

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
    /// L-BFGS iterations, over all rounds.
    pub iterations: u64,
}

/// A box `(lo, hi)` of one stiffness group, N/m, as the polish takes it: within
/// [`STIFFNESS_RANGE`] (a lower bound of zero becomes the least stiffness).
pub fn effective_bounds(bounds: (f64, f64)) -> (f64, f64) {
    let (min, max) = STIFFNESS_RANGE;
    (bounds.0.max(min), bounds.1.min(max))
}

/// The objective in `ln theta` of the free groups inside their box: the solver moves the
/// coordinates `moving`, the others stay at `base`.
struct BoxedLog<'a, 'b> {
    objective: RefCell<&'b mut Objective<'a>>,
    groups: &'b Groups,
    start: MsmParams,
    /// The box of each free group, N/m.
    lin: Vec<(f64, f64)>,
    /// Its logarithm.
    log: Vec<(f64, f64)>,
    /// The current point, `ln theta` of each free group, in the box.
    base: Vec<f64>,
    /// The free groups (indices into `groups.free`) the solver moves.
    moving: Vec<usize>,
    /// Weight of the wall outside the box.
    wall: f64,
}

impl BoxedLog<'_, '_> {
    /// `base` with the moving coordinates from the solver's `x`, clamped into the box.
    fn point(&self, x: &[f64]) -> Vec<f64> {
        let mut s = self.base.clone();
        for (&i, &v) in self.moving.iter().zip(x) {
            s[i] = v.max(self.log[i].0).min(self.log[i].1);
        }
        s
    }

    /// The parameters at `s`, each group clamped into its box in N/m too (rounding in `exp`
    /// cannot leave it).
    fn params(&self, s: &[f64]) -> MsmParams {
        let values: Vec<f64> = s.iter().zip(&self.lin).map(|(v, &(lo, hi))| v.exp().max(lo).min(hi)).collect();
        with_group_values(&self.start, &self.groups.expand(&values))
    }

    /// The objective at `s` (in the box) and its gradient by `ln theta` of each free group.
    fn at(&self, s: &[f64]) -> Result<(f64, Vec<f64>), argmin::core::Error> {
        let p = self.params(s);
        let (f, g) = (self.objective.borrow_mut())(&p).map_err(argmin::core::Error::msg)?;
        let theta = group_values(&p);
        let reduced = self.groups.reduce(&g);
        Ok((f, reduced.iter().zip(&self.groups.free).map(|(g, &i)| g * theta[i]).collect()))
    }

    /// The solver's objective at `x`: the objective at the clamped point plus the wall outside
    /// the box, and its exact gradient by the moving coordinates.
    fn eval(&self, x: &[f64]) -> Result<(f64, Vec<f64>), argmin::core::Error> {
        let s = self.point(x);
        let (mut f, g) = self.at(&s)?;
        let mut grad = Vec::with_capacity(x.len());
        for (&i, &v) in self.moving.iter().zip(x) {
            let out = v - s[i];
            if out == 0.0 {
                grad.push(g[i]);
            } else {
                f += self.wall * out * out;
                grad.push(2.0 * self.wall * out);
            }
        }
        Ok((f, grad))
    }

    /// Whether free group `i` at `s` lies within [`HOLD`] of a bound that the gradient `g` (by
    /// `ln theta`) pushes it against.
    fn pushed_out(&self, i: usize, s: &[f64], g: &[f64]) -> bool {
        let (lo, hi) = self.log[i];
        lo < hi && ((s[i] - lo <= HOLD && g[i] > 0.0) || (hi - s[i] <= HOLD && g[i] < 0.0))
    }
}

/// One L-BFGS run on a [`BoxedLog`].
struct Round<'p, 'a, 'b>(&'p BoxedLog<'a, 'b>);

impl CostFunction for Round<'_, '_, '_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, x: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        Ok(self.0.eval(x)?.0)
    }
}

impl Gradient for Round<'_, '_, '_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, x: &Vec<f64>) -> Result<Vec<f64>, argmin::core::Error> {
        Ok(self.0.eval(x)?.1)
    }
}

/// L-BFGS over `problem`'s moving coordinates from its base point: the best point it found,
/// clamped into the box (none if it kept none), and its iterations.
fn lbfgs_round(problem: &BoxedLog<'_, '_>) -> Result<(Option<Vec<f64>>, u64), String> {
    let x0: Vec<f64> = problem.moving.iter().map(|&i| problem.base[i]).collect();
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), 10)
        .with_tolerance_grad(1e-12)
        .and_then(|s| s.with_tolerance_cost(1e-14))
        .map_err(|e| e.to_string())?;
    let result = Executor::new(Round(problem), solver)
        .configure(|s| s.param(x0).max_iters(MAX_ITERATIONS))
        .run()
        .map_err(|e| format!("L-BFGS: {e}"))?;
    let state = result.state();
    Ok((state.best_param.as_ref().map(|x| problem.point(x)), state.iter))
}

/// Minimises `objective` from `start` over its free stiffness groups (the ties of a transversely
/// isotropic material kept) inside `bounds`, one `(lo, hi)` in N/m per group of
/// [`crate::response::linear::GROUP_NAMES`], taken within the stiffness range
/// ([`effective_bounds`]): the answer lies inside them. A diagonal stiffness at zero starts at a
/// thousandth of the softest axis spring (a logarithm needs a positive start), moved into its box.
pub fn polish_within(
    start: &MsmParams,
    transversely_isotropic: bool,
    bounds: &[(f64, f64); 7],
    objective: &mut Objective<'_>,
) -> Result<Polished, String> {
    let groups = Groups::new(start.topology(), transversely_isotropic);
    let theta0 = group_values(start);
    let floor = theta0[..3].iter().copied().fold(f64::INFINITY, f64::min) * 1e-3;
    let lin: Vec<(f64, f64)> = groups.free.iter().map(|&g| effective_bounds(bounds[g])).collect();
    let log: Vec<(f64, f64)> = lin.iter().map(|&(lo, hi)| (lo.ln(), hi.ln())).collect();
    let base: Vec<f64> =
        groups.free.iter().zip(&log).map(|(&g, &(lo, hi))| theta0[g].max(floor).ln().max(lo).min(hi)).collect();
    let mut problem = BoxedLog {
        objective: RefCell::new(objective),
        groups: &groups,
        start: *start,
        lin,
        log,
        base,
        moving: vec![],
        wall: 1.0,
    };
    let (start_cost, mut grad) = problem.at(&problem.base).map_err(|e| e.to_string())?;
    if start_cost.is_finite() && start_cost > 0.0 {
        problem.wall = start_cost;
    }
    let n = groups.free.len();
    let (mut cost, mut iterations, mut held) = (start_cost, 0, vec![false; n]);
    for round in 0..=n {
        problem.moving = (0..n).filter(|&i| !held[i] && problem.log[i].0 < problem.log[i].1).collect();
        if problem.moving.is_empty() {
            break;
        }
        let best = match lbfgs_round(&problem) {
            Ok((best, it)) => {
                iterations += it;
                best
            }
            Err(e) if round == 0 => return Err(e),
            Err(_) => break, // keep what the earlier rounds found
        };
        if let Some(s) = best {
            let (f, g) = problem.at(&s).map_err(|e| e.to_string())?;
            if f <= cost {
                (problem.base, cost, grad) = (s, f, g);
            }
        }
        let next: Vec<bool> = (0..n).map(|i| problem.pushed_out(i, &problem.base, &grad)).collect();
        if next == held {
            break;
        }
        held = next;
        // Set the held genes on their bounds (to first order this lowers the cost).
        let mut s = problem.base.clone();
        for i in (0..n).filter(|&i| held[i]) {
            s[i] = if grad[i] > 0.0 { problem.log[i].0 } else { problem.log[i].1 };
        }
        let (f, g) = problem.at(&s).map_err(|e| e.to_string())?;
        if f <= cost {
            (problem.base, cost, grad) = (s, f, g);
        }
    }
    Ok(Polished { params: problem.params(&problem.base), start_cost, cost, iterations })
}

/// [`polish_within`] the whole stiffness range ([`STIFFNESS_RANGE`]): the optimum without a
/// search box.
pub fn polish(
    start: &MsmParams,
    transversely_isotropic: bool,
    objective: &mut Objective<'_>,
) -> Result<Polished, String> {
    polish_within(start, transversely_isotropic, &[STIFFNESS_RANGE; 7], objective)
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

    #[test]
    fn polish_within_a_box_ends_inside_it_on_the_bounds_that_bind() {
        // The optimum of k1 (100) lies below its box [200, 1000] and that of c12 (50) above its
        // box [1, 20]; k1 starts near its bound. The polish ends inside the box, on those two
        // bounds, with the other groups at their optimum; without the box it reaches 100 and 50.
        let target = [100.0, 200.0, 300.0, 50.0, 20.0, 30.0, 0.0];
        let mut objective = |p: &MsmParams| {
            let t = group_values(p);
            let f = (0..6).map(|g| (t[g] / target[g]).ln().powi(2)).sum::<f64>();
            Ok((f, std::array::from_fn(|g| if g < 6 { 2.0 * (t[g] / target[g]).ln() / t[g] } else { 0.0 })))
        };
        let mut bounds = [STIFFNESS_RANGE; 7];
        bounds[0] = (200.0, 1000.0);
        bounds[3] = (1.0, 20.0);
        let theta0 = [210.0, 150.0, 400.0, 10.0, 10.0, 10.0, 0.0];
        let start = with_group_values(&MsmParams::unit(Topology::Shear), &theta0);
        let p = polish_within(&start, false, &bounds, &mut objective).unwrap();
        let t = group_values(&p.params);
        for g in 0..6 {
            assert!(bounds[g].0 <= t[g] && t[g] <= bounds[g].1, "{g}: {} outside the box", t[g]);
        }
        assert!((t[0] / 200.0 - 1.0).abs() < 1e-9 && (t[3] / 20.0 - 1.0).abs() < 1e-9, "{t:?}");
        for g in [1, 2, 4, 5] {
            assert!((t[g] / target[g] - 1.0).abs() < 1e-6, "{g}: {}", t[g]);
        }
        assert!(p.cost < p.start_cost);
        let free = group_values(&polish(&start, false, &mut objective).unwrap().params);
        assert!((free[0] / 100.0 - 1.0).abs() < 1e-6 && (free[3] / 50.0 - 1.0).abs() < 1e-6, "{free:?}");
    }
}
