//! The corotational FEM's implicit step: Newton's method on the step's equation, each solve by
//! conjugate gradients on the stiffness warped by the elements' rotations, preconditioned by the
//! rest factor.

use super::*;

/// The corotational implicit steps' solver ([`crate::mechanics::newton_krylov`]) and buffers
/// (interleaved).
#[derive(Debug)]
pub(super) struct Krylov {
    pub(super) newton: NewtonKrylov,
    /// The step's start positions and force.
    pub(super) x0: Vec<f64>,
    pub(super) f0: Vec<f64>,
}

/// The corotational implicit step's equation for [`NewtonKrylov`]: the tangent is the stiffness
/// warped by the elements' rotations of the last force evaluation, `K_w = sum_e R_e K_e R_e^T`
/// (Mueller et al. 2002), the preconditioner the rest factor, both with the held node's anchor.
pub(super) struct CorotationalStep<'a> {
    fem: &'a mut FemDynamics,
    factor: &'a mut Factor,
    pub(super) x0: &'a [f64],
    pub(super) f0: &'a [f64],
    /// `a` (mass), `k` (stiffness), `v_s`, `w_n`, `w_e` and the position's scale `d` of `y`.
    scales: [f64; 6],
}

impl StepEquation for CorotationalStep<'_> {
    fn residual(&mut self, y: &[f64], r: &mut [f64]) {
        let [a, _, v_scale, w_n, w_e, d_scale] = self.scales;
        let fem = &mut *self.fem;
        for i in 0..y.len() {
            fem.x[i] = self.x0[i] + d_scale * y[i] * fem.free[i];
        }
        fem.compute_forces();
        for i in 0..y.len() {
            r[i] = (v_scale * fem.mass[i] * fem.v[i] + w_n * self.f0[i] + w_e * fem.f[i] - a * fem.mass[i] * y[i])
                * fem.free[i];
        }
        self.factor.add_held(y, -1.0, r);
    }

    fn product(&mut self, p: &[f64], out: &mut [f64]) {
        let [a, k_scale, ..] = self.scales;
        self.fem.warped_system_product(p, a, k_scale, out);
        self.factor.add_held(p, 1.0, out);
    }

    fn precondition(&mut self, z: &mut [f64]) -> Result<(), SparseError> {
        self.factor.solve(z)
    }
}

impl FemDynamics {
    /// The corotational implicit step's unknown `y` (`dx` for the trapezoidal rule, `v'` for
    /// backward Euler) from its linearised right-hand side `b` (given in `y`), by Newton's method
    /// on the warped stiffness ([`crate::mechanics::newton_krylov`]). The positions are the
    /// step's start again on return.
    pub(super) fn corotational_solve(
        &mut self,
        factor: &mut Factor,
        y: &mut [f64],
        k: &mut Krylov,
        dt: f64,
        trapezoidal: bool,
    ) -> Result<(), SparseError> {
        let (c_scale, k_scale) = implicit_scales(dt, trapezoidal);
        let a = 1.0 + c_scale * self.alpha;
        let (v_scale, w_n, w_e) = if trapezoidal { (dt, 0.25 * dt * dt, 0.25 * dt * dt) } else { (1.0, 0.0, dt) };
        let d_scale = if trapezoidal { 1.0 } else { dt };
        // The residual's scale: the sizes of the equation's terms, which stay finite at rest
        // (where `b` itself vanishes and round-off in the elastic force would dominate it).
        let scale = (0..y.len())
            .map(|i| {
                let t =
                    v_scale * (self.mass[i] * self.v[i]).abs() + (w_n + w_e) * (self.f[i].abs() + self.f_ext[i].abs());
                (t * self.free[i]).powi(2)
            })
            .sum::<f64>()
            .sqrt();
        k.x0.copy_from_slice(&self.x);
        k.f0.copy_from_slice(&self.f);
        k.newton.krylov_max = self.krylov_iterations;
        k.newton.newton_max = self.newton_iterations;
        let Krylov { newton, x0, f0 } = k;
        let mut step = CorotationalStep { fem: self, factor, x0, f0, scales: [a, k_scale, v_scale, w_n, w_e, d_scale] };
        let solved = newton.solve(&mut step, y, scale);
        self.x.copy_from_slice(&k.x0);
        solved
    }

    /// `out = (m_scale M p + k_scale K_w p)` on the free dofs (0 on the fixed ones), `K_w` the
    /// stiffness warped by each element's rotation of the last force evaluation: the element
    /// kernel on a rest shape of zero size, with no iteration of the rotations.
    pub(super) fn warped_system_product(&mut self, p: &[f64], m_scale: f64, k_scale: f64, out: &mut [f64]) {
        for (n, p) in p.chunks_exact(3).enumerate() {
            for c in 0..3 {
                self.x_components[c][n] = p[c];
            }
        }
        let at = Corotation {
            x: [&self.x_components[0], &self.x_components[1], &self.x_components[2]],
            rest_spacing: 0.0,
            ke: &self.model.ke,
            parity: self.parity.as_ref(),
            grid: self.model.grid,
            iterations: 0,
            tolerance: self.rotation_tolerance,
        };
        // No iteration: `next_rotations` receives the rotations unchanged and is not swapped in.
        for f in &mut self.f_components {
            f.fill(0.0);
        }
        at.all(&self.rotations, &mut self.next_rotations, &mut self.f_components, self.parallel);
        at.patched(self.model.patch(), &self.rotations, &mut self.f_components);
        for (n, out) in out.chunks_exact_mut(3).enumerate() {
            for c in 0..3 {
                out[c] = -self.f_components[c][n];
            }
        }
        for i in 0..out.len() {
            out[i] = (k_scale * out[i] + m_scale * self.mass[i] * p[i]) * self.free[i];
        }
    }
}
