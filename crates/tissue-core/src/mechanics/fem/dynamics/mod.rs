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
//!
//! `corotational`: the corotational model's implicit step (Newton-Krylov on the warped
//! stiffness).

use super::FemModel;
pub use super::corotation::{ROTATION_ITERATIONS, ROTATION_TOLERANCE};
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
        at.patched(self.model.patch(), &self.next_rotations, out);
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


mod corotational;

use corotational::Krylov;

#[cfg(test)]
mod tests;
