//! Two studies of the hex lattice on the touch benchmark (`cargo run --release --example
//! touch_studies`):
//!
//! 1. Does a separate stiffness class for the surface springs lift its touch accuracy? Each of
//!    the seven stiffness groups is split into springs with both ends on the cube's surface and
//!    the rest (14 groups, no ties), fitted to the touch training cases by L-BFGS in `ln k` from
//!    the shipped tissue, and scored on the validation set. (Measured: the training cost drops,
//!    the validation error rises; not kept.)
//! 2. Its lowest six frequencies with equal node masses (the paper's mass model) and with
//!    element-lumped masses (the hex lattice's own, as the FEM's).

use argmin::core::{CostFunction, Executor, Gradient};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use std::cell::RefCell;
use tissue_sim::calibrate::fit::touch_cost;
use tissue_sim::mechanics::grid::Grid;
use tissue_sim::mechanics::material::Material;
use tissue_sim::mechanics::msm::Topology;
use tissue_sim::response::linear::{GroupedStiffness, group_of, group_values};
use tissue_sim::validate::touch::Set;
use tissue_sim::validate::touch_score::Reference;
use tissue_sim::validate::touch_score::{Responder, case_score};

fn on_surface(grid: &Grid, p: usize) -> bool {
    grid.ijk(p).iter().any(|&c| c == 0 || c == grid.n() - 1)
}

/// The hex lattice's rest stiffness with 14 groups: group `g` inside, `g + 7` on the surface.
fn split_lattice(grid: Grid) -> GroupedStiffness {
    GroupedStiffness::lattice_grouped(grid, Topology::Hex, 14, |s, family| {
        group_of(family) + if on_surface(&grid, s.a) && on_surface(&grid, s.b) { 7 } else { 0 }
    })
}

struct Problem<'a> {
    reference: &'a Reference,
    responder: RefCell<Responder>,
}

impl Problem<'_> {
    /// Touch cost over `set` and its gradient by `ln theta`.
    fn eval(&self, s: &[f64], set: Set) -> (f64, Vec<f64>) {
        let theta: Vec<f64> = s.iter().map(|v| v.exp()).collect();
        let (cost, grad) =
            touch_cost(self.reference, set, &mut self.responder.borrow_mut(), &theta).expect("touch cost");
        (cost, grad.iter().zip(&theta).map(|(g, t)| g * t).collect())
    }

    fn worst_validation(&self, s: &[f64]) -> f64 {
        let theta: Vec<f64> = s.iter().map(|v| v.exp()).collect();
        let mut r = self.responder.borrow_mut();
        r.set_theta(&theta).expect("factorises");
        let h = self.reference.grid.h();
        let mut worst = 0.0f64;
        for (case, fem) in self.reference.cases.iter().zip(&self.reference.answers) {
            if case.set == Set::Validation {
                let (answer, _) = r.answer(case).expect("solves");
                worst = worst.max((1.0 - case_score(case, &answer, fem, h).compliance_ratio).abs());
            }
        }
        worst
    }
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, s: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        Ok(self.eval(s, Set::Training).0)
    }
}

impl Gradient for Problem<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, s: &Vec<f64>) -> Result<Vec<f64>, argmin::core::Error> {
        Ok(self.eval(s, Set::Training).1)
    }
}

fn main() -> anyhow::Result<()> {
    let grid = Grid::paper();
    for m in [Material::object_a(), Material::object_b()] {
        let reference = Reference::new(&m, grid)?;
        let shipped = tissue_sim::sim::shipped::tissue_params(&m, Topology::Hex)?;
        let t = group_values(&shipped);
        let s0: Vec<f64> = (0..14).map(|g| t[g % 7].ln()).collect();
        let responder = Responder::new(grid, split_lattice(grid), &[1.0; 14])?;
        let problem = Problem { reference: &reference, responder: RefCell::new(responder) };
        let before = (problem.eval(&s0, Set::Training).0, problem.worst_validation(&s0));
        let solver =
            LBFGS::new(MoreThuenteLineSearch::new(), 10).with_tolerance_grad(1e-12)?.with_tolerance_cost(1e-14)?;
        let result = Executor::new(problem, solver).configure(|st| st.param(s0).max_iters(300)).run()?;
        let best = result.state().best_param.clone().unwrap_or_default();
        let problem = result.problem.problem.as_ref().expect("problem");
        let after = (problem.eval(&best, Set::Training).0, problem.worst_validation(&best));
        println!(
            "object {}: shipped hex: training cost {:.5}, worst validation force error {:.1} %; with surface classes: \
             training cost {:.5}, worst validation force error {:.1} %",
            m.name,
            before.0,
            100.0 * before.1,
            after.0,
            100.0 * after.1
        );
        let k: Vec<String> = best.iter().map(|v| format!("{:.1}", v.exp())).collect();
        println!("  groups (k1..b inside, then on the surface): {}", k.join(", "));
        // The shipped lattice's modes with equal node masses and with element-lumped ones.
        let mut r = Responder::new(grid, GroupedStiffness::lattice(grid, Topology::Hex), &t)?;
        let fixed = tissue_sim::response::linear::scene_fixed_dofs(&grid);
        let node_mass = m.density * tissue_sim::mechanics::grid::CUBE_SIDE_M.powi(3) / grid.num_nodes() as f64;
        let equal: Vec<f64> = fixed.iter().map(|&f| if f { 0.0 } else { node_mass }).collect();
        let nodal = tissue_sim::mechanics::msm::model::lumped_masses(&grid, m.density);
        let lumped: Vec<f64> = fixed.iter().enumerate().map(|(d, &f)| if f { 0.0 } else { nodal[d / 3] }).collect();
        for (name, mass) in [("equal node masses", &equal), ("element-lumped masses", &lumped)] {
            let hz = tissue_sim::response::modes::lowest_frequencies_hz(&mut r.solver, mass, 6)?;
            let worst = hz.iter().zip(&reference.modes_hz).map(|(a, b)| (1.0 - a / b).abs()).fold(0.0, f64::max);
            println!("  shipped hex with {name}: worst frequency error {:.1} %", 100.0 * worst);
        }
    }
    Ok(())
}
