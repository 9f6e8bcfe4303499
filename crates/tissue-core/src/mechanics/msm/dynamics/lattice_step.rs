//! The lattices' implicit step's equation, solved by Newton's method on the rest factor.

use super::*;

/// The lattice's implicit step's equation for [`NewtonKrylov`], on the reduced unknowns: the
/// springs' tangent at the iterate (geometric parts clamped at zero), the rest factor as the
/// preconditioner, both with the held node's anchor.
pub(super) struct LatticeStep<'a> {
    pub(super) model: &'a MsmModel,
    pub(super) dofs: &'a DofMap,
    pub(super) system: &'a mut SpdSystem,
    pub(super) anchored: &'a AnchoredSolve,
    /// The held node's unknowns and what the anchor adds to their diagonal.
    pub(super) held: Option<Held>,
    /// `m + c_s c` of each unknown.
    pub(super) mass: &'a [f64],
    pub(super) x0: &'a [Vec<f64>; 3],
    pub(super) f0: &'a [Vec<f64>; 3],
    pub(super) v: &'a [Vec<f64>; 3],
    pub(super) f_ext: &'a [Vec<f64>; 3],
    /// The iterate's positions and forces.
    pub(super) x: &'a mut [Vec<f64>; 3],
    pub(super) f: &'a mut [Vec<f64>; 3],
    pub(super) p_nodes: &'a mut [Vec<f64>; 3],
    pub(super) out_nodes: &'a mut [Vec<f64>; 3],
    pub(super) scratch: &'a mut ForceScratch,
    /// `k` (stiffness), `v_s`, `w_n`, `w_e` and the position's scale `d` of `y`.
    pub(super) scales: [f64; 5],
}

impl StepEquation for LatticeStep<'_> {
    fn residual(&mut self, y: &[f64], r: &mut [f64]) {
        let [_, v_scale, w_n, w_e, d_scale] = self.scales;
        for (dof, &(u, _)) in self.dofs.map.iter().enumerate() {
            if u != u32::MAX {
                let (p, c) = (dof / 3, dof % 3);
                self.x[c][p] = self.x0[c][p] + d_scale * y[u as usize];
            }
        }
        for (f, f_ext) in self.f.iter_mut().zip(self.f_ext) {
            f.copy_from_slice(f_ext);
        }
        add_spring_forces(self.model, self.x, self.f, self.scratch);
        for (dof, &(u, _)) in self.dofs.map.iter().enumerate() {
            if u != u32::MAX {
                let (p, c, u) = (dof / 3, dof % 3, u as usize);
                let m = self.model.masses[p];
                r[u] = v_scale * m * self.v[c][p] + w_n * self.f0[c][p] + w_e * self.f[c][p] - self.mass[u] * y[u];
            }
        }
        if let Some(held) = self.held {
            held.add_to(y, -1.0, r);
        }
    }

    fn product(&mut self, p: &[f64], out: &mut [f64]) {
        let k_scale = self.scales[0];
        for (dof, &(u, _)) in self.dofs.map.iter().enumerate() {
            self.p_nodes[dof % 3][dof / 3] = if u == u32::MAX { 0.0 } else { p[u as usize] };
        }
        tangent_product(self.model, self.x, self.p_nodes, self.out_nodes, self.scratch);
        for (dof, &(u, _)) in self.dofs.map.iter().enumerate() {
            if u != u32::MAX {
                let u = u as usize;
                out[u] = k_scale * self.out_nodes[dof % 3][dof / 3] + self.mass[u] * p[u];
            }
        }
        if let Some(held) = self.held {
            held.add_to(p, 1.0, out);
        }
    }

    fn precondition(&mut self, z: &mut [f64]) -> Result<(), SparseError> {
        self.system.solve_in_place(z)?;
        if self.held.is_some() {
            self.anchored.correct(z);
        }
        Ok(())
    }
}
