//! The hex8 FEM of the cube on a graded tensor-product mesh: boxes of a fine spacing around one
//! point, growing geometrically away from it. This is how the continuum's answer to a small tool
//! is computed without a uniformly fine cube: the same element ([`super::element`], exact on
//! boxes), assembled over node coordinates chosen per axis.

use std::collections::HashMap;

use super::element::{ElementStiffness, hex8_box_stiffness, hex8_box_stiffness_varying};
use crate::mechanics::grid::CUBE_SIDE_M;
use crate::mechanics::material::Material;
use crate::mechanics::sparse::{SparseError, SpdSystem};

/// Node coordinates of a tensor-product mesh of the cube, per axis, ascending from 0 to the side.
#[derive(Debug, Clone, PartialEq)]
pub struct GradedMesh {
    /// x, y and z coordinates of the node planes, metres.
    pub axes: [Vec<f64>; 3],
}

/// Node coordinates on `[0, length]`: spacing `fine` within `half_width` of `centre` (nodes at
/// `centre + i fine`), then steps growing by `growth` towards both ends; a last step shorter
/// than half the one before is merged into it.
pub fn graded_axis(length: f64, centre: f64, fine: f64, half_width: f64, growth: f64) -> Vec<f64> {
    capped_axis(length, centre, fine, half_width, growth, f64::INFINITY)
}

/// [`graded_axis`] with no step longer than `max_step` (the far field kept fine enough for the
/// cube's own motion).
pub fn capped_axis(length: f64, centre: f64, fine: f64, half_width: f64, growth: f64, max_step: f64) -> Vec<f64> {
    let lo = (centre - half_width).max(0.0);
    let hi = (centre + half_width).min(length);
    let first = ((lo - centre) / fine).ceil() as i64;
    let last = ((hi - centre) / fine).floor() as i64;
    let mut core: Vec<f64> = (first..=last).map(|i| centre + i as f64 * fine).collect();
    if core.is_empty() {
        core.push(centre.clamp(0.0, length));
    }
    // A node closer to an end than half the fine spacing moves onto it.
    if core[0] < 0.5 * fine {
        core[0] = 0.0;
    }
    let top = core.len() - 1;
    if length - core[top] < 0.5 * fine {
        core[top] = length;
    }
    let mut below = extend(core[0], 0.0, fine, growth, max_step);
    let above = extend(core[top], length, fine, growth, max_step);
    below.reverse();
    below.extend(core);
    below.extend(above);
    below
}

/// Nodes from `start` (excluded) to `end` (included), steps `min(fine growth^k, max_step)`,
/// k = 1, 2, ...; the last step is between half and one and a half times the growing step.
fn extend(start: f64, end: f64, fine: f64, growth: f64, max_step: f64) -> Vec<f64> {
    let sign = if end >= start { 1.0 } else { -1.0 };
    let mut out = Vec::new();
    let mut x = start;
    let mut step = fine;
    while (end - x) * sign > 0.0 {
        step = (step * growth).min(max_step.max(fine));
        if (end - x) * sign < 1.5 * step {
            out.push(end);
            break;
        }
        x += sign * step;
        out.push(x);
    }
    out
}

impl GradedMesh {
    /// A mesh of the cube fine (`fine` metres) within `half_width` of `point` along each axis,
    /// steps growing by `growth` beyond.
    pub fn around(point: [f64; 3], fine: f64, half_width: f64, growth: f64) -> Self {
        Self { axes: [0, 1, 2].map(|a| graded_axis(CUBE_SIDE_M, point[a], fine, half_width, growth)) }
    }

    /// [`GradedMesh::around`] with no element side longer than `max_step`.
    pub fn around_capped(point: [f64; 3], fine: f64, half_width: f64, growth: f64, max_step: f64) -> Self {
        Self { axes: [0, 1, 2].map(|a| capped_axis(CUBE_SIDE_M, point[a], fine, half_width, growth, max_step)) }
    }

    /// Lumped masses of `density` (kg/m^3): each box's mass shared equally by its eight nodes, kg.
    pub fn lumped_masses(&self, density: f64) -> Vec<f64> {
        let [nx, ny, nz] = self.dims();
        let side = |a: usize, c: usize| self.axes[a][c + 1] - self.axes[a][c];
        let mut m = vec![0.0; self.num_nodes()];
        for k in 0..nz - 1 {
            for j in 0..ny - 1 {
                for i in 0..nx - 1 {
                    let share = density * side(0, i) * side(1, j) * side(2, k) / 8.0;
                    for o in 0..8 {
                        m[self.node([i + (o & 1), j + ((o >> 1) & 1), k + (o >> 2)])] += share;
                    }
                }
            }
        }
        m
    }

    /// Node planes per axis.
    pub fn dims(&self) -> [usize; 3] {
        [0, 1, 2].map(|a| self.axes[a].len())
    }

    /// Number of nodes.
    pub fn num_nodes(&self) -> usize {
        self.dims().iter().product()
    }

    /// Linear index of node `(i, j, k)`, x fastest (the grid's convention).
    pub fn node(&self, ijk: [usize; 3]) -> usize {
        let [nx, ny, _] = self.dims();
        ijk[0] + nx * (ijk[1] + ny * ijk[2])
    }

    /// `(i, j, k)` of a node.
    pub fn ijk(&self, node: usize) -> [usize; 3] {
        let [nx, ny, _] = self.dims();
        [node % nx, (node / nx) % ny, node / (nx * ny)]
    }

    /// The nodes of the box holding the point `x` (metres, inside the cube) and their trilinear
    /// weights.
    pub fn corners(&self, x: [f64; 3]) -> [(usize, f64); 8] {
        let at: [(usize, f64); 3] = std::array::from_fn(|a| {
            let line = &self.axes[a];
            let i = line.partition_point(|&y| y <= x[a]).clamp(1, line.len() - 1) - 1;
            (i, ((x[a] - line[i]) / (line[i + 1] - line[i])).clamp(0.0, 1.0))
        });
        super::element::NODE_SIDES.map(|o| {
            let w: f64 = (0..3).map(|a| if o[a] == 1 { at[a].1 } else { 1.0 - at[a].1 }).product();
            (self.node(std::array::from_fn(|a| at[a].0 + o[a])), w)
        })
    }

    /// Element `[i, j, k]` (its lowest node's indices): its lowest corner and sides, metres, and
    /// its nodes in the element's order.
    pub fn element(&self, ijk: [usize; 3]) -> ([f64; 3], [f64; 3], [usize; 8]) {
        let lo = std::array::from_fn(|a| self.axes[a][ijk[a]]);
        let sides = std::array::from_fn(|a| self.axes[a][ijk[a] + 1] - self.axes[a][ijk[a]]);
        let nodes = super::element::NODE_SIDES.map(|o| self.node(std::array::from_fn(|a| ijk[a] + o[a])));
        (lo, sides, nodes)
    }

    /// Rest position of a node, metres.
    pub fn position(&self, node: usize) -> [f64; 3] {
        let ijk = self.ijk(node);
        [0, 1, 2].map(|a| self.axes[a][ijk[a]])
    }

    /// Whether a node lies on the cube's boundary.
    pub fn on_boundary(&self, node: usize) -> bool {
        let ijk = self.ijk(node);
        let dims = self.dims();
        (0..3).any(|a| ijk[a] == 0 || ijk[a] + 1 == dims[a])
    }

    /// The smallest element side, metres.
    pub fn finest(&self) -> f64 {
        self.axes.iter().flat_map(|x| x.windows(2).map(|w| w[1] - w[0])).fold(f64::INFINITY, f64::min)
    }
}

/// Sub-boxes per axis of an element an inclusion's surface cuts ([`hex8_box_stiffness_varying`]).
pub const SUB_CELLS: usize = 4;

/// Which material fills the box `lo + [0, sides]` whole: `Some(None)` the background,
/// `Some(Some(i))` inclusion `i`; `None` where an inclusion's surface cuts it.
fn inside(material: &Material, lo: [f64; 3], sides: [f64; 3]) -> Option<Option<usize>> {
    let hi: [f64; 3] = std::array::from_fn(|a| lo[a] + sides[a]);
    let mut whole = None;
    for (w, inclusion) in material.inclusions.iter().enumerate() {
        match inclusion.meets_box(lo, hi) {
            Some(false) => {}
            Some(true) => whole = Some(w),
            None => return None,
        }
    }
    Some(whole)
}

/// The stiffness `material`'s inclusions add to its background's on `mesh`: the nodes of the
/// elements an inclusion meets (ascending) and the change of `K` on their dofs (`3 n` square,
/// column-major; an element the inclusion's surface cuts by sub-cell quadrature, as assembled).
pub fn inclusion_change(mesh: &GradedMesh, material: &Material) -> (Vec<usize>, Vec<f64>) {
    let [nx, ny, nz] = mesh.dims();
    let mut changed: Vec<([usize; 8], ElementStiffness)> = Vec::new();
    for k in 0..nz - 1 {
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let (lo, sides, nodes) = mesh.element([i, j, k]);
                let ke = match inside(material, lo, sides) {
                    Some(None) => continue,
                    Some(Some(w)) => hex8_box_stiffness(&material.inclusions[w].stiffness, sides),
                    None => hex8_box_stiffness_varying(|x| material.stiffness_at(x), lo, sides, SUB_CELLS),
                };
                changed.push((nodes, ke - hex8_box_stiffness(&material.stiffness, sides)));
            }
        }
    }
    let mut nodes: Vec<usize> = changed.iter().flat_map(|(n, _)| *n).collect();
    nodes.sort_unstable();
    nodes.dedup();
    let m = 3 * nodes.len();
    let mut change = vec![0.0; m * m];
    for (element, ke) in &changed {
        let row = |l: usize| 3 * nodes.partition_point(|&n| n < element[l / 3]) + l % 3;
        for b in 0..24 {
            let column = m * row(b);
            for a in 0..24 {
                change[column + row(a)] += ke[(a, b)];
            }
        }
    }
    (nodes, change)
}

/// The stiffness of `material` (its inclusions too) on a graded mesh with face z = 0 clamped,
/// factorised.
#[derive(Debug)]
pub struct GradedFem {
    /// The mesh.
    pub mesh: GradedMesh,
    /// Clamped dofs.
    pub fixed: Vec<bool>,
    system: SpdSystem,
}

impl GradedFem {
    /// Assembles and factorises `K` of `material` on `mesh`, face z = 0 clamped.
    pub fn clamped_bottom(mesh: GradedMesh, material: &Material) -> Result<Self, SparseError> {
        Self::shifted(mesh, material, 0.0)
    }

    /// Assembles and factorises `K + shift M` (`M` the lumped masses of the material's density)
    /// on `mesh`, face z = 0 clamped: the matrix of an implicit step.
    pub fn shifted(mesh: GradedMesh, material: &Material, shift: f64) -> Result<Self, SparseError> {
        let [nx, ny, nz] = mesh.dims();
        let n = 3 * mesh.num_nodes();
        let elements = (nx - 1) * (ny - 1) * (nz - 1);
        // One element matrix per distinct box (the mesh has few distinct sides).
        let mut matrices: HashMap<([u64; 3], Option<usize>), ElementStiffness> = HashMap::new();
        let mut entries = Vec::with_capacity(elements * 300);
        let mut values = Vec::with_capacity(elements * 300);
        for k in 0..nz - 1 {
            for j in 0..ny - 1 {
                for i in 0..nx - 1 {
                    let (lo, sides, nodes) = mesh.element([i, j, k]);
                    let cut;
                    let ke = match inside(material, lo, sides) {
                        Some(which) => matrices.entry((sides.map(f64::to_bits), which)).or_insert_with(|| {
                            let c = which.map_or(&material.stiffness, |w| &material.inclusions[w].stiffness);
                            hex8_box_stiffness(c, sides)
                        }),
                        None => {
                            cut = hex8_box_stiffness_varying(|x| material.stiffness_at(x), lo, sides, SUB_CELLS);
                            &cut
                        }
                    };
                    let dof = |l: usize| 3 * nodes[l / 3] + l % 3;
                    for a in 0..24 {
                        for b in 0..=a {
                            entries.push((dof(a), dof(b)));
                            values.push(ke[(a, b)]);
                        }
                    }
                }
            }
        }
        let nodes: Vec<[u32; 3]> = (0..n).map(|d| mesh.ijk(d / 3).map(|i| i as u32)).collect();
        let (mut system, slots) = SpdSystem::on_grid(n, &entries, &nodes)?;
        drop(entries);
        for (&slot, &v) in slots.iter().zip(&values) {
            system.add(slot, v);
        }
        if shift != 0.0 {
            let masses = mesh.lumped_masses(material.density);
            let per_dof: Vec<f64> = (0..n).map(|d| masses[d / 3]).collect();
            system.add_diagonal_scaled(shift, &per_dof);
        }
        let fixed: Vec<bool> = (0..n).map(|d| mesh.ijk(d / 3)[2] == 0).collect();
        system.decouple(&fixed, 1.0);
        system.factor()?;
        Ok(Self { mesh, fixed, system })
    }

    /// Solves `K U = F` in place for `cols` load columns stored one after another (clamped dofs
    /// answer zero).
    pub fn solve_columns(&mut self, rhs: &mut [f64], cols: usize) -> Result<(), SparseError> {
        let n = self.fixed.len();
        for col in rhs.chunks_exact_mut(n) {
            for (v, &f) in col.iter_mut().zip(&self.fixed) {
                if f {
                    *v = 0.0;
                }
            }
        }
        self.system.solve_columns_in_place(rhs, cols)
    }

    /// Nonzeros of the Cholesky factor.
    pub fn factor_nonzeros(&self) -> usize {
        self.system.factor_nonzeros()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_cover_the_cube_and_grade_smoothly() {
        for (centre, fine, half) in
            [(0.05, 0.001, 0.01), (0.0, 0.0015, 0.012), (0.1, 0.002, 0.02), (0.0971, 0.001, 0.008)]
        {
            let x = graded_axis(0.1, centre, fine, half, 1.3);
            assert_eq!(x[0], 0.0);
            assert_eq!(*x.last().unwrap(), 0.1);
            let steps: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
            assert!(steps.iter().all(|&s| s > 0.4 * fine), "{centre}: {steps:?}");
            for w in steps.windows(2) {
                assert!(w[1] / w[0] < 2.5 && w[0] / w[1] < 2.5, "{centre}: {steps:?}");
            }
            let near = steps.iter().zip(&x).filter(|(_, xi)| (**xi - centre).abs() < half - fine);
            assert!(near.clone().all(|(s, _)| *s < fine * 1.0001), "{centre}: {steps:?}");
        }
    }

    #[test]
    fn lumped_masses_weigh_the_cube_and_a_cap_bounds_the_steps() {
        let mesh = GradedMesh::around_capped([0.043, 0.043, 0.1], 0.002, 0.012, 1.45, 0.008);
        let total: f64 = mesh.lumped_masses(1000.0).iter().sum();
        assert!((total - 1.0).abs() < 1e-9, "{total}");
        for axis in &mesh.axes {
            assert!(axis.windows(2).all(|w| w[1] - w[0] < 1.5 * 0.008 + 1e-12), "{axis:?}");
        }
    }

    #[test]
    fn a_uniform_graded_mesh_is_the_structured_fem() {
        // With a fine spacing equal to the grid's, the graded FEM solves the clamped cube like the
        // structured one.
        let material = Material::object_a();
        let h = 0.1 / 4.0;
        let mesh = GradedMesh::around([0.05, 0.05, 0.1], h, 1.0, 1.0);
        assert_eq!(mesh.dims(), [5, 5, 5]);
        let mut graded = GradedFem::clamped_bottom(mesh.clone(), &material).unwrap();
        let grid = crate::mechanics::grid::Grid::new(5).unwrap();
        let fem = super::super::FemModel::new(grid, &material);
        let mut f = vec![0.0; 3 * grid.num_nodes()];
        f[3 * grid.node(2, 1, 4) + 2] = -1.0;
        f[3 * grid.node(4, 4, 4)] = 0.5;
        let mut u = f.clone();
        graded.solve_columns(&mut u, 1).unwrap();
        let mut solver = super::super::StaticSolver::new(&fem).unwrap();
        let fixed = crate::mechanics::cases::LoadCase::bottom_clamp(&grid, "t").fixed;
        solver.constrain(&fixed).unwrap();
        let reference = solver.solve(&fem, &f).unwrap();
        let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (a, b) in u.iter().zip(&reference) {
            assert!((a - b).abs() < 1e-9 * scale, "{a} vs {b}");
        }
    }
}
