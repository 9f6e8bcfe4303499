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

use crate::cases::{Bc, CaseSolution, LoadCase, benchmark_cases};
use crate::fem::FemModel;
use crate::grid::Grid;
use crate::material::Material;
use crate::msm::forces::TangentAssembler;
use crate::msm::statics::{NewtonOptions, StaticError, case_dofs, closed_form_axis, solve_newton_with};
use crate::msm::{MsmModel, MsmParams, ParamError, Topology};
use crate::sparse::SparseError;

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

/// The tangent pattern kept in `slot` for `case`'s reduction, built on first use.
fn tangent_for<'w>(
    slot: &'w mut Option<TangentAssembler>,
    model: &MsmModel,
    case: &LoadCase,
) -> Result<&'w mut TangentAssembler, CostError> {
    match slot {
        Some(t) => Ok(t),
        empty => Ok(empty.insert(TangentAssembler::new(model, case_dofs(&model.grid, case))?)),
    }
}

/// Per-thread buffers of the shear model's solves: one tangent pattern per loaded axis, for the
/// static and for the transient cost.
#[derive(Debug, Default)]
pub struct Workspace {
    tangents: [Option<TangentAssembler>; 3],
    transient: [Option<TangentAssembler>; 3],
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
        Ok(Self { material, grid, topology, cases, fem, axial })
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
            super::CostMode::Static => self.cost(params, ws),
            super::CostMode::Transient => {
                let solutions = self.transient_solutions(params, ws)?;
                Ok(crate::accuracy::cost(&solutions, &self.fem))
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

    /// The paper's cost (eq. 1) of `params` with static equilibria, metres.
    pub fn cost(&self, params: &MsmParams, ws: &mut Workspace) -> Result<f64, CostError> {
        params.validate()?;
        if params.topology() == Topology::Axis {
            let k = [params.k1, params.k2, params.k3];
            return Ok((0..self.cases.len()).map(|c| self.axis_cost(c, k[self.cases[c].axis - 1])).sum());
        }
        let solutions = self.static_solutions(params, ws)?;
        Ok(crate::accuracy::cost(&solutions, &self.fem))
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
