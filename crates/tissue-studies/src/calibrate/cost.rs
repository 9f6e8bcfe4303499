//! The calibration cost, the paper's eq. 1: the sum over the 9 clamped cases and all nodes of
//! `|x_msm - x_fem|`, with the FEM references computed once by this program's FEM.
//!
//! Static mode compares static equilibria. For the paper's axis-spring model the equilibrium is
//! closed-form (`msm::statics::closed_form_axis`), so one evaluation is a pass over 9 x 512
//! nodes; the cost then splits into one term per independent stiffness, each a convex function of
//! `1/k` (a sum of norms of affine functions), which [`Problem::axis_optimum`] minimises exactly
//! by golden-section search: the independent optimum the calibration is checked against. For the
//! shear-spring model each case is a mirror-symmetric Newton solve on a quarter of the unknowns,
//! warm-started from the previous force of the same axis, with the sparse pattern and symbolic
//! factorisation kept in a per-thread [`Workspace`].

use crate::mechanics::cases::{Bc, CaseSolution, LoadCase, benchmark_cases};
use crate::mechanics::fem::FemModel;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::msm::forces::TangentAssembler;
use crate::mechanics::msm::statics::{NewtonOptions, StaticError, case_dofs, closed_form_axis, solve_newton_with};
use crate::mechanics::msm::{MsmModel, MsmParams, ParamError, Topology};
use crate::mechanics::sparse::SparseError;
use glam::DVec3;

/// Errors of a cost evaluation or of setting up a calibration problem.
#[derive(Debug, thiserror::Error)]
pub enum CostError {
    /// Invalid MSM parameters.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The static MSM solve failed.
    #[error(transparent)]
    Static(#[from] StaticError),
    /// A sparse factorisation failed.
    #[error(transparent)]
    Sparse(#[from] SparseError),
    /// The touch cases cannot be used.
    #[error("touch cases: {0}")]
    Touch(String),
    /// The local polish failed.
    #[error("polish: {0}")]
    Polish(String),
    /// The settings cannot inform the cost: it would not depend on the parameters, or would not
    /// be the cost the result names ([`super::check_cases`], [`super::check_setup`]).
    #[error("{0}")]
    Uninformative(String),
}

/// The clamped benchmark of one object: FEM references and what the cost needs of them.
#[derive(Debug, Clone)]
pub struct Problem {
    /// The material.
    pub material: Material,
    /// The grid.
    pub grid: Grid,
    /// Which MSM is calibrated.
    pub topology: Topology,
    /// The 9 clamped cases.
    pub cases: Vec<LoadCase>,
    /// Their FEM answers.
    pub fem: Vec<CaseSolution>,
    /// Per case: FEM displacement along the loaded axis, squared transverse displacement, and the
    /// node's lattice index along the loaded axis (closed-form cost of the axis model).
    axial: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)>,
    /// The training cases the static objective uses.
    pub case_set: super::CaseSet,
    /// The touch benchmark's FEM answers, when the objective uses them.
    pub touch: Option<std::sync::Arc<crate::validate::touch::score::Reference>>,
    /// The continuum's training presses and the material's force on each (newtons), when the
    /// objective uses them.
    pub presses: Option<std::sync::Arc<Vec<(crate::validate::continuum::Press, f64)>>>,
    /// The paper cost of a zero displacement (the sum of the FEM's nodal displacement norms),
    /// metres: the scale that makes the paper's cost relative in the combined objective.
    paper_scale: f64,
}

/// A case's answer without support reactions (the cost does not need them).
fn unreacted(case: &LoadCase, displacements: Vec<[f64; 3]>) -> CaseSolution {
    CaseSolution {
        case_id: case.id.clone(),
        axis: case.axis,
        force_n: case.force_n,
        displacements,
        reaction_n: [0.0; 3],
    }
}

/// The lattice of `topology` on `grid` with every stiffness group at 1 N/m: its springs' `k` are
/// the unit shares of each group.
fn unit_lattice(grid: Grid, topology: Topology) -> Result<MsmModel, ParamError> {
    MsmModel::new(grid, MsmParams::unit(topology), 1.0)
}

/// The tangent pattern kept in `slot` for `case`'s reduction, built on first use.
fn tangent_for<'w>(
    slot: &'w mut Option<TangentAssembler>,
    model: &MsmModel,
    case: &LoadCase,
) -> Result<&'w mut TangentAssembler, CostError> {
    match slot {
        Some(t) => Ok(t),
        empty => Ok(empty.insert(TangentAssembler::new(model, case_dofs(model, case))?)),
    }
}

/// Per-thread buffers of the shear model's solves: one tangent pattern per loaded axis, for the
/// static and for the transient cost.
#[derive(Debug, Default)]
pub struct Workspace {
    tangents: [Option<TangentAssembler>; 3],
    transient: [Option<TangentAssembler>; 3],
    touch: Option<crate::validate::touch::score::Responder>,
}

impl Problem {
    /// Solves the FEM references of `material`'s 9 clamped cases on `grid`.
    pub fn new(material: Material, grid: Grid, topology: Topology) -> Result<Self, CostError> {
        let cases = benchmark_cases(&grid, &material.name, Bc::Clamped);
        let fem = FemModel::new(grid, &material).solve_cases(&cases)?;
        let axial = cases
            .iter()
            .zip(&fem)
            .map(|(c, f)| {
                let a = c.axis - 1;
                let ua = f.displacements.iter().map(|u| u[a]).collect();
                let perp = f.displacements.iter().map(|u| u[(a + 1) % 3].powi(2) + u[(a + 2) % 3].powi(2)).collect();
                let idx = (0..grid.num_nodes()).map(|p| grid.ijk(p)[a] as f64).collect();
                (ua, perp, idx)
            })
            .collect();
        let paper_scale = fem.iter().flat_map(|f| &f.displacements).map(|u| DVec3::from(*u).length()).sum();
        Ok(Self {
            material,
            grid,
            topology,
            cases,
            fem,
            axial,
            case_set: super::CaseSet::Paper,
            touch: None,
            presses: None,
            paper_scale,
        })
    }

    /// The MSM of `params` on this grid with this material's density.
    pub fn model(&self, params: &MsmParams) -> Result<MsmModel, ParamError> {
        MsmModel::new(self.grid, *params, self.material.density)
    }

    /// Cost of the axis model's closed form for the cases of one axis at stiffness `k`.
    fn axis_cost(&self, case: usize, k: f64) -> f64 {
        let n = self.grid.n() as f64;
        let s = self.cases[case].force_n / (n * n) / k;
        let (ua, perp, idx) = &self.axial[case];
        ua.iter().zip(perp).zip(idx).map(|((u, q), i)| ((u - i * s).powi(2) + q).sqrt()).sum()
    }

    /// The cost of `params` in `mode`, metres.
    pub fn cost_in(&self, mode: super::CostMode, params: &MsmParams, ws: &mut Workspace) -> Result<f64, CostError> {
        match mode {
            super::CostMode::Static => self.objective(params, ws),
            super::CostMode::Transient => {
                let solutions = self.transient_solutions(params, ws)?;
                Ok(crate::validate::accuracy::cost(&solutions, &self.fem))
            }
        }
    }

    /// MSM states [`super::transient::TRANSIENT_TIME_S`] after the step loads of the 9 cases.
    pub fn transient_solutions(&self, params: &MsmParams, ws: &mut Workspace) -> Result<Vec<CaseSolution>, CostError> {
        let model = self.model(params)?;
        let mut out: Vec<CaseSolution> = Vec::with_capacity(self.cases.len());
        for case in &self.cases {
            let a = case.axis - 1;
            let tangent = tangent_for(&mut ws.transient[a], &model, case)?;
            let prepared = out.last().is_some_and(|prev| prev.axis == case.axis);
            out.push(unreacted(case, super::transient::transient_displacements(&model, case, tangent, prepared)?));
        }
        Ok(out)
    }

    /// This problem using `set` as its training cases (the touch benchmark's FEM answers are
    /// computed here when it needs them). A set that cannot inform the static cost on this lattice
    /// and grid is refused first, before any reference is computed ([`super::check_cases`]).
    pub fn with_cases(mut self, set: super::CaseSet) -> Result<Self, CostError> {
        super::check_cases(set, self.topology, self.grid)?;
        if set == super::CaseSet::Presses {
            let forces = crate::validate::probe::score::training_forces(&self.material)
                .map_err(|e| CostError::Touch(format!("the material's presses: {e:#}")))?;
            self.presses = Some(std::sync::Arc::new(forces));
        } else if set != super::CaseSet::Paper {
            let reference = crate::validate::touch::score::Reference::new(&self.material, self.grid)
                .map_err(|e| CostError::Touch(format!("{e:#}")))?;
            self.touch = Some(std::sync::Arc::new(reference));
        }
        self.case_set = set;
        Ok(self)
    }

    /// The static objective over the training cases of [`Problem::case_set`]: the paper's cost
    /// (metres), the touch cost (dimensionless, [`crate::calibrate::fit`]), or for both the touch
    /// cost plus the paper's cost relative to the FEM's summed nodal displacements.
    pub fn objective(&self, params: &MsmParams, ws: &mut Workspace) -> Result<f64, CostError> {
        match self.case_set {
            super::CaseSet::Paper => self.cost(params, ws),
            super::CaseSet::Touch | super::CaseSet::Both | super::CaseSet::Presses => {
                Ok(self.objective_gradient(params, ws)?.0)
            }
        }
    }

    /// The paper's cost (eq. 1) of `params` with static equilibria, metres.
    pub fn cost(&self, params: &MsmParams, ws: &mut Workspace) -> Result<f64, CostError> {
        params.validate()?;
        if params.topology() == Topology::Axis {
            let k = [params.k1, params.k2, params.k3];
            return Ok((0..self.cases.len()).map(|c| self.axis_cost(c, k[self.cases[c].axis - 1])).sum());
        }
        let solutions = self.static_solutions(params, ws)?;
        Ok(crate::validate::accuracy::cost(&solutions, &self.fem))
    }

    /// The paper's cost of a shear or hex lattice and its exact gradient by each stiffness group
    /// ([`crate::response::linear::GROUP_NAMES`]), by the adjoint of the nonlinear equilibrium: with
    /// `K_t` the tangent at the equilibrium and `g = dC/du`, `dC/dtheta_g = (K_t^-1 g) . phi_g`,
    /// `phi_g` the spring forces of group `g` at unit stiffness. One extra solve per case.
    pub fn paper_gradient(&self, params: &MsmParams, ws: &mut Workspace) -> Result<(f64, [f64; 7]), CostError> {
        params.validate()?;
        let model = self.model(params)?;
        let solutions = self.static_solutions(params, ws)?;
        let unit = unit_lattice(self.grid, self.topology)?;
        let grid = self.grid;
        let nn = grid.num_nodes();
        let (mut cost, mut grad) = (0.0, [0.0; 7]);
        for ((case, sol), fem) in self.cases.iter().zip(&solutions).zip(&self.fem) {
            let fixed = case.fixed_nodes();
            let x: [Vec<f64>; 3] =
                std::array::from_fn(|c| (0..nn).map(|p| grid.position(p)[c] + sol.displacements[p][c]).collect());
            let mut g: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; nn]);
            for p in 0..nn {
                let d: [f64; 3] = std::array::from_fn(|c| sol.displacements[p][c] - fem.displacements[p][c]);
                let norm = DVec3::from(d).length();
                cost += norm;
                if norm > 0.0 && !fixed[p] {
                    for c in 0..3 {
                        g[c][p] = d[c] / norm;
                    }
                }
            }
            let tangent = tangent_for(&mut ws.tangents[case.axis - 1], &model, case)?;
            tangent.assemble(&model, &x, 1.0, 0.0, false, None);
            tangent.system.factor()?;
            let mut rhs = vec![0.0; tangent.dofs.n];
            tangent.dofs.fold(&g, &mut rhs);
            tangent.system.solve_in_place(&mut rhs)?;
            let mut mu: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; nn]);
            tangent.dofs.expand_add(&rhs, &mut mu);
            tangent.system.invalidate();
            for s in unit.springs() {
                let group = crate::response::linear::group_of(unit.families[s.family].family);
                let d: [f64; 3] = std::array::from_fn(|c| x[c][s.b] - x[c][s.a]);
                let l = DVec3::from(d).length();
                let coef = s.k * (l - s.rest) / l;
                grad[group] += coef * (0..3).map(|c| d[c] * (mu[c][s.a] - mu[c][s.b])).sum::<f64>();
            }
        }
        Ok((cost, grad))
    }

    /// The static objective ([`Problem::objective`]) and its gradient by each stiffness group.
    pub fn objective_gradient(&self, params: &MsmParams, ws: &mut Workspace) -> Result<(f64, [f64; 7]), CostError> {
        let touch = |ws: &mut Workspace| -> Result<(f64, [f64; 7]), CostError> {
            params.validate()?;
            let reference = self.touch.as_deref().ok_or_else(|| CostError::Touch("no touch reference".into()))?;
            let responder = match &mut ws.touch {
                Some(r) => r,
                empty => empty.insert(crate::calibrate::fit::lattice_responder(reference, self.topology)?),
            };
            let theta = crate::response::linear::group_values(params);
            let (cost, g) =
                crate::calibrate::fit::touch_cost(reference, crate::validate::touch::Set::Training, responder, &theta)?;
            let mut grad = [0.0; 7];
            grad.copy_from_slice(&g);
            Ok((cost, grad))
        };
        let presses = |ws: &mut Workspace| -> Result<(f64, [f64; 7]), CostError> {
            params.validate()?;
            let presses = self.presses.as_deref().ok_or_else(|| CostError::Touch("no presses".into()))?;
            let responder = match &mut ws.touch {
                Some(r) => r,
                empty => empty.insert(crate::validate::touch::score::Responder::new(
                    self.grid,
                    crate::response::linear::GroupedStiffness::lattice(self.grid, self.topology),
                    &[1.0; 7],
                )?),
            };
            let theta = crate::response::linear::group_values(params);
            let (cost, g) = crate::calibrate::fit::press_cost(presses, self.grid, responder, &theta)?;
            let mut grad = [0.0; 7];
            grad.copy_from_slice(&g);
            Ok((cost, grad))
        };
        match self.case_set {
            super::CaseSet::Paper => self.paper_gradient(params, ws),
            super::CaseSet::Touch => touch(ws),
            super::CaseSet::Presses => presses(ws),
            super::CaseSet::Both => {
                let (t, tg) = touch(ws)?;
                let (p, pg) = self.paper_gradient(params, ws)?;
                Ok((t + p / self.paper_scale, std::array::from_fn(|g| tg[g] + pg[g] / self.paper_scale)))
            }
        }
    }

    /// Static MSM answers of the 9 cases (closed form or warm-started symmetric Newton).
    pub fn static_solutions(&self, params: &MsmParams, ws: &mut Workspace) -> Result<Vec<CaseSolution>, CostError> {
        let model = self.model(params)?;
        let mut out: Vec<CaseSolution> = Vec::with_capacity(self.cases.len());
        for case in &self.cases {
            let displacements = match closed_form_axis(&model, case) {
                Some(u) => u,
                None => {
                    let a = case.axis - 1;
                    let tangent = tangent_for(&mut ws.tangents[a], &model, case)?;
                    let first_of_axis = out.last().is_none_or(|prev| prev.axis != case.axis);
                    if first_of_axis {
                        tangent.system.invalidate(); // factorised for other parameters
                    }
                    // Warm start: the previous force of the same axis, scaled.
                    let start: Option<Vec<[f64; 3]>> =
                        out.last().filter(|prev| prev.axis == case.axis && prev.force_n > 0.0).map(|prev| {
                            let r = case.force_n / prev.force_n;
                            prev.displacements.iter().map(|u| u.map(|v| v * r)).collect()
                        });
                    let opts = NewtonOptions { chord: true, ..NewtonOptions::default() };
                    solve_newton_with(&model, case, opts, tangent, start.as_deref())?.0
                }
            };
            out.push(unreacted(case, displacements));
        }
        Ok(out)
    }

    /// The exact minimum of the axis model's static cost, independently of any heuristic: the
    /// cost is a sum of one term per independent stiffness (`k1`, `k2`, `k3`; `k3 = k2` for a
    /// transversely isotropic object), each convex in `1/k`, minimised by golden-section search to
    /// machine precision. Returns `(k1, k2, k3)` and the cost.
    pub fn axis_optimum(&self) -> ([f64; 3], f64) {
        let groups: Vec<Vec<usize>> = if self.material.is_transversely_isotropic() {
            vec![vec![1], vec![2, 3]]
        } else {
            vec![vec![1], vec![2], vec![3]]
        };
        let mut k = [0.0; 3];
        let mut total = 0.0;
        for axes in groups {
            let members: Vec<usize> = (0..self.cases.len()).filter(|&c| axes.contains(&self.cases[c].axis)).collect();
            let cost_t = |t: f64| members.iter().map(|&c| self.axis_cost(c, 1.0 / t)).sum::<f64>();
            // Bracket in t = 1/k: [0, 100 / k*] holds the minimiser for any sensible material.
            let e = [self.material.constants.e1, self.material.constants.e2, self.material.constants.e3][axes[0] - 1];
            let n = self.grid.n() as f64;
            let k_star = e * 0.01 / (n * n * self.grid.h());
            let (mut lo, mut hi) = (0.0f64, 100.0 / k_star);
            let r = (5f64.sqrt() - 1.0) / 2.0;
            let (mut x1, mut x2) = (hi - r * (hi - lo), lo + r * (hi - lo));
            let (mut f1, mut f2) = (cost_t(x1), cost_t(x2));
            for _ in 0..200 {
                if f1 <= f2 {
                    hi = x2;
                    (x2, f2) = (x1, f1);
                    x1 = hi - r * (hi - lo);
                    f1 = cost_t(x1);
                } else {
                    lo = x1;
                    (x1, f1) = (x2, f2);
                    x2 = lo + r * (hi - lo);
                    f2 = cost_t(x2);
                }
            }
            let t = 0.5 * (lo + hi);
            total += cost_t(t);
            for &a in &axes {
                k[a - 1] = 1.0 / t;
            }
        }
        (k, total)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_gradient_matches_finite_differences() {
        let m = Material::object_a();
        let problem = Problem::new(m, Grid::new(4).unwrap(), Topology::Hex).unwrap();
        let params = MsmParams {
            c12: Some(300.0),
            c13: Some(250.0),
            c23: Some(200.0),
            b: Some(150.0),
            ..MsmParams::axis(900.0, 800.0, 700.0, 0.0)
        };
        let mut ws = Workspace::default();
        let (c, g) = problem.paper_gradient(&params, &mut ws).unwrap();
        assert!((c - problem.cost(&params, &mut ws).unwrap()).abs() <= 1e-12 * c);
        let theta = crate::response::linear::group_values(&params);
        let scale = g.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for i in 0..7 {
            let h = 1e-5 * theta[i];
            let at = |t: f64| {
                let mut th = theta;
                th[i] = t;
                let p = crate::response::linear::with_group_values(&params, &th);
                problem.cost(&p, &mut Workspace::default()).unwrap()
            };
            let fd = (at(theta[i] + h) - at(theta[i] - h)) / (2.0 * h);
            assert!((fd - g[i]).abs() <= 1e-4 * scale, "{i}: {fd} vs {}", g[i]);
        }
    }
}
