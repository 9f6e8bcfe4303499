//! Linear static finite elements: the reference the mass-spring model is calibrated against.
//!
//! Hex8 elements with full 2x2x2 Gauss integration ([`element`]); every element of the
//! structured cube is identical, so one element matrix serves them all, the background's; the
//! elements a material's inclusions meet add their change ([`inclusions`]). Fixed degrees of freedom
//! are eliminated, the reduced stiffness is factorised once per constraint set with faer's sparse
//! Cholesky (symbolic analysis kept), and every solve is followed by iterative refinement on the
//! element-by-element residual so that answers sit at round-off.
//!
//! [`clamped`]: the clamped cases by symmetry; [`stencil`]: the linear FEM's `K u` as a stencil;
//! [`corotation`]: the corotated element force; [`dynamics`]: lumped masses, damping and the steps;
//! [`graded`]: meshes graded around a contact; [`inclusions`]: the elements an inclusion meets.

pub mod clamped;
pub mod corotation;
pub mod dynamics;
pub mod element;
pub mod graded;
pub mod inclusions;
pub mod stencil;

use crate::mechanics::cases::{CaseSolution, LoadCase};
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::sparse::{SparseError, SpdSystem};
use element::{ElementStiffness, hex8_stiffness};

/// Steps of iterative refinement after each direct solve.
const REFINEMENT_STEPS: usize = 2;

/// A linear elastic hex8 model of the cube.
#[derive(Debug, Clone)]
pub struct FemModel {
    /// The grid.
    pub grid: Grid,
    /// The background's element stiffness, shared by every element (those an inclusion meets add
    /// their change, [`FemModel::patch`]).
    pub ke: ElementStiffness,
    /// The material stiffness `C` (Voigt).
    pub material: nalgebra::Matrix6<f64>,
    elements: Vec<[usize; 8]>,
    stencil: stencil::Stencil,
    /// The elements the material's inclusions meet, with their change of stiffness.
    patch: Vec<inclusions::PatchedElement>,
}

impl FemModel {
    /// The elements' node lists (spec node order).
    pub fn elements(&self) -> &[[usize; 8]] {
        &self.elements
    }

    /// The elements the material's inclusions meet and their change of stiffness (empty for a
    /// homogeneous material).
    pub fn patch(&self) -> &[inclusions::PatchedElement] {
        &self.patch
    }

    /// The lower-triangle entries `(row, col)` of every element matrix over global dofs, with
    /// their values (duplicates add up at assembly), the inclusions' changes too.
    pub fn stiffness_entries(&self) -> (Vec<(usize, usize)>, Vec<f64>) {
        let mut entries = Vec::with_capacity((self.elements.len() + self.patch.len()) * 300);
        let mut values = Vec::with_capacity(entries.capacity());
        let blocks = self.elements.iter().map(|n| (n, &self.ke)).chain(self.patch.iter().map(|e| (&e.nodes, &e.delta)));
        for (nodes, ke) in blocks {
            let dof = |l: usize| 3 * nodes[l / 3] + l % 3;
            for a in 0..24 {
                for b in 0..=a {
                    entries.push((dof(a), dof(b)));
                    values.push(ke[(a, b)]);
                }
            }
        }
        (entries, values)
    }

    /// The largest eigenvalue of any element's matrix (the background's, or one an inclusion
    /// meets), N/m.
    pub fn stiffest_element(&self) -> f64 {
        let largest = |k: &element::ElementStiffness| k.symmetric_eigenvalues().max();
        self.patch.iter().map(|e| largest(&(self.ke + e.delta))).fold(largest(&self.ke), f64::max)
    }

    /// The assembled stiffness as a dense matrix (small grids, for tests against dense solves).
    #[cfg(test)]
    pub fn dense_stiffness(&self) -> nalgebra::DMatrix<f64> {
        let dofs = 3 * self.grid.num_nodes();
        let mut k = nalgebra::DMatrix::<f64>::zeros(dofs, dofs);
        let (entries, values) = self.stiffness_entries();
        for (&(r, c), v) in entries.iter().zip(&values) {
            k[(r, c)] += v;
            if r != c {
                k[(c, r)] += v;
            }
        }
        k
    }

    /// Builds the element matrix of `material` on `grid`: the background's for every element (the
    /// stencil), and the change of each element an inclusion meets ([`inclusions`]).
    pub fn new(grid: Grid, material: &Material) -> Self {
        let ke = hex8_stiffness(&material.stiffness, grid.h());
        Self {
            grid,
            stencil: stencil::Stencil::new(&grid, &ke),
            ke,
            material: material.stiffness,
            elements: grid.elements().collect(),
            patch: inclusions::patch(&grid, material),
        }
    }

    /// `K` as a stencil of 3x3 blocks ([`stencil`]).
    pub fn stencil(&self) -> &stencil::Stencil {
        &self.stencil
    }

    /// `out = K u` over all degrees of freedom, by the stencil ([`stencil`]) and the inclusions'
    /// elements. Allocates nothing.
    pub fn apply(&self, u: &[f64], out: &mut [f64]) {
        self.stencil.apply(u, out);
        inclusions::add_product(&self.patch, u, out);
    }

    /// [`FemModel::apply`] on component-wise arrays (`u[c][node]`). Allocates nothing.
    pub fn apply_components(&self, u: &[Vec<f64>; 3], out: &mut [Vec<f64>; 3]) {
        self.stencil.apply_components(u, out);
        inclusions::add_product_components(&self.patch, u, out);
    }

    /// `out = K u` over all degrees of freedom, element by element: the stencil's check, and
    /// the baseline `bench` compares it with.
    pub fn apply_by_elements(&self, u: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        let mut ue = [0.0; 24];
        for nodes in &self.elements {
            for (a, &p) in nodes.iter().enumerate() {
                ue[3 * a..3 * a + 3].copy_from_slice(&u[3 * p..3 * p + 3]);
            }
            // K_e is symmetric: row i is column i, which is contiguous.
            for (a, &p) in nodes.iter().enumerate() {
                for c in 0..3 {
                    let i = 3 * a + c;
                    let col = &self.ke.as_slice()[24 * i..24 * i + 24];
                    let mut s = [0.0; 4];
                    for (k, u) in col.chunks_exact(4).zip(ue.chunks_exact(4)) {
                        for l in 0..4 {
                            s[l] += k[l] * u[l];
                        }
                    }
                    out[3 * p + c] += (s[0] + s[1]) + (s[2] + s[3]);
                }
            }
        }
        inclusions::add_product(&self.patch, u, out);
    }

    /// Solves all `cases`: clamped ones of a homogeneous material with the symmetry-reduced
    /// [`clamped::ClampedSolver`] (one numeric factorisation per loaded axis), others with the general [`StaticSolver`]
    /// (one numeric factorisation per set of fixed degrees of freedom).
    pub fn solve_cases(&self, cases: &[LoadCase]) -> Result<Vec<CaseSolution>, SparseError> {
        self.solve_cases_with_progress(cases, &mut |_, _| {})
    }

    /// [`FemModel::solve_cases`], calling `progress(i, case id)` before case `i`.
    pub fn solve_cases_with_progress(
        &self,
        cases: &[LoadCase],
        progress: &mut dyn FnMut(usize, &str),
    ) -> Result<Vec<CaseSolution>, SparseError> {
        let mut clamped: Option<clamped::ClampedSolver> = None;
        let mut general: Option<StaticSolver> = None;
        let mut out = Vec::with_capacity(cases.len());
        for (i, case) in cases.iter().enumerate() {
            progress(i, &case.id);
            // The symmetry-reduced solver needs the material mirror-symmetric: no inclusions.
            let sol = if case.bc == crate::mechanics::cases::Bc::Clamped && self.patch.is_empty() {
                let solver = match &mut clamped {
                    Some(s) => s,
                    None => clamped.insert(clamped::ClampedSolver::new(self.grid, &self.material)?),
                };
                solver.solve_case(self, case)?
            } else {
                let solver = match &mut general {
                    Some(s) => s,
                    None => general.insert(StaticSolver::new(self)?),
                };
                solver.solve_case(self, case)?
            };
            out.push(sol);
        }
        Ok(out)
    }
}

/// The assembled stiffness of a [`FemModel`] on one sparse pattern with its symbolic Cholesky,
/// refactorised per set of fixed degrees of freedom.
///
/// Fixed degrees of freedom are eliminated by decoupling: their rows and columns are zeroed and
/// their diagonal set to one, which leaves the free unknowns with exactly the reduced system while
/// every constraint set shares one pattern and one symbolic analysis.
#[derive(Debug)]
pub struct StaticSolver {
    system: SpdSystem,
    stiffness: Vec<f64>,
    fixed: Vec<bool>,
}

impl StaticSolver {
    /// Assembles the full stiffness and analyses its pattern.
    pub fn new(model: &FemModel) -> Result<Self, SparseError> {
        let (entries, values) = model.stiffness_entries();
        let dofs = 3 * model.grid.num_nodes();
        let (mut system, slots) = SpdSystem::on_grid(dofs, &entries, &model.grid.dof_nodes())?;
        for (slot, v) in slots.iter().zip(values) {
            system.add(*slot, v);
        }
        let stiffness = system.values().to_vec();
        Ok(Self { system, stiffness, fixed: Vec::new() })
    }

    /// Factorises the stiffness with `fixed` degrees of freedom eliminated (skipped when they
    /// are those of the last factorisation).
    pub fn constrain(&mut self, fixed: &[bool]) -> Result<(), SparseError> {
        if self.fixed == fixed {
            return Ok(());
        }
        self.fixed.clear();
        self.system.set_values(&self.stiffness);
        self.system.decouple(fixed, 1.0);
        self.system.factor()?;
        self.fixed.extend_from_slice(fixed);
        Ok(())
    }

    /// Solves all `cases`, refactorising only when the fixed degrees of freedom change.
    pub fn solve_cases(&mut self, model: &FemModel, cases: &[LoadCase]) -> Result<Vec<CaseSolution>, SparseError> {
        cases.iter().map(|c| self.solve_case(model, c)).collect()
    }

    /// Solves `K u = f` with the current fixed degrees of freedom at zero; returns the full `u`.
    pub fn solve(&mut self, model: &FemModel, f: &[f64]) -> Result<Vec<f64>, SparseError> {
        let free = |d: usize| !self.fixed[d];
        let mut u: Vec<f64> = (0..f.len()).map(|d| if free(d) { f[d] } else { 0.0 }).collect();
        self.system.solve_in_place(&mut u)?;
        let mut ku = vec![0.0; f.len()];
        for _ in 0..REFINEMENT_STEPS {
            model.apply(&u, &mut ku);
            for (d, r) in ku.iter_mut().enumerate() {
                *r = if self.fixed[d] { 0.0 } else { f[d] - *r };
            }
            self.system.solve_in_place(&mut ku)?;
            for (ud, du) in u.iter_mut().zip(&ku) {
                *ud += du;
            }
        }
        Ok(u)
    }

    /// Solves one load case and computes its support reactions.
    pub fn solve_case(&mut self, model: &FemModel, case: &LoadCase) -> Result<CaseSolution, SparseError> {
        self.constrain(&case.fixed)?;
        let u = self.solve(model, &case.load)?;
        Ok(solution_with_reactions(model, case, u))
    }
}

/// Packs a displacement vector into a [`CaseSolution`] with its support reactions `K u - f`.
fn solution_with_reactions(model: &FemModel, case: &LoadCase, u: Vec<f64>) -> CaseSolution {
    let mut ku = vec![0.0; u.len()];
    model.apply(&u, &mut ku);
    let mut reaction_n = [0.0; 3];
    for (d, &fixed) in case.fixed.iter().enumerate() {
        if fixed {
            reaction_n[d % 3] += ku[d] - case.load[d];
        }
    }
    CaseSolution {
        case_id: case.id.clone(),
        axis: case.axis,
        force_n: case.force_n,
        displacements: u.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        reaction_n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::cases::{Bc, benchmark_cases};

    #[test]
    fn clamped_symmetric_solver_matches_full_solve() {
        for (n, m) in [(4, Material::object_a()), (5, Material::object_b())] {
            let grid = Grid::new(n).unwrap();
            let model = FemModel::new(grid, &m);
            let cases = benchmark_cases(&grid, &m.name, Bc::Clamped);
            let fast = model.solve_cases(&cases).unwrap();
            let mut full = StaticSolver::new(&model).unwrap();
            for (c, f) in cases.iter().zip(&fast) {
                let s = full.solve_case(&model, c).unwrap();
                let scale = s.displacements.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
                for (x, y) in s.displacements.iter().flatten().zip(f.displacements.iter().flatten()) {
                    assert!((x - y).abs() <= 1e-13 * scale, "{}: {x} vs {y}", c.id);
                }
            }
        }
    }

    #[test]
    fn patch_test_small_grid() {
        let grid = Grid::new(3).unwrap();
        let m = Material::object_a();
        let model = FemModel::new(grid, &m);
        let cases = benchmark_cases(&grid, "A", Bc::Patch);
        let sols = model.solve_cases(&cases).unwrap();
        for (c, s) in cases.iter().zip(&sols) {
            let exact = c.patch_exact(&grid, &m.compliance);
            let scale = exact.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
            for (u, e) in s.displacements.iter().zip(&exact) {
                for k in 0..3 {
                    assert!((u[k] - e[k]).abs() <= 1e-12 * scale, "{}: {u:?} vs {e:?}", c.id);
                }
            }
        }
    }
}
