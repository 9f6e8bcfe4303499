//! A fast exact solver for the clamped benchmark cases, built on their symmetries.
//!
//! A clamped case along axis `a` (face `x_a = 0` fixed, a uniform load along `+a` on face
//! `x_a = L`) of an orthotropic material aligned with the grid is invariant under the two
//! reflections across the mid-planes of the transverse axes. Its unique solution is therefore
//! symmetric too, and lies in the subspace spanned by the symmetrised unit vectors
//! `e_O = sum_{d in O} s_d e_d` of each orbit `O` of degrees of freedom under those reflections
//! (`s_d = -1` for a transverse component that the reflection flips; a component that a reflection
//! maps onto minus itself is zero). With `P` the matrix of those vectors, `P^T K P c = P^T f` and
//! `u = P c` is the exact answer of `K u = f`, on a quarter of the unknowns.
//!
//! Every case is solved in a local frame in which the loaded axis comes first (a cyclic
//! relabelling of the axes; the material is relabelled with it), so the three axes share one
//! sparse pattern and one symbolic factorisation; each axis costs one numeric factorisation of
//! the quarter system. Answers are polished by iterative refinement against the full
//! element-by-element residual in the global frame, so they agree with an unreduced solve to
//! round-off.

use nalgebra::Matrix6;

use super::FemModel;
use super::element::hex8_stiffness;
use crate::mechanics::cases::{Bc, CaseSolution, LoadCase};
use crate::mechanics::grid::Grid;
use crate::mechanics::sparse::{SparseError, SpdSystem};

/// Steps of iterative refinement (full residual) after each reduced solve.
const REFINEMENT_STEPS: usize = 2;

/// Voigt index of the symmetric index pair `(i, j)`, order (11, 22, 33, 23, 13, 12).
fn voigt(i: usize, j: usize) -> usize {
    if i == j {
        i
    } else {
        6 - i - j // {1,2} -> 3, {0,2} -> 4, {0,1} -> 5
    }
}

/// `C` in the local frame whose axis `m` is global axis `(a + m) % 3`.
fn local_stiffness(c: &Matrix6<f64>, a: usize) -> Matrix6<f64> {
    let pairs = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)];
    let global = pairs.map(|(i, j)| voigt((a + i) % 3, (a + j) % 3));
    Matrix6::from_fn(|p, q| c[(global[p], global[q])])
}

/// Solver for the clamped cases of one object on one grid.
#[derive(Debug)]
pub struct ClampedSolver {
    grid: Grid,
    /// Local dof (`3 local_node + m`) -> (reduced index or `u32::MAX`, sign).
    map: Vec<(u32, f64)>,
    /// For every element and every lower local pair `(a, b)`: the slot and the factor
    /// `s_a s_b` (doubled when both dofs fold onto one reduced diagonal entry).
    slots: Vec<(u32, f64)>,
    /// Number of representative elements.
    elements: usize,
    system: SpdSystem,
    material: Matrix6<f64>,
    factored_axis: Option<usize>,
}

/// One element per orbit under the two transverse reflections (local frame), with the orbit size.
fn representative_elements(grid: &Grid) -> Vec<([usize; 8], f64)> {
    let m = grid.n() - 1; // elements per axis
    let mut out = Vec::new();
    for e2 in 0..m.div_ceil(2) {
        for e1 in 0..m.div_ceil(2) {
            let w1 = if 2 * e1 + 1 == m { 1.0 } else { 2.0 };
            let w2 = if 2 * e2 + 1 == m { 1.0 } else { 2.0 };
            for e0 in 0..m {
                out.push((grid.element_nodes(e0, e1, e2), w1 * w2));
            }
        }
    }
    out
}

impl ClampedSolver {
    /// Builds the shared quarter-system pattern for `model`'s grid; `material` is the global `C`.
    pub fn new(grid: Grid, material: &Matrix6<f64>) -> Result<Self, SparseError> {
        let n = grid.n();
        let mut map = vec![(u32::MAX, 1.0); 3 * grid.num_nodes()];
        let mut next = 0u32;
        // Representatives: l1, l2 in the lower half (the middle included); other nodes fold onto them.
        let half = (n - 1) / 2;
        for l in 0..grid.num_nodes() {
            let [l0, l1, l2] = grid.ijk(l);
            if l0 == 0 || l1 > half || l2 > half {
                continue;
            }
            for m in 0..3 {
                // A component flipped by a reflection that fixes its node is zero.
                let self_flip = (m == 1 && 2 * l1 == n - 1) || (m == 2 && 2 * l2 == n - 1);
                if !self_flip {
                    map[3 * l + m] = (next, 1.0);
                    next += 1;
                }
            }
        }
        for l in 0..grid.num_nodes() {
            let [l0, l1, l2] = grid.ijk(l);
            let (r1, f1) = if l1 > half { (n - 1 - l1, true) } else { (l1, false) };
            let (r2, f2) = if l2 > half { (n - 1 - l2, true) } else { (l2, false) };
            let rep = grid.node(l0, r1, r2);
            for m in 0..3 {
                let sign = if (m == 1 && f1) || (m == 2 && f2) { -1.0 } else { 1.0 };
                map[3 * l + m] = (map[3 * rep + m].0, sign);
            }
        }
        // Reflected elements contribute identically to P^T K P: assemble one representative per
        // orbit of elements, weighted by the orbit's size.
        let elements = representative_elements(&grid);
        let mut entries = Vec::new();
        let mut factors = Vec::new();
        let mut used = Vec::with_capacity(elements.len() * 300);
        for (nodes, weight) in &elements {
            let dof = |x: usize| map[3 * nodes[x / 3] + x % 3];
            for a in 0..24 {
                let (ra, sa) = dof(a);
                for b in 0..=a {
                    let (rb, sb) = dof(b);
                    let ok = ra != u32::MAX && rb != u32::MAX;
                    used.push(ok);
                    if ok {
                        entries.push((ra as usize, rb as usize));
                        let twice = if a != b && ra == rb { 2.0 } else { 1.0 };
                        factors.push(sa * sb * twice * weight);
                    }
                }
            }
        }
        let nodes = grid.unknown_nodes(map.iter().map(|m| m.0), next as usize);
        let (system, slot_ids) = SpdSystem::on_grid(next as usize, &entries, &nodes)?;
        // One (slot, factor) per representative element and lower local pair, to replay assembly.
        let mut it = slot_ids.into_iter().zip(factors);
        let slots = used.into_iter().map(|ok| if ok { it.next() } else { None }.unwrap_or((u32::MAX, 0.0))).collect();
        Ok(Self { grid, map, slots, elements: elements.len(), system, material: *material, factored_axis: None })
    }

    /// Local node index of global node `p` for loaded axis `a` (0-based).
    fn local_node(&self, p: usize, a: usize) -> usize {
        let g = self.grid.ijk(p);
        self.grid.node(g[a], g[(a + 1) % 3], g[(a + 2) % 3])
    }

    fn factor_axis(&mut self, a: usize) -> Result<(), SparseError> {
        if self.factored_axis == Some(a) {
            return Ok(());
        }
        self.factored_axis = None;
        let ke = hex8_stiffness(&local_stiffness(&self.material, a), self.grid.h());
        self.system.clear();
        let mut s = self.slots.iter();
        for _ in 0..self.elements {
            for x in 0..24 {
                for y in 0..=x {
                    if let Some(&(slot, f)) = s.next()
                        && slot != u32::MAX
                    {
                        self.system.add(slot, f * ke[(x, y)]);
                    }
                }
            }
        }
        self.system.factor()?;
        self.factored_axis = Some(a);
        Ok(())
    }

    /// `P^T r` of a global-frame vector `r`, solved and expanded back: `du = P (P^T K P)^-1 P^T r`.
    fn reduced_solve(&mut self, a: usize, r: &[f64], du: &mut [f64], work: &mut [f64]) -> Result<(), SparseError> {
        work.fill(0.0);
        for p in 0..self.grid.num_nodes() {
            let l = self.local_node(p, a);
            for m in 0..3 {
                let (i, s) = self.map[3 * l + m];
                if i != u32::MAX {
                    work[i as usize] += s * r[3 * p + (a + m) % 3];
                }
            }
        }
        self.system.solve_in_place(work)?;
        for p in 0..self.grid.num_nodes() {
            let l = self.local_node(p, a);
            for m in 0..3 {
                let (i, s) = self.map[3 * l + m];
                du[3 * p + (a + m) % 3] = if i == u32::MAX { 0.0 } else { s * work[i as usize] };
            }
        }
        Ok(())
    }

    /// Solves a clamped case (`case.bc` must be [`Bc::Clamped`]).
    pub fn solve_case(&mut self, model: &FemModel, case: &LoadCase) -> Result<CaseSolution, SparseError> {
        debug_assert_eq!(case.bc, Bc::Clamped);
        let a = case.axis - 1;
        self.factor_axis(a)?;
        let dofs = case.load.len();
        let mut u = vec![0.0; dofs];
        let mut work = vec![0.0; self.system.n()];
        self.reduced_solve(a, &case.load, &mut u, &mut work)?;
        let (mut r, mut du) = (vec![0.0; dofs], vec![0.0; dofs]);
        for _ in 0..REFINEMENT_STEPS {
            model.apply(&u, &mut r);
            for (d, rd) in r.iter_mut().enumerate() {
                *rd = if case.fixed[d] { 0.0 } else { case.load[d] - *rd };
            }
            self.reduced_solve(a, &r, &mut du, &mut work)?;
            for (x, y) in u.iter_mut().zip(&du) {
                *x += y;
            }
        }
        Ok(super::solution_with_reactions(model, case, u))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn local_stiffness_relabels_axes() {
        let c = crate::mechanics::material::Material::object_a().stiffness;
        assert_eq!(local_stiffness(&c, 0), c);
        let l = local_stiffness(&c, 1); // local (x, y, z) = global (y, z, x)
        assert_eq!(l[(0, 0)], c[(1, 1)]);
        assert_eq!(l[(0, 2)], c[(1, 0)]);
        assert_eq!(l[(3, 3)], c[(4, 4)]); // local 23 = global {z, x} = 13
        assert_eq!(l[(5, 5)], c[(3, 3)]); // local 12 = global {y, z} = 23
    }
}
