//! Small-displacement stiffness of a tissue model over the touch scene (face z = 0 clamped), its
//! factorisation, point-load solves and the probe's frictionless node contact.
//!
//! A model enters as its rest stiffness, the sum `K = sum_j theta_j K_j` of parameter groups:
//! one group for a FEM cube (`theta = 1`), one per stiffness parameter of a spring lattice
//! (`k1, k2, k3, c12, c13, c23, b`), so that calibration can differentiate through it.

use crate::mechanics::fem::FemModel;
use crate::mechanics::grid::{Grid, SpringFamily};
use crate::mechanics::msm::model::Spring;
use crate::mechanics::msm::{MsmModel, MsmParams, Topology};
use crate::mechanics::sparse::{SparseError, SpdSystem};
use glam::DVec3;

use super::contact;

/// Parameter groups of a spring lattice, in this order.
pub const GROUP_NAMES: [&str; 7] = ["k1", "k2", "k3", "c12", "c13", "c23", "b"];

/// The stiffness group of a spring family: its axis, its plane, or the body diagonals.
pub fn group_of(family: SpringFamily) -> usize {
    let nz: Vec<usize> = (0..3).filter(|&c| family.offset[c] != 0).collect();
    match nz[..] {
        [a] => a,
        [0, 1] => 3,
        [0, 2] => 4,
        [1, 2] => 5,
        _ => 6,
    }
}

/// The groups' values of `params` (a missing diagonal stiffness is 0).
pub fn group_values(params: &MsmParams) -> [f64; 7] {
    let o = |v: Option<f64>| v.unwrap_or(0.0);
    [params.k1, params.k2, params.k3, o(params.c12), o(params.c13), o(params.c23), o(params.b)]
}

/// `params` with the groups set to `theta` (groups the topology lacks stay absent).
pub fn with_group_values(params: &MsmParams, theta: &[f64; 7]) -> MsmParams {
    let mut p = *params;
    (p.k1, p.k2, p.k3) = (theta[0], theta[1], theta[2]);
    let set = |v: Option<f64>, t: f64| v.map(|_| t);
    (p.c12, p.c13, p.c23, p.b) = (set(p.c12, theta[3]), set(p.c13, theta[4]), set(p.c23, theta[5]), set(p.b, theta[6]));
    p
}

/// A rest stiffness as lower-triangle entries over all `3 n^3` dofs, each tagged with its group.
#[derive(Debug, Clone)]
pub struct GroupedStiffness {
    /// `(row, col)` with `row >= col`; duplicates add up.
    pub entries: Vec<(usize, usize)>,
    /// Value of each entry for a group value of 1.
    pub unit: Vec<f64>,
    /// Group of each entry.
    pub group: Vec<u8>,
    /// Number of groups.
    pub groups: usize,
}

impl GroupedStiffness {
    /// The hex8 FEM's stiffness: one group.
    pub fn fem(model: &FemModel) -> Self {
        let (entries, unit) = model.stiffness_entries();
        let group = vec![0; unit.len()];
        Self { entries, unit, group, groups: 1 }
    }

    /// The rest tangent of a spring lattice of `topology` on `grid`, per stiffness group: each
    /// spring adds `k d d^T` (unit direction `d` at rest) to its end nodes' blocks.
    pub fn lattice(grid: Grid, topology: Topology) -> Self {
        Self::lattice_grouped(grid, topology, 7, |_, family| group_of(family))
    }

    /// [`GroupedStiffness::lattice`] with `groups` groups, spring `s` of `family` in group
    /// `group(s, family)` (its stiffness at 1 N/m times its element share).
    pub fn lattice_grouped(
        grid: Grid,
        topology: Topology,
        groups: usize,
        group: impl Fn(&Spring, SpringFamily) -> usize,
    ) -> Self {
        // Unit parameters are valid, so the model always builds.
        let model = MsmModel::new(grid, MsmParams::unit(topology), 1.0)
            .unwrap_or_else(|_| unreachable!("unit parameters are valid"));
        Self::of_springs(&model, groups, group)
    }

    /// [`GroupedStiffness::lattice`] of a lattice whose springs take inclusions by `rule`
    /// ([`crate::mechanics::msm::inclusions`]).
    pub fn lattice_in(
        grid: Grid,
        topology: Topology,
        rule: Option<&crate::mechanics::msm::inclusions::SpringRule>,
    ) -> Self {
        let model = MsmModel::new(grid, MsmParams::unit(topology), 1.0)
            .unwrap_or_else(|_| unreachable!("unit parameters are valid"))
            .with_rule(rule.cloned());
        Self::of_springs(&model, 7, |_, family| group_of(family))
    }

    /// The rest tangent of `model`'s springs at unit parameters, spring `s` in group `group(s, family)`.
    fn of_springs(model: &MsmModel, groups: usize, group: impl Fn(&Spring, SpringFamily) -> usize) -> Self {
        let mut out = Self { entries: Vec::new(), unit: Vec::new(), group: Vec::new(), groups };
        for s in model.springs() {
            let fam = model.families[s.family].family;
            let g = group(&s, fam) as u8;
            let o = fam.offset.map(f64::from);
            let len = DVec3::from(o).length();
            let d = o.map(|c| c / len);
            for i in 0..3 {
                for j in 0..3 {
                    let v = s.k * d[i] * d[j];
                    if v == 0.0 {
                        continue;
                    }
                    for (r, c, sign) in [
                        (3 * s.a + i, 3 * s.a + j, 1.0),
                        (3 * s.b + i, 3 * s.b + j, 1.0),
                        (3 * s.b + i, 3 * s.a + j, -1.0),
                    ] {
                        // Lower triangle only: the (a, a) and (b, b) blocks are symmetric, and b > a.
                        if r >= c {
                            out.entries.push((r, c));
                            out.unit.push(sign * v);
                            out.group.push(g);
                        }
                    }
                }
            }
        }
        out
    }

    /// `y = K(theta) x` over all dofs.
    pub fn mul(&self, theta: &[f64], x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for ((&(r, c), &u), &g) in self.entries.iter().zip(&self.unit).zip(&self.group) {
            let v = u * theta[g as usize];
            y[r] += v * x[c];
            if r != c {
                y[c] += v * x[r];
            }
        }
    }

    /// `w^T K_j u` for every group `j` (the derivative of `w^T K u` by `theta_j`).
    pub fn group_forms(&self, w: &[f64], u: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for ((&(r, c), &v), &g) in self.entries.iter().zip(&self.unit).zip(&self.group) {
            let t = if r == c { w[r] * u[r] } else { w[r] * u[c] + w[c] * u[r] };
            out[g as usize] += v * t;
        }
    }
}

/// The dofs the touch scene holds: face z = 0 ([`crate::mechanics::cases::LoadCase::bottom_clamp`]).
pub fn scene_fixed_dofs(grid: &Grid) -> Vec<bool> {
    crate::mechanics::cases::LoadCase::bottom_clamp(grid, "touch").fixed
}

/// A factorised rest stiffness on the touch scene.
#[derive(Debug)]
pub struct SceneSolver {
    system: SpdSystem,
    slots: Vec<u32>,
    fixed: Vec<bool>,
}

/// The probe's answer: displacements, the force on the probe, the contact nodes.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeAnswer {
    /// Displacements, all dofs, metres.
    pub u: Vec<f64>,
    /// Force of the tissue on the probe, newtons.
    pub force: [f64; 3],
    /// Contact nodes and their contact force along the outward normal, newtons.
    pub contacts: Vec<(usize, f64)>,
    /// The field `w` with `d|force| = -w^T dK u` for a change `dK` of the stiffness (the
    /// contact set held): the adjoint of the probe force.
    pub sensitivity: Vec<f64>,
}

impl ProbeAnswer {
    /// The magnitude of the force on the probe, newtons.
    pub fn force_n(&self) -> f64 {
        DVec3::from(self.force).length()
    }
}

impl SceneSolver {
    /// The pattern of `k` on the scene (factorise with [`SceneSolver::factor`]).
    pub fn new(grid: &Grid, k: &GroupedStiffness) -> Result<Self, SparseError> {
        Self::with_fixed(grid, k, scene_fixed_dofs(grid))
    }

    /// The pattern of `k` with the dofs `fixed` held instead of the scene's clamp.
    pub fn with_fixed(grid: &Grid, k: &GroupedStiffness, fixed: Vec<bool>) -> Result<Self, SparseError> {
        let (system, slots) = SpdSystem::on_grid(3 * grid.num_nodes(), &k.entries, &grid.dof_nodes())?;
        Ok(Self { system, slots, fixed })
    }

    /// Assembles `K(theta)` with the clamped face eliminated and factorises it.
    pub fn factor(&mut self, k: &GroupedStiffness, theta: &[f64]) -> Result<(), SparseError> {
        self.system.clear();
        for ((&slot, &u), &g) in self.slots.iter().zip(&k.unit).zip(&k.group) {
            self.system.add(slot, u * theta[g as usize]);
        }
        self.system.decouple(&self.fixed, 1.0);
        self.system.factor()
    }

    /// Solves `K u = f` in place with the clamped dofs at zero.
    pub fn solve(&mut self, f: &mut [f64]) -> Result<(), SparseError> {
        for (v, &fixed) in f.iter_mut().zip(&self.fixed) {
            if fixed {
                *v = 0.0;
            }
        }
        self.system.solve_in_place(f)
    }

    /// The sphere (`centre`, `radius`, metres) held still against the tissue at rest: every free
    /// surface node inside it is moved onto its surface along the outward normal at rest (linearised node
    /// contact, frictionless: the contact force is normal), with an active set so that no contact
    /// pulls and no free node ends inside.
    pub fn probe(&mut self, grid: &Grid, centre: [f64; 3], radius: f64) -> Result<ProbeAnswer, SparseError> {
        let nn = grid.num_nodes();
        let geometry = sphere_geometry(grid, centre, radius);
        // Contact is with the surface: interior nodes never touch the sphere.
        let free_nodes: Vec<bool> = (0..nn).map(|p| !self.fixed[3 * p] && grid.on_boundary(p)).collect();
        let zero = vec![0.0; 3 * nn];
        let ContactSolve { u, solved, lambda, columns, mut scratch } =
            contact_active_set(&mut |w| self.solve(w), &zero, &geometry, &free_nodes, radius)?;
        let mut force = [0.0; 3];
        for (&p, &l) in solved.iter().zip(&lambda) {
            for c in 0..3 {
                force[c] -= l * geometry[p].0[c];
            }
        }
        let sensitivity = probe_sensitivity(&force, &solved, &geometry, &columns, &mut scratch, 3 * nn);
        Ok(ProbeAnswer { u, force, contacts: solved.into_iter().zip(lambda).collect(), sensitivity })
    }
}

/// Where a sphere meets each node of `grid` at rest ([`contact::sphere_gap`]).
pub fn sphere_geometry(grid: &Grid, centre: [f64; 3], radius: f64) -> Vec<([f64; 3], f64)> {
    (0..grid.num_nodes()).map(|p| contact::sphere_gap(centre, radius, grid.position(p), [0.0, 0.0, 1.0])).collect()
}

/// The last solved contact set of [`contact_active_set`].
#[derive(Debug)]
pub struct ContactSolve {
    /// Displacements with the contact forces applied, all dofs.
    pub u: Vec<f64>,
    /// The contact nodes.
    pub solved: Vec<usize>,
    /// Their contact forces along their normals, newtons.
    pub lambda: Vec<f64>,
    /// Their unit-normal-force responses (`K^-1 n_p`), all dofs.
    pub columns: Vec<Vec<f64>>,
    /// The contact's memory, holding the factorised normal compliance of the contact nodes.
    pub scratch: contact::ContactScratch,
}

/// A factorised system's nodes as the contact sees them: unit normal-force responses solved once
/// per node, on demand.
struct NodeBody<'a> {
    solve: &'a mut dyn FnMut(&mut [f64]) -> Result<(), SparseError>,
    /// Node of each candidate.
    nodes: &'a [usize],
    geometry: &'a [([f64; 3], f64)],
    dofs: usize,
    /// Per candidate solved: `K^-1 n_p`, all dofs.
    columns: std::collections::HashMap<usize, Vec<f64>>,
}

impl contact::Compliance for NodeBody<'_> {
    fn prepare(&mut self, slots: &[usize]) -> Result<(), contact::ContactError> {
        for &s in slots {
            if let std::collections::hash_map::Entry::Vacant(e) = self.columns.entry(s) {
                let p = self.nodes[s];
                let mut w = vec![0.0; self.dofs];
                w[3 * p..3 * p + 3].copy_from_slice(&self.geometry[p].0);
                (self.solve)(&mut w).map_err(|e| contact::ContactError::Body(e.to_string()))?;
                e.insert(w);
            }
        }
        Ok(())
    }

    fn normal(&self, i: usize, n_i: [f64; 3], j: usize, _: [f64; 3]) -> f64 {
        let (p, col) = (self.nodes[i], &self.columns[&j]);
        (0..3).map(|c| n_i[c] * col[3 * p + c]).sum()
    }
}

/// Frictionless linearised node contact ([`contact::solve`]) on a system whose solve is `solve`,
/// from its unconstrained answer `base`: every `free` node in contact is put on the sphere
/// (`n_p . u_p = g_p`, `geometry` as [`sphere_geometry`]).
pub fn contact_active_set(
    solve: &mut dyn FnMut(&mut [f64]) -> Result<(), SparseError>,
    base: &[f64],
    geometry: &[([f64; 3], f64)],
    free: &[bool],
    radius: f64,
) -> Result<ContactSolve, SparseError> {
    let nodes: Vec<usize> = (0..geometry.len()).filter(|&p| free[p]).collect();
    let mut scratch = contact::ContactScratch::default();
    scratch.candidates.extend(nodes.iter().map(|&p| {
        let (n, depth) = geometry[p];
        (n, depth - (0..3).map(|c| n[c] * base[3 * p + c]).sum::<f64>())
    }));
    let mut body = NodeBody { solve, nodes: &nodes, geometry, dofs: base.len(), columns: Default::default() };
    contact::solve(&mut body, &mut scratch, 1e-12 * radius).map_err(|e| match e {
        contact::ContactError::NotPositiveDefinite => SparseError::NotPositiveDefinite,
        e => SparseError::Contact(e.to_string()),
    })?;
    let mut u = base.to_vec();
    let mut columns = Vec::with_capacity(scratch.active.len());
    for (&s, &l) in scratch.active.iter().zip(&scratch.lambda) {
        let col = body.columns.remove(&s).unwrap_or_default();
        for (ud, wd) in u.iter_mut().zip(&col) {
            *ud += l * wd;
        }
        columns.push(col);
    }
    let solved = scratch.active.iter().map(|&s| nodes[s]).collect();
    Ok(ContactSolve { u, solved, lambda: scratch.lambda.clone(), columns, scratch })
}

/// The adjoint of the probe force's magnitude with the contact set held: `d|F| = -w^T dK u`
/// with `w = W S^-1 b`, `b_i = F . n_i / |F|`, `W` the unit-force responses of the contacts.
fn probe_sensitivity(
    force: &[f64; 3],
    solved: &[usize],
    geometry: &[([f64; 3], f64)],
    columns: &[Vec<f64>],
    scratch: &mut contact::ContactScratch,
    dofs: usize,
) -> Vec<f64> {
    let mut sensitivity = vec![0.0; dofs];
    let magnitude = DVec3::from(*force).length();
    if !solved.is_empty() && magnitude > 0.0 {
        let mut mu: Vec<f64> =
            solved.iter().map(|&p| (0..3).map(|c| force[c] * geometry[p].0[c]).sum::<f64>() / magnitude).collect();
        scratch.solve_factored(&mut mu);
        for (col, m) in columns.iter().zip(mu.iter()) {
            for (s, w) in sensitivity.iter_mut().zip(col) {
                *s += m * w;
            }
        }
    }
    sensitivity
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::material::Material;

    #[test]
    fn lattice_groups_reassemble_the_model_tangent() {
        // K(theta) from the groups equals the lattice built with those parameters, entry by entry.
        let grid = Grid::new(4).unwrap();
        let params = MsmParams {
            c12: Some(7.0),
            c13: Some(11.0),
            c23: Some(13.0),
            b: Some(3.0),
            ..MsmParams::axis(2.0, 3.0, 5.0, 0.0)
        };
        let k = GroupedStiffness::lattice(grid, Topology::Hex);
        let theta = group_values(&params);
        let model = MsmModel::new(grid, params, 1.0).unwrap();
        // Energy of a rigid translation is zero; a random field's energy matches 1/2 sum k (d.du)^2.
        let dofs = 3 * grid.num_nodes();
        let x: Vec<f64> = (0..dofs).map(|i| ((i * 37 % 101) as f64 - 50.0) * 1e-4).collect();
        let mut y = vec![0.0; dofs];
        k.mul(&theta, &x, &mut y);
        let energy: f64 = 0.5 * x.iter().zip(&y).map(|(a, b)| a * b).sum::<f64>();
        let mut expected = 0.0;
        for s in model.springs() {
            let o = model.families[s.family].family.offset.map(f64::from);
            let len = DVec3::from(o).length();
            let stretch: f64 = (0..3).map(|c| o[c] / len * (x[3 * s.b + c] - x[3 * s.a + c])).sum();
            expected += 0.5 * s.k * stretch * stretch;
        }
        assert!((energy - expected).abs() <= 1e-12 * expected, "{energy} vs {expected}");
        let t: Vec<f64> = (0..dofs).map(|i| [1.0, -2.0, 0.5][i % 3]).collect();
        k.mul(&theta, &t, &mut y);
        assert!(y.iter().all(|v| v.abs() < 1e-9));
        // The group forms are the derivatives of x^T K x.
        let mut forms = [0.0; 7];
        k.group_forms(&x, &x, &mut forms);
        let total: f64 = forms.iter().zip(&theta).map(|(f, t)| f * t).sum();
        assert!((total - 2.0 * energy).abs() <= 1e-12 * energy);
    }

    #[test]
    fn probe_pushes_and_never_pulls() {
        let grid = Grid::new(6).unwrap();
        let fem = FemModel::new(grid, &Material::object_a());
        let k = GroupedStiffness::fem(&fem);
        let mut solver = SceneSolver::new(&grid, &k).unwrap();
        solver.factor(&k, &[1.0]).unwrap();
        let top = grid.position(grid.node(2, 3, 5));
        let r = 0.015;
        let a = solver.probe(&grid, [top[0], top[1], top[2] + r - 0.004], r).unwrap();
        assert_eq!(a.contacts.len(), 1);
        assert!(a.contacts.iter().all(|(_, l)| *l > 0.0));
        assert!(a.force[2] > 0.0, "the tissue pushes the probe up: {:?}", a.force);
        // The contact node sits on the sphere (linearised), to round-off.
        let p = a.contacts[0].0;
        assert!((a.u[3 * p + 2] + 0.004).abs() < 1e-12);
    }
}
