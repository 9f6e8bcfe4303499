//! The hex8 FEM cube (linear or corotational, lumped masses, mass-proportional damping) as a
//! [`Tissue`]: the same tools, contact and blow-up guard act on it as on a spring lattice.
//!
//! The FEM's state is interleaved (`3 node + component`); the simulation's is component-wise
//! (`x[c][node]`). The component-wise copy is the state between steps. Both FEMs' symplectic
//! steps run on it directly ([`FemTissue::step_linear_symplectic`], the stencil's component-wise
//! product with the inclusions' elements added, and [`FemTissue::step_corotational_symplectic`], the corotated elements read
//! component-wise: no copies); every other step copies it in and out (no allocation).

use super::explicit_form::{ExplicitForm, ForceForm};
use super::integrator::Integrator;
use super::tissue::Tissue;
use crate::mechanics::cases::LoadCase;
use crate::mechanics::fem::FemModel;
use crate::mechanics::fem::dynamics::{FemDynamics, Formulation};
use crate::mechanics::grid::Grid;
use crate::mechanics::msm::MsmParams;
use crate::response::damping::Damping;
use crate::response::single_mode::damped_explicit_limit;

/// Why a FEM with inclusions has no GPU step.
const INCLUSIONS_CPU: &str = "a FEM with inclusions steps on the CPU (`cpu` or `cpu-f32`): the GPU step applies \
                              the homogeneous stencil only";

/// A FEM cube as a [`Tissue`].
#[derive(Debug)]
pub struct FemTissue {
    /// The FEM state and its step buffers.
    pub dynamics: FemDynamics,
    x: [Vec<f64>; 3],
    v: [Vec<f64>; 3],
    f_ext: [Vec<f64>; 3],
    forces: [Vec<f64>; 3],
    free: Vec<f64>,
    /// The displacement buffer of the component-wise step.
    u: [Vec<f64>; 3],
    /// `u` and `K u` in `f32` for the linear FEM's symplectic step, which takes `K u` in `f32`
    /// where they are sized ([`Tissue::set_single_precision`]; empty otherwise).
    u_f32: [Vec<f32>; 3],
    ku_f32: [Vec<f32>; 3],
    /// 1.0 for a free dof, 0.0 for a fixed one, component-wise.
    free_dofs: [Vec<f64>; 3],
    /// `1 / mass` of each node (its three dofs share it), 1/kg.
    inv_mass: Vec<f64>,
    /// The mass of each node, kg.
    node_mass: Vec<f64>,
    /// The explicit limits' `omega_max^2` ([`fem_stiffest`]), s^-2.
    omega_max_sq: f64,
    dt_limit: f64,
    total_mass: f64,
    density: f64,
    damping: Damping,
}

impl FemTissue {
    /// `material` on `grid` at rest, undamped until [`Tissue::set_damping_ratio`].
    pub fn new(grid: Grid, material: &crate::mechanics::material::Material, formulation: Formulation) -> Self {
        let model = FemModel::new(grid, material);
        let dynamics = FemDynamics::new(model, material.density, formulation, 0.0);
        let omega_max_sq = fem_stiffest(&dynamics.model, material.density, &dynamics.mass);
        let nn = grid.num_nodes();
        let split = |v: &[f64]| -> [Vec<f64>; 3] { std::array::from_fn(|c| (0..nn).map(|p| v[3 * p + c]).collect()) };
        Self {
            x: split(&dynamics.x),
            v: split(&dynamics.v),
            f_ext: split(&dynamics.f_ext),
            forces: std::array::from_fn(|_| vec![0.0; nn]),
            free: vec![1.0; nn],
            u: std::array::from_fn(|_| vec![0.0; nn]),
            u_f32: Default::default(),
            ku_f32: Default::default(),
            free_dofs: split(&dynamics.free),
            inv_mass: (0..nn).map(|p| dynamics.inv_mass[3 * p]).collect(),
            node_mass: (0..nn).map(|p| dynamics.mass[3 * p]).collect(),
            omega_max_sq,
            dt_limit: damped_explicit_limit(omega_max_sq.sqrt(), 0.0),
            total_mass: dynamics.mass.iter().sum::<f64>() / 3.0,
            density: material.density,
            damping: Damping::Nodal(0.0),
            dynamics,
        }
    }

    fn copy_in(&mut self) {
        let d = &mut self.dynamics;
        for c in 0..3 {
            for p in 0..self.free.len() {
                d.x[3 * p + c] = self.x[c][p];
                d.v[3 * p + c] = self.v[c][p];
                d.f_ext[3 * p + c] = self.f_ext[c][p];
            }
        }
    }

    /// One symplectic Euler step of the linear FEM on the component-wise state, the operations
    /// of [`FemDynamics::step_symplectic`] in the same order (the same bits): `u = x - X`,
    /// `v = (v + dt ((f_ext - K u) m^-1 - alpha v)) free`, `x += dt v`. Allocation-free.
    pub fn step_linear_symplectic(&mut self, dt: f64) {
        if !self.u_f32[0].is_empty() {
            return self.step_linear_symplectic_f32(dt);
        }
        let d = &self.dynamics;
        for c in 0..3 {
            for ((u, x), r) in self.u[c].iter_mut().zip(&self.x[c]).zip(&d.rest_components()[c]) {
                *u = x - r;
            }
        }
        d.model.apply_components(&self.u, &mut self.forces);
        self.advance_symplectic::<true>(dt);
    }

    /// [`FemTissue::step_linear_symplectic`] with `u` rounded to `f32` and `K u` summed in `f32`
    /// (the stencil's blocks rounded too), the rest in `f64`; with AVX2 where the CPU has it.
    /// Allocation-free.
    fn step_linear_symplectic_f32(&mut self, dt: f64) {
        let tissue = self;
        crate::mechanics::msm::forces::dispatch_avx2!(
            linear_f32_step,
            linear_f32_step_avx2,
            (tissue: &mut FemTissue, dt: f64)
        );
    }

    /// One symplectic Euler step of the corotational FEM on the component-wise state, the
    /// operations of [`FemDynamics::step_symplectic`] in the same order (the same bits), without
    /// moving the state into the FEM's interleaved layout and back. Allocation-free.
    pub fn step_corotational_symplectic(&mut self, dt: f64) {
        let x = [&self.x[0][..], &self.x[1][..], &self.x[2][..]];
        self.dynamics.corotated_forces_components(x, &self.f_ext, &mut self.forces);
        self.advance_symplectic::<false>(dt);
    }

    /// `v = (v + dt (f m^-1 - alpha v)) free`, `x += dt v`, with the total force `f` in
    /// `self.forces`, or (`LINEAR`) `f = f_ext - K u` with `K u` there (in the same pass, which
    /// then leaves the total force in `self.forces`).
    fn advance_symplectic<const LINEAR: bool>(&mut self, dt: f64) {
        let (alpha, n) = (self.dynamics.alpha, self.inv_mass.len());
        for c in 0..3 {
            // Every slice cut to `n`: no bounds checks, so the loop vectorises.
            let (x, v, f) = (&mut self.x[c][..n], &mut self.v[c][..n], &mut self.forces[c][..n]);
            let (f_ext, free, inv_mass) = (&self.f_ext[c][..n], &self.free_dofs[c][..n], &self.inv_mass[..n]);
            for p in 0..n {
                if LINEAR {
                    f[p] = f_ext[p] - f[p];
                }
                symplectic_update(&mut x[p], &mut v[p], f[p] * inv_mass[p], alpha, free[p], dt);
            }
        }
    }

    fn copy_out(&mut self) {
        for c in 0..3 {
            for p in 0..self.free.len() {
                self.x[c][p] = self.dynamics.x[3 * p + c];
                self.v[c][p] = self.dynamics.v[3 * p + c];
            }
        }
    }
}

/// The body of [`FemTissue::step_linear_symplectic_f32`], inlined into its AVX2 and plain
/// copies. The total force is not kept: [`Tissue::forces`] computes it when asked.
#[inline(always)]
fn linear_f32_step(t: &mut FemTissue, dt: f64) {
    let (d, n) = (&t.dynamics, t.inv_mass.len());
    for c in 0..3 {
        // Every slice cut to `n`: no bounds checks, so the loops vectorise.
        let (u, x, r) = (&mut t.u_f32[c][..n], &t.x[c][..n], &d.rest_components()[c][..n]);
        for p in 0..n {
            u[p] = (x[p] - r[p]) as f32;
        }
    }
    d.model.stencil().apply_components(&t.u_f32, &mut t.ku_f32);
    crate::mechanics::fem::inclusions::add_product_components_f32(d.model.patch(), &t.u_f32, &mut t.ku_f32);
    let alpha = d.alpha;
    for c in 0..3 {
        let (x, v) = (&mut t.x[c][..n], &mut t.v[c][..n]);
        let (f_ext, ku, free, inv_mass) = (&t.f_ext[c][..n], &t.ku_f32[c][..n], &t.free_dofs[c][..n], &t.inv_mass[..n]);
        for p in 0..n {
            symplectic_update(&mut x[p], &mut v[p], (f_ext[p] - f64::from(ku[p])) * inv_mass[p], alpha, free[p], dt);
        }
    }
}

/// A node's symplectic Euler update from its acceleration `a = f / m`: `v = (v + dt (a - alpha
/// v)) free`, `x += dt v`.
#[inline(always)]
fn symplectic_update(x: &mut f64, v: &mut f64, a: f64, alpha: f64, free: f64, dt: f64) {
    let vel = (*v + dt * (a - alpha * *v)) * free;
    *v = vel;
    *x += dt * vel;
}

/// The FEM cube's `omega_max^2` for its explicit limit, s^-2: the Lanczos upper estimate on the
/// linear stiffness with no dof held ([`crate::response::stiffest_mode`]; holding dofs only
/// lowers the largest eigenvalue), capped by the rigorous element bound `lambda_max(K_e) / m_e`.
/// That bound holds because the lumped masses are the elements' shares (`m_e = density h^3 / 8`
/// a node) summed, so `u^T K u = sum_e u_e^T K_e u_e <= (lambda_max(K_e) / m_e) u^T M u` for any
/// `u`; it is 1.9 times the true `omega_max^2` at 4^3, which the estimate finds within 0.1 %.
/// The corotational FEM rotates each `K_e`, which keeps its spectrum: the same limit.
fn fem_stiffest(model: &FemModel, density: f64, mass: &[f64]) -> f64 {
    use crate::response::stiffest_mode::{LIMIT_ITERATIONS, LIMIT_TOLERANCE, fem};
    let m_e = density * model.grid.h().powi(3) / 8.0;
    let element = model.stiffest_element() / m_e;
    let free = vec![true; mass.len()];
    let estimate = fem(model, mass, &free, LIMIT_TOLERANCE, LIMIT_ITERATIONS).upper();
    estimate.min(element)
}

impl Tissue for FemTissue {
    fn explicit_form(&self) -> Result<ExplicitForm, String> {
        let d = &self.dynamics;
        if d.formulation != Formulation::Linear {
            return Err("the corotational FEM has no GPU step (its rotations are per element): \
                        the lattices and the linear FEM have one"
                .into());
        }
        if !d.model.patch().is_empty() {
            return Err(INCLUSIONS_CPU.into());
        }
        let nn = self.free.len();
        Ok(ExplicitForm {
            grid: d.model.grid,
            force: ForceForm::Stencil(d.model.stencil().blocks().to_vec()),
            inv_mass: (0..nn).map(|p| 1.0 / d.mass[3 * p]).collect(),
            damping_rate: vec![d.alpha; nn],
            free: std::array::from_fn(|c| (0..nn).map(|p| d.free[3 * p + c]).collect()),
        })
    }
    fn newton_solves(&self) -> Option<crate::mechanics::newton_krylov::NewtonSolves> {
        self.dynamics.newton_solves()
    }
    fn set_single_precision(&mut self, single: bool) -> Result<(), String> {
        if single && self.dynamics.formulation != Formulation::Linear {
            return Err("the corotational FEM has no f32 step (its rotations are per element): the lattices and the linear FEM \
                        have one".into());
        }
        let nn = if single { self.free.len() } else { 0 };
        for buffer in self.u_f32.iter_mut().chain(&mut self.ku_f32) {
            buffer.resize(nn, 0.0);
        }
        Ok(())
    }
    fn set_anchor(&mut self, anchor: Option<crate::mechanics::anchor::Anchor>) -> bool {
        self.dynamics.anchor = anchor;
        true
    }
    fn modal(&self) -> Result<crate::response::modal::ModalModel, String> {
        Ok(crate::response::modal::ModalModel::fem(&self.dynamics.model, self.density))
    }
    fn grid(&self) -> Grid {
        self.dynamics.model.grid
    }
    fn total_mass(&self) -> f64 {
        self.total_mass
    }
    fn node_mass(&self, p: usize) -> f64 {
        self.node_mass[p]
    }
    fn x(&self) -> &[Vec<f64>; 3] {
        &self.x
    }
    fn x_mut(&mut self) -> &mut [Vec<f64>; 3] {
        &mut self.x
    }
    fn v(&self) -> &[Vec<f64>; 3] {
        &self.v
    }
    fn v_mut(&mut self) -> &mut [Vec<f64>; 3] {
        &mut self.v
    }
    fn x_v_mut(&mut self) -> (&mut [Vec<f64>; 3], &mut [Vec<f64>; 3]) {
        (&mut self.x, &mut self.v)
    }
    fn f_ext_mut(&mut self) -> &mut [Vec<f64>; 3] {
        &mut self.f_ext
    }
    fn free(&self) -> &[f64] {
        &self.free
    }
    fn forces(&mut self) -> &[Vec<f64>; 3] {
        if self.dynamics.formulation == Formulation::Corotational {
            let x = [&self.x[0][..], &self.x[1][..], &self.x[2][..]];
            self.dynamics.corotated_forces_components(x, &self.f_ext, &mut self.forces);
            return &self.forces;
        }
        self.copy_in();
        let f = self.dynamics.forces();
        for c in 0..3 {
            for (p, out) in self.forces[c].iter_mut().enumerate() {
                *out = f[3 * p + c];
            }
        }
        &self.forces
    }
    fn step(&mut self, integrator: Integrator, dt: f64) -> Result<(), String> {
        if integrator == Integrator::Symplectic {
            match self.dynamics.formulation {
                Formulation::Linear => self.step_linear_symplectic(dt),
                Formulation::Corotational => self.step_corotational_symplectic(dt),
            }
            return Ok(());
        }
        self.copy_in();
        match integrator {
            Integrator::Symplectic => self.dynamics.step_symplectic(dt),
            Integrator::Prefactored => self.dynamics.step_prefactored(dt).map_err(|e| e.to_string())?,
            Integrator::Newmark => self.dynamics.step_newmark(dt).map_err(|e| e.to_string())?,
            Integrator::Implicit => return check_integrator(integrator),
        }
        self.copy_out();
        Ok(())
    }
    fn kinetic_energy(&self) -> f64 {
        crate::mechanics::kinetic::kinetic_energy(&self.node_mass, &self.v)
    }
    fn explicit_dt_limit(&self) -> f64 {
        self.dt_limit
    }
    fn step_limit(&self) -> super::integrator::StepLimit {
        match self.dynamics.formulation {
            Formulation::Linear => super::integrator::StepLimit::constant_stiffness(self.dt_limit),
            Formulation::Corotational => super::integrator::StepLimit::tissue(self.dt_limit),
        }
    }
    fn apply_case(&mut self, case: &LoadCase) {
        self.copy_in();
        self.dynamics.apply_case(case);
        for (p, f) in self.free.iter_mut().enumerate() {
            *f = if case.fixed[3 * p..3 * p + 3].iter().all(|&x| x) { 0.0 } else { 1.0 };
        }
        for c in 0..3 {
            for p in 0..self.free.len() {
                self.free_dofs[c][p] = self.dynamics.free[3 * p + c];
            }
        }
        for c in 0..3 {
            for p in 0..self.free.len() {
                self.f_ext[c][p] = case.load[3 * p + c];
            }
        }
    }
    fn params(&self) -> Option<MsmParams> {
        None
    }
    fn set_params(&mut self, _params: MsmParams) -> Result<(), String> {
        Err("a FEM model has no spring parameters".into())
    }
    fn set_damping_ratio(&mut self, zeta: f64) -> Result<(), String> {
        let zeta = crate::response::damping::check_ratio(zeta)?;
        let omega_1 = match self.damping.omega_1() {
            Some(w) => w,
            None => crate::response::modal::scene_fundamental(&crate::response::modal::ModalModel::fem(
                &self.dynamics.model,
                self.density,
            ))?,
        };
        self.damping = Damping::Ratio { zeta, omega_1 };
        self.dynamics.alpha = self.damping.rate();
        self.dt_limit = damped_explicit_limit(self.omega_max_sq.sqrt(), self.dynamics.alpha);
        Ok(())
    }
    fn damping(&self) -> Damping {
        self.damping
    }
}

/// The FEM steps with symplectic or prefactored implicit Euler; a full-tangent implicit step is
/// refused with this message.
pub fn check_integrator(integrator: Integrator) -> Result<(), String> {
    match integrator {
        Integrator::Implicit => {
            Err("the FEM models step with symplectic or prefactored implicit Euler, not implicit".into())
        }
        Integrator::Symplectic | Integrator::Prefactored | Integrator::Newmark => Ok(()),
    }
}

#[cfg(test)]
mod tests;
