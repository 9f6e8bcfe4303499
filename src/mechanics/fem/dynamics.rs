//! Finite-element dynamics of the cube: linear and corotational hex8 elements with lumped masses,
//! symplectic Euler and a prefactored backward Euler step.
//!
//! Linear elements compute `f = -K u`: exact for small displacements, but a rigid rotation
//! produces strain and force (the body swells when it turns). Corotational elements take out
//! each element's rotation `R` (polar decomposition of the deformation gradient at its centre,
//! updated incrementally: [`super::corotation`]) and compute `f_e = -R K_e (R^T x_e - X_e)`,
//! which is zero for any rigid motion. The implicit
//! steps factorise `M (1 + dt alpha) + dt^2 K` (or the trapezoidal rule's matrix) once, with the
//! linear stiffness, so for the linear model each is one exact solve. The corotational model
//! solves its step's nonlinear equation by Newton's method on the stiffness warped by the
//! elements' rotations (Mueller et al. 2002: `K_w = sum_e R_e K_e R_e^T`), each linear solve by
//! conjugate gradients preconditioned with the rest factor ([`NewtonSolves`] counts both). A
//! held node ([`FemDynamics::anchor`]) is carried inside the implicit steps' solves
//! ([`crate::mechanics::anchor`]). No step allocates.

use super::FemModel;
use super::corotation::{Corotation, IDENTITY, ParityBlocks};
use crate::mechanics::anchor::{Anchor, AnchoredSolve, Held};
use crate::mechanics::newton_krylov::{
    KRYLOV_MAX_ITERATIONS, NEWTON_MAX_ITERATIONS, NewtonKrylov, NewtonSolves, StepEquation,
};
use crate::mechanics::sparse::{SparseError, SpdSystem};

/// How element forces are computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Formulation {
    /// Small-strain linear elasticity, `f = -K u`.
    Linear,
    /// Corotational: linear elasticity in each element's rotated frame.
    Corotational,
}

impl Formulation {
    /// The lower-case name used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Formulation::Linear => "linear",
            Formulation::Corotational => "corotational",
        }
    }
}

/// The state of a running FEM cube and the buffers its steps use. Vectors are interleaved,
/// `3 node + component`.
#[derive(Debug)]
pub struct FemDynamics {
    /// Element model.
    pub model: FemModel,
    /// Force computation.
    pub formulation: Formulation,
    /// Positions, metres.
    pub x: Vec<f64>,
    /// Velocities, m/s.
    pub v: Vec<f64>,
    /// External nodal forces, newtons.
    pub f_ext: Vec<f64>,
    /// Lumped mass of each dof, kg.
    pub mass: Vec<f64>,
    /// `1 / mass`, 1/kg.
    pub inv_mass: Vec<f64>,
    /// Mass-proportional damping `C = alpha M`, 1/s.
    pub alpha: f64,
    /// 1.0 for a free dof, 0.0 for a fixed one.
    pub free: Vec<f64>,
    rest: Vec<f64>,
    f: Vec<f64>,
    u: Vec<f64>,
    /// Per element: the rotation (a unit quaternion `[w, x, y, z]`) of the last force
    /// evaluation (warm start of the next), and the buffer the next one writes.
    rotations: Vec<[f64; 4]>,
    next_rotations: Vec<[f64; 4]>,
    /// Positions component-wise (`[c][node]`), for the corotated elements.
    x_components: [Vec<f64>; 3],
    /// Rest positions component-wise, for a step on component-wise state.
    rest_components: [Vec<f64>; 3],
    /// The element matrix in the corners' parity basis, where it has that form.
    parity: Option<ParityBlocks>,
    /// The force on every node, component-wise (`[c][node]`), where the corotated elements'
    /// forces are summed (and the warped product `K_w p` is, negated).
    f_components: [Vec<f64>; 3],
    /// Whether the element loop may use the physics pool ([`crate::mechanics::parallel`]).
    pub parallel: bool,
    /// The most iterations of each element's rotation update per force evaluation
    /// ([`ROTATION_ITERATIONS`] by default).
    pub rotation_iterations: usize,
    /// Where the update stops: every correction at most this, radians ([`ROTATION_TOLERANCE`]
    /// by default).
    pub rotation_tolerance: f64,
    /// The most conjugate-gradient iterations of the corotational implicit steps' warped solve
    /// ([`KRYLOV_MAX_ITERATIONS`] by default; 0 keeps the rest factor's solve: the Jacobian
    /// frozen at rest).
    pub krylov_iterations: usize,
    /// The most Newton corrections of a corotational implicit step ([`NEWTON_MAX_ITERATIONS`] by
    /// default; 0 keeps the linearised step).
    pub newton_iterations: usize,
    /// A node held by a spring and damper, carried inside the implicit steps' solves (its pull at
    /// the step's start is the caller's, in `f_ext`); the symplectic step leaves it to its
    /// caller. Ignored on a fixed node.
    pub anchor: Option<Anchor>,
    /// The implicit steps' factor and buffers.
    implicit: Option<Implicit>,
}

/// The factor of an implicit step and its buffers.
#[derive(Debug)]
struct Implicit {
    /// The factor, corrected for the anchor.
    factor: Factor,
    /// The right-hand side, then the solution.
    rhs: Vec<f64>,
    /// The `(dt, alpha, trapezoidal)` it was built for.
    key: (f64, f64, bool),
    /// The conjugate gradients' buffers, for the corotational model.
    krylov: Option<Krylov>,
}

/// `M (1 + c alpha) + k K` on the free dofs, the fixed ones decoupled, factorised, and its
/// correction for the held node.
#[derive(Debug)]
struct Factor {
    system: SpdSystem,
    anchored: AnchoredSolve,
    /// This step's held node.
    held: Option<Held>,
}

impl Factor {
    /// Solves the anchored system in place.
    fn solve(&mut self, y: &mut [f64]) -> Result<(), SparseError> {
        self.system.solve_in_place(y)?;
        if self.held.is_some() {
            self.anchored.correct(y);
        }
        Ok(())
    }

    /// Adds the anchor's `d y` on the held node's dofs to `out`, scaled by `sign`.
    fn add_held(&self, y: &[f64], sign: f64, out: &mut [f64]) {
        if let Some(held) = self.held {
            held.add_to(y, sign, out);
        }
    }
}

/// The corotational implicit steps' solver ([`crate::mechanics::newton_krylov`]) and buffers
/// (interleaved).
#[derive(Debug)]
struct Krylov {
    newton: NewtonKrylov,
    /// The step's start positions and force.
    x0: Vec<f64>,
    f0: Vec<f64>,
}

/// The corotational implicit step's equation for [`NewtonKrylov`]: the tangent is the stiffness
/// warped by the elements' rotations of the last force evaluation, `K_w = sum_e R_e K_e R_e^T`
/// (Mueller et al. 2002), the preconditioner the rest factor, both with the held node's anchor.
struct CorotationalStep<'a> {
    fem: &'a mut FemDynamics,
    factor: &'a mut Factor,
    x0: &'a [f64],
    f0: &'a [f64],
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
    /// The cube at rest with lumped masses (`density h^3 / 8` from each element at a node).
    pub fn new(model: FemModel, density: f64, formulation: Formulation, alpha: f64) -> Self {
        let g = model.grid;
        let dofs = 3 * g.num_nodes();
        let rest: Vec<f64> = (0..g.num_nodes()).flat_map(|p| g.position(p)).collect();
        let mut mass = vec![0.0; dofs];
        let m_e = density * g.h().powi(3) / 8.0;
        for nodes in model.elements() {
            for &p in nodes {
                for c in 0..3 {
                    mass[3 * p + c] += m_e;
                }
            }
        }
        let inv_mass = mass.iter().map(|m| 1.0 / m).collect();
        let parity = ParityBlocks::of(&model.ke);
        let elements = model.elements().len();
        Self {
            model,
            formulation,
            x: rest.clone(),
            v: vec![0.0; dofs],
            f_ext: vec![0.0; dofs],
            mass,
            inv_mass,
            alpha,
            free: vec![1.0; dofs],
            rest,
            f: vec![0.0; dofs],
            u: vec![0.0; dofs],
            rotations: vec![IDENTITY; elements],
            next_rotations: vec![IDENTITY; elements],
            x_components: std::array::from_fn(|_| vec![0.0; g.num_nodes()]),
            rest_components: std::array::from_fn(|c| (0..g.num_nodes()).map(|p| g.position(p)[c]).collect()),
            parity,
            f_components: std::array::from_fn(|_| vec![0.0; g.num_nodes()]),
            parallel: true,
            rotation_iterations: ROTATION_ITERATIONS,
            rotation_tolerance: ROTATION_TOLERANCE,
            krylov_iterations: KRYLOV_MAX_ITERATIONS,
            newton_iterations: NEWTON_MAX_ITERATIONS,
            anchor: None,
            implicit: None,
        }
    }

    /// Fixes dofs and sets the loads of a case (the state is kept).
    pub fn apply_case(&mut self, case: &crate::mechanics::cases::LoadCase) {
        for (f, &fixed) in self.free.iter_mut().zip(&case.fixed) {
            *f = if fixed { 0.0 } else { 1.0 };
        }
        self.f_ext.copy_from_slice(&case.load);
        self.implicit = None;
    }

    /// Rest positions, interleaved.
    pub fn rest(&self) -> &[f64] {
        &self.rest
    }

    /// Rest positions, component-wise (`[c][node]`).
    pub fn rest_components(&self) -> &[Vec<f64>; 3] {
        &self.rest_components
    }

    /// Displacements from rest, interleaved.
    pub fn displacement(&self, out: &mut [f64]) {
        for ((o, x), r) in out.iter_mut().zip(&self.x).zip(&self.rest) {
            *o = x - r;
        }
    }

    /// Elastic + external force at the current positions, into `self.f`.
    fn compute_forces(&mut self) {
        match self.formulation {
            Formulation::Linear => {
                for ((u, x), r) in self.u.iter_mut().zip(&self.x).zip(&self.rest) {
                    *u = x - r;
                }
                self.model.apply(&self.u, &mut self.f);
                for (f, fe) in self.f.iter_mut().zip(&self.f_ext) {
                    *f = fe - *f;
                }
            }
            Formulation::Corotational => {
                for (p, x) in self.x.chunks_exact(3).enumerate() {
                    for c in 0..3 {
                        self.x_components[c][p] = x[c];
                    }
                }
                for (p, f) in self.f_ext.chunks_exact(3).enumerate() {
                    for c in 0..3 {
                        self.f_components[c][p] = f[c];
                    }
                }
                // Moved out while the elements read and write them, and back (moves only: no
                // allocation).
                let (x, mut f) = (std::mem::take(&mut self.x_components), std::mem::take(&mut self.f_components));
                self.corotated_elements([&x[0], &x[1], &x[2]], &mut f);
                (self.x_components, self.f_components) = (x, f);
                for (p, f) in self.f.chunks_exact_mut(3).enumerate() {
                    for c in 0..3 {
                        f[c] = self.f_components[c][p];
                    }
                }
            }
        }
    }

    /// Every element's rotation moved on and `out[c][node] -= ` its corotated force, at the
    /// component-wise positions `x`.
    fn corotated_elements(&mut self, x: [&[f64]; 3], out: &mut [Vec<f64>; 3]) {
        let at = Corotation {
            x,
            rest_spacing: self.model.grid.h(),
            ke: &self.model.ke,
            parity: self.parity.as_ref(),
            grid: self.model.grid,
            iterations: self.rotation_iterations,
            tolerance: self.rotation_tolerance,
        };
        at.all(&self.rotations, &mut self.next_rotations, out, self.parallel);
        std::mem::swap(&mut self.rotations, &mut self.next_rotations);
    }

    /// The corotational elastic + external force at the component-wise positions `x`, from the
    /// component-wise external forces `f_ext`, into `out` (`[c][node]`): the operations of the
    /// interleaved force in the same order (the same bits), for a step on component-wise state.
    /// Allocation-free.
    pub fn corotated_forces_components(&mut self, x: [&[f64]; 3], f_ext: &[Vec<f64>; 3], out: &mut [Vec<f64>; 3]) {
        for (out, f_ext) in out.iter_mut().zip(f_ext) {
            out.copy_from_slice(f_ext);
        }
        self.corotated_elements(x, out);
    }

    /// The elastic + external force at the current positions.
    pub fn forces(&mut self) -> &[f64] {
        self.compute_forces();
        &self.f
    }

    /// One symplectic Euler step: `v += dt (f / m - alpha v)`, `x += dt v` (`1 / m` kept, no
    /// division). Allocation-free.
    pub fn step_symplectic(&mut self, dt: f64) {
        self.compute_forces();
        for i in 0..self.x.len() {
            let v = (self.v[i] + dt * (self.f[i] * self.inv_mass[i] - self.alpha * self.v[i])) * self.free[i];
            self.v[i] = v;
            self.x[i] += dt * v;
        }
    }

    /// One backward Euler step with the linear stiffness factorised once per `dt`:
    /// `(M (1 + dt alpha) + dt^2 K) v' = M v + dt f(x)`, `x += dt v'`. Exact backward Euler for the
    /// linear model; for the corotational one the step's equation with the force at its end is
    /// solved by Newton's method on the warped stiffness `K_w`, by conjugate gradients on the
    /// rest factor ([`NewtonSolves`]). The first step (or a new `dt`) factorises; later steps
    /// allocate nothing.
    pub fn step_prefactored(&mut self, dt: f64) -> Result<(), SparseError> {
        self.prefactored_step(dt, false)
    }

    /// One step of Newmark's average acceleration (the trapezoidal rule: no numerical damping,
    /// second order) with the linear stiffness factorised once per `dt`:
    /// `(M (1 + dt alpha / 2) + dt^2 / 4 K) dx = dt M v + dt^2 / 2 f(x)`, `v' = 2 dx / dt - v`,
    /// `x += dx`. Exact trapezoidal steps for the linear model; for the corotational one the
    /// step's equation with the force at its end (`f(x) + f(x + dx)` for `2 f(x)`) is solved by
    /// Newton's method on the warped stiffness `K_w`, by conjugate gradients on the rest factor
    /// ([`NewtonSolves`]): the iterations bounded and counted.
    pub fn step_newmark(&mut self, dt: f64) -> Result<(), SparseError> {
        self.prefactored_step(dt, true)
    }

    fn prefactored_step(&mut self, dt: f64, trapezoidal: bool) -> Result<(), SparseError> {
        let key = (dt, self.alpha, trapezoidal);
        // Moved out while the forces are computed and the system solved, and back in (moves
        // only: no allocation).
        let mut work = match self.implicit.take() {
            Some(work) if work.key == key => work,
            stale => {
                self.implicit = stale; // kept if the new factorisation fails
                let dofs = self.x.len();
                Implicit {
                    factor: Factor {
                        system: self.prefactored_system(dt, trapezoidal)?,
                        anchored: AnchoredSolve::new(dofs),
                        held: None,
                    },
                    rhs: vec![0.0; dofs],
                    key,
                    krylov: (self.formulation == Formulation::Corotational).then(|| Krylov {
                        newton: NewtonKrylov::new(dofs, self.krylov_iterations, self.newton_iterations),
                        x0: vec![0.0; dofs],
                        f0: vec![0.0; dofs],
                    }),
                }
            }
        };
        // Held where any of the node's dofs is free (a fixed dof's row is decoupled, its
        // unknown stays 0 with the anchor's diagonal too).
        let held = self
            .anchor
            .filter(|a| self.free.get(3 * a.node..3 * a.node + 3).is_some_and(|f| f.iter().any(|&f| f != 0.0)))
            .map(|a| {
                let (c_scale, k_scale) = implicit_scales(dt, trapezoidal);
                Held { unknowns: std::array::from_fn(|c| 3 * a.node + c), diagonal: a.diagonal(c_scale, k_scale) }
            });
        work.factor.held = held;
        if let Some(held) = held
            && let Err(e) = work.factor.anchored.prepare(&mut work.factor.system, held)
        {
            self.implicit = Some(work);
            return Err(e);
        }
        self.compute_forces();
        let (v_scale, f_scale) = if trapezoidal { (dt, 0.5 * dt * dt) } else { (1.0, dt) };
        for i in 0..work.rhs.len() {
            work.rhs[i] = (v_scale * self.mass[i] * self.v[i] + f_scale * self.f[i]) * self.free[i];
        }
        let solved = match work.krylov.as_mut() {
            Some(krylov) => self.corotational_solve(&mut work.factor, &mut work.rhs, krylov, dt, trapezoidal),
            None => work.factor.solve(&mut work.rhs),
        };
        let work = self.implicit.insert(work);
        solved?;
        for i in 0..work.rhs.len() {
            let solved = work.rhs[i] * self.free[i];
            if trapezoidal {
                self.v[i] = (2.0 * solved / dt - self.v[i]) * self.free[i];
                self.x[i] += solved;
            } else {
                self.v[i] = solved;
                self.x[i] += dt * solved;
            }
        }
        Ok(())
    }

    /// The corotational implicit step's unknown `y` (`dx` for the trapezoidal rule, `v'` for
    /// backward Euler) from its linearised right-hand side `b` (given in `y`), by Newton's method
    /// on the warped stiffness ([`crate::mechanics::newton_krylov`]). The positions are the
    /// step's start again on return.
    fn corotational_solve(
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
    fn warped_system_product(&mut self, p: &[f64], m_scale: f64, k_scale: f64, out: &mut [f64]) {
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
        for (n, out) in out.chunks_exact_mut(3).enumerate() {
            for c in 0..3 {
                out[c] = -self.f_components[c][n];
            }
        }
        for i in 0..out.len() {
            out[i] = (k_scale * out[i] + m_scale * self.mass[i] * p[i]) * self.free[i];
        }
    }

    /// What the corotational implicit steps' solves have done since their factor was built
    /// (`None` before the first implicit step, or for the linear model).
    pub fn newton_solves(&self) -> Option<NewtonSolves> {
        self.implicit.as_ref()?.krylov.as_ref().map(|k| k.newton.solves)
    }

    /// `M (1 + dt alpha) + dt^2 K` (backward Euler) or `M (1 + dt alpha / 2) + dt^2 / 4 K` (the
    /// trapezoidal rule) with the fixed dofs decoupled, factorised.
    fn prefactored_system(&self, dt: f64, trapezoidal: bool) -> Result<SpdSystem, SparseError> {
        let (c_scale, k_scale) = implicit_scales(dt, trapezoidal);
        let (entries, values) = self.model.stiffness_entries();
        let (mut system, slots) = SpdSystem::on_grid(self.x.len(), &entries, &self.model.grid.dof_nodes())?;
        for (slot, v) in slots.iter().zip(values) {
            system.add(*slot, k_scale * v);
        }
        system.add_diagonal_scaled(1.0 + c_scale * self.alpha, &self.mass);
        let fixed: Vec<bool> = self.free.iter().map(|&f| f == 0.0).collect();
        system.decouple(&fixed, 1.0);
        system.factor()?;
        Ok(system)
    }

    /// Kinetic energy, joules.
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.v.iter().zip(&self.mass).map(|(v, m)| m * v * v).sum::<f64>()
    }

    /// Bytes held by the prefactored step's factor (0 before its first step).
    pub fn factor_memory_bytes(&self) -> usize {
        self.implicit.as_ref().map_or(0, |w| {
            // The solver's vectors and the step's start (two vectors).
            let krylov = w.krylov.as_ref().map_or(0, |k| k.newton.memory_bytes() + 2 * k.x0.len() * 8);
            w.factor.system.memory_bytes() + w.factor.anchored.memory_bytes() + w.rhs.len() * 8 + krylov
        })
    }

    /// Bytes held by the state, the element data and the factor (if built).
    pub fn memory_bytes(&self) -> usize {
        let vectors = 8 * self.x.len() * 8
            + self.rotations.len() * 64
            + self.model.elements().len() * 64
            + 9 * 8 * self.rest.len() / 3
            + 24 * 24 * 8;
        vectors + self.factor_memory_bytes()
    }
}

/// The implicit step's `(c, k)` in `M (1 + c alpha) + k K`: `(dt, dt^2)` for backward Euler,
/// `(dt / 2, dt^2 / 4)` for the trapezoidal rule.
fn implicit_scales(dt: f64, trapezoidal: bool) -> (f64, f64) {
    if trapezoidal { (0.5 * dt, 0.25 * dt * dt) } else { (dt, dt * dt) }
}

/// The most iterations of the rotation extraction per force evaluation, from the last
/// evaluation's rotation ([`FemDynamics::rotation_iterations`]'s default). Each element's update
/// runs until its correction is below [`ROTATION_TOLERANCE`] (four elements at a time), so a
/// still element costs one check and a fast-turning one as many iterations as it takes.
///
/// A rotation left lagging behind the polar rotation feeds energy in: at 16^3 (object A, damping
/// ratio 0.2, bottom clamp, 4 symplectic substeps of the 1 ms tick) with the top corner dragged
/// 4 cm up and outwards over 0.1 s and held, a fixed 2 iterations a step rang at 9.9 m/s for
/// the whole second held, a fixed 6 grew from 2 mm/s to 0.63 m/s, and stopping at 1e-6 rad
/// left a 1 mm/s ringing; iterated to 1e-8 rad the cube comes to rest. During that drag the
/// updates took 6.1 iterations on average and at most 18; held still, 0.09. Those counts are
/// of Mueller's fixed-point step; with Newton's (`corotation::newton_half_turn`, since
/// 2026-12-04), in the bench sweep's press at 16^3, a group of four elements took 0.99 updates
/// a step over the press and hold against Mueller's 6.4, and 1.00 against 3.9 in the next 0.2 s.
pub const ROTATION_ITERATIONS: usize = 20;
/// Where the rotation extraction stops: every correction of four elements at most this, radians
/// ([`FemDynamics::rotation_tolerance`]'s default; see [`ROTATION_ITERATIONS`]).
pub const ROTATION_TOLERANCE: f64 = 1e-8;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::grid::Grid;
    use crate::mechanics::material::Material;
    use crate::mechanics::newton_krylov::{KRYLOV_TOLERANCE, NEWTON_TOLERANCE};

    /// The rotation by `angle` about the unit axis `(1, 2, 2) / 3`, row-major.
    fn rotation(angle: f64) -> [[f64; 3]; 3] {
        let k = [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
        let (s, c) = angle.sin_cos();
        std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                let cross = match (i, j) {
                    (0, 1) => -k[2],
                    (0, 2) => k[1],
                    (1, 0) => k[2],
                    (1, 2) => -k[0],
                    (2, 0) => -k[1],
                    (2, 1) => k[0],
                    _ => 0.0,
                };
                let delta = if i == j { 1.0 } else { 0.0 };
                c * delta + s * cross + (1.0 - c) * k[i] * k[j]
            })
        })
    }

    fn rotate(r: &[[f64; 3]; 3], v: &[f64], transpose: bool) -> Vec<f64> {
        v.chunks_exact(3)
            .flat_map(|v| {
                let row = |i: usize| (0..3).map(|j| if transpose { r[j][i] } else { r[i][j] } * v[j]).sum::<f64>();
                [row(0), row(1), row(2)]
            })
            .collect()
    }

    /// A corotational cube of object B (orthotropic) on 4^3, turned rigidly by `r` about its
    /// centre, its rotations converged.
    fn turned(r: &[[f64; 3]; 3]) -> FemDynamics {
        let m = Material::object_b();
        let grid = Grid::new(4).unwrap();
        let mut fem = FemDynamics::new(FemModel::new(grid, &m), m.density, Formulation::Corotational, 0.0);
        let centred: Vec<f64> = fem.rest.iter().map(|x| x - 0.05).collect();
        for (x, t) in fem.x.iter_mut().zip(rotate(r, &centred, false)) {
            *x = t + 0.05;
        }
        for _ in 0..20 {
            fem.forces();
        }
        fem
    }

    #[test]
    fn the_warped_stiffness_of_a_rigidly_turned_cube_is_the_turned_rest_stiffness() {
        let r = rotation(0.7);
        let mut fem = turned(&r);
        let dofs = fem.x.len();
        let p: Vec<f64> = (0..dofs).map(|i| (0.37 * i as f64).sin()).collect();
        let mut warped = vec![0.0; dofs];
        fem.warped_system_product(&p, 0.0, 1.0, &mut warped);
        // R K R^T p, the rest stiffness in the turned frame.
        let mut k_local = vec![0.0; dofs];
        fem.model.apply(&rotate(&r, &p, true), &mut k_local);
        let want = rotate(&r, &k_local, false);
        let scale = want.iter().fold(0.0f64, |a, w| a.max(w.abs()));
        let worst = warped.iter().zip(&want).fold(0.0f64, |a, (w, v)| a.max((w - v).abs()));
        // The element rotations are the cube's to their tolerance (1e-8 rad).
        assert!(worst <= 1e-7 * scale, "warped product off by {worst} of {scale}");
    }

    #[test]
    fn the_warped_solve_meets_its_tolerance_where_the_rest_factor_alone_does_not() {
        // A turned cube moving: the step's system is the warped one, far from the rest factor.
        let r = rotation(0.9);
        for trapezoidal in [true, false] {
            let mut fem = turned(&r);
            fem.newton_iterations = 0; // the linearised step
            for (i, v) in fem.v.iter_mut().enumerate() {
                *v = 0.05 * (0.7 * i as f64).cos();
            }
            let (v0, x0) = (fem.v.clone(), fem.x.clone());
            let dt = 1e-3;
            let step = |fem: &mut FemDynamics| {
                if trapezoidal { fem.step_newmark(dt) } else { fem.step_prefactored(dt) }.unwrap()
            };
            step(&mut fem);
            let solves = fem.newton_solves().unwrap();
            assert_eq!((solves.steps, solves.unconverged), (1, 0), "{solves:?}");
            assert!(solves.most >= 2, "{solves:?}");
            // The residual of the linearised system at the solution: the step's unknown is
            // dx (trapezoidal) or v' (backward Euler).
            let (c_scale, k_scale) = implicit_scales(dt, trapezoidal);
            let y: Vec<f64> =
                if trapezoidal { fem.x.iter().zip(&x0).map(|(x, x0)| x - x0).collect() } else { fem.v.clone() };
            // The rotations and forces of the step's start.
            let mut start = turned(&r);
            start.v.copy_from_slice(&v0);
            let f = start.forces().to_vec();
            let (v_scale, f_scale) = if trapezoidal { (dt, 0.5 * dt * dt) } else { (1.0, dt) };
            let b: Vec<f64> = (0..y.len()).map(|i| v_scale * start.mass[i] * v0[i] + f_scale * f[i]).collect();
            let mut ay = vec![0.0; y.len()];
            start.warped_system_product(&y, 1.0 + c_scale * start.alpha, k_scale, &mut ay);
            let norm = |v: &[f64]| v.iter().map(|v| v * v).sum::<f64>().sqrt();
            let residual: Vec<f64> = b.iter().zip(&ay).map(|(b, a)| b - a).collect();
            let relative = norm(&residual) / norm(&b);
            assert!(relative < 2.0 * KRYLOV_TOLERANCE, "trapezoidal {trapezoidal}: residual {relative} of |b|");
            // The rest factor's solve alone leaves a residual many orders larger.
            let mut frozen = turned(&r);
            frozen.v.copy_from_slice(&v0);
            frozen.newton_iterations = 0;
            frozen.krylov_iterations = 0;
            step(&mut frozen);
            let y0: Vec<f64> =
                if trapezoidal { frozen.x.iter().zip(&x0).map(|(x, x0)| x - x0).collect() } else { frozen.v.clone() };
            start.warped_system_product(&y0, 1.0 + c_scale * start.alpha, k_scale, &mut ay);
            let residual: Vec<f64> = b.iter().zip(&ay).map(|(b, a)| b - a).collect();
            let frozen_relative = norm(&residual) / norm(&b);
            assert!(frozen_relative > 1e3 * relative, "rest factor alone: {frozen_relative}, warped {relative}");
            eprintln!(
                "trapezoidal {trapezoidal}: {solves:?}, residual {relative:.2e}, rest factor alone {frozen_relative:.2e}"
            );
        }
    }

    /// The step's nonlinear residual `|v_s M v + w_n f(x) + w_e f(x + d(y)) - a M y| / |b|` of a
    /// corotational implicit step from `start` (rotations converged) to `end`.
    fn nonlinear_residual(start: &FemDynamics, end: &FemDynamics, dt: f64, trapezoidal: bool) -> f64 {
        let mut at_start = FemDynamics::new(start.model.clone(), 1040.0, Formulation::Corotational, 0.0);
        at_start.mass.copy_from_slice(&start.mass);
        at_start.x.copy_from_slice(&start.x);
        let mut at_end = FemDynamics::new(start.model.clone(), 1040.0, Formulation::Corotational, 0.0);
        at_end.x.copy_from_slice(&end.x);
        let (f0, f1) = (converged_forces(&mut at_start), converged_forces(&mut at_end));
        let a = 1.0 + implicit_scales(dt, trapezoidal).0 * start.alpha;
        let (v_s, w_n, w_e) = if trapezoidal { (dt, 0.25 * dt * dt, 0.25 * dt * dt) } else { (1.0, 0.0, dt) };
        let (mut r, mut b) = (0.0, 0.0);
        for i in 0..f0.len() {
            let y = if trapezoidal { end.x[i] - start.x[i] } else { end.v[i] };
            let m = start.mass[i];
            r += (v_s * m * start.v[i] + w_n * f0[i] + w_e * f1[i] - a * m * y).powi(2);
            b += (v_s * m * start.v[i] + (w_n + w_e) * f0[i]).powi(2);
        }
        (r / b).sqrt()
    }

    fn converged_forces(fem: &mut FemDynamics) -> Vec<f64> {
        for _ in 0..20 {
            fem.forces();
        }
        fem.forces().to_vec()
    }

    #[test]
    fn newtons_corrections_solve_the_steps_equation_with_the_force_at_its_end() {
        let r = rotation(0.9);
        for trapezoidal in [true, false] {
            let mut residuals = Vec::new();
            for newton in [NEWTON_MAX_ITERATIONS, 0] {
                let mut fem = turned(&r);
                fem.newton_iterations = newton;
                // Spinning at 10 rad/s about z, and wobbling.
                for p in 0..fem.x.len() / 3 {
                    let (x, y) = (fem.x[3 * p] - 0.05, fem.x[3 * p + 1] - 0.05);
                    fem.v[3 * p] = -10.0 * y;
                    fem.v[3 * p + 1] = 10.0 * x;
                }
                for (i, v) in fem.v.iter_mut().enumerate() {
                    *v += 0.05 * (0.7 * i as f64).cos();
                }
                let start = FemDynamics { x: fem.x.clone(), v: fem.v.clone(), ..turned(&r) };
                if trapezoidal { fem.step_newmark(1e-3) } else { fem.step_prefactored(1e-3) }.unwrap();
                let solves = fem.newton_solves().unwrap();
                assert_eq!((solves.steps, solves.unconverged, solves.newton_unconverged), (1, 0, 0), "{solves:?}");
                assert!(newton == 0 || solves.newton >= 1, "{solves:?}");
                residuals.push(nonlinear_residual(&start, &fem, 1e-3, trapezoidal));
            }
            eprintln!(
                "trapezoidal {trapezoidal}: nonlinear residual {:.2e} (Newton), {:.2e} (linearised)",
                residuals[0], residuals[1]
            );
            assert!(
                residuals[0] <= 5.0 * NEWTON_TOLERANCE,
                "trapezoidal {trapezoidal}: residual {} with Newton",
                residuals[0]
            );
            assert!(residuals[1] > 10.0 * residuals[0], "trapezoidal {trapezoidal}: linearised {}", residuals[1]);
        }
    }
}
