//! Finite-element dynamics of the cube: linear and corotational hex8 elements with lumped masses,
//! symplectic Euler and a prefactored backward Euler step.
//!
//! Linear elements compute `f = -K u`: exact for small displacements, but a rigid rotation
//! produces strain and force (the body swells when it turns). Corotational elements take out
//! each element's rotation `R` (polar decomposition of the deformation gradient at its centre,
//! updated incrementally: [`super::corotation`]) and compute `f_e = -R K_e (R^T x_e - X_e)`,
//! which is zero for any rigid motion. The implicit
//! step factorises `M (1 + dt alpha) + dt^2 K` once (the linear stiffness), so for the linear
//! model it is exact backward Euler and for the corotational one the Jacobian is frozen at rest
//! while the forces are the full corotational ones. No step allocates.

use super::FemModel;
use super::corotation::{Corotation, IDENTITY, ParityBlocks};
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
    /// Positions and rest positions component-wise (`[c][node]`), for the corotated elements.
    x_components: [Vec<f64>; 3],
    rest_components: [Vec<f64>; 3],
    /// The element matrix in the corners' parity basis, where it has that form.
    parity: Option<ParityBlocks>,
    /// Each element's corotated force on its eight nodes (filled in parallel, gathered in order).
    element_forces: Vec<[f64; 24]>,
    /// Whether the element loop may use the physics pool ([`crate::mechanics::parallel`]).
    pub parallel: bool,
    /// The most iterations of each element's rotation update per force evaluation
    /// ([`ROTATION_ITERATIONS`] by default).
    pub rotation_iterations: usize,
    /// Where the update stops: every correction at most this, radians ([`ROTATION_TOLERANCE`]
    /// by default).
    pub rotation_tolerance: f64,
    /// The factor, its right-hand side buffer, and the `(dt, alpha, trapezoidal)` it was built
    /// for.
    implicit: Option<(SpdSystem, Vec<f64>, (f64, f64, bool))>,
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
            element_forces: vec![[0.0; 24]; elements],
            parallel: true,
            rotation_iterations: ROTATION_ITERATIONS,
            rotation_tolerance: ROTATION_TOLERANCE,
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
                // Moved out while the elements read them, and back (moves only: no allocation).
                let x = std::mem::take(&mut self.x_components);
                self.corotated_elements([&x[0], &x[1], &x[2]]);
                self.x_components = x;
                self.f.copy_from_slice(&self.f_ext);
                let f = &mut self.f;
                gather(self.model.elements(), &self.element_forces, |p, c, fe| f[3 * p + c] -= fe);
            }
        }
    }

    /// Every element's rotation moved on and its corotated force into `element_forces`, at the
    /// component-wise positions `x`.
    fn corotated_elements(&mut self, x: [&[f64]; 3]) {
        let rest = &self.rest_components;
        let at = Corotation {
            x,
            rest: [&rest[0], &rest[1], &rest[2]],
            ke: &self.model.ke,
            parity: self.parity.as_ref(),
            grid: self.model.grid,
            iterations: self.rotation_iterations,
            tolerance: self.rotation_tolerance,
        };
        at.all(&self.rotations, &mut self.next_rotations, &mut self.element_forces, self.parallel);
        std::mem::swap(&mut self.rotations, &mut self.next_rotations);
    }

    /// The corotational elastic + external force at the component-wise positions `x`, from the
    /// component-wise external forces `f_ext`, into `out` (`[c][node]`): the operations of the
    /// interleaved force in the same order (the same bits), for a step on component-wise state.
    /// Allocation-free.
    pub fn corotated_forces_components(&mut self, x: [&[f64]; 3], f_ext: &[Vec<f64>; 3], out: &mut [Vec<f64>; 3]) {
        self.corotated_elements(x);
        for (out, f_ext) in out.iter_mut().zip(f_ext) {
            out.copy_from_slice(f_ext);
        }
        gather(self.model.elements(), &self.element_forces, |p, c, fe| out[c][p] -= fe);
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
    /// linear model; for the corotational one the forces are corotational and the Jacobian is
    /// the rest stiffness. The first step (or a new `dt`) factorises; later steps allocate nothing.
    pub fn step_prefactored(&mut self, dt: f64) -> Result<(), SparseError> {
        self.prefactored_step(dt, false)
    }

    /// One step of Newmark's average acceleration (the trapezoidal rule: no numerical damping,
    /// second order) with the linear stiffness factorised once per `dt`:
    /// `(M (1 + dt alpha / 2) + dt^2 / 4 K) dx = dt M v + dt^2 / 2 f(x)`, `v' = 2 dx / dt - v`,
    /// `x += dx`. Exact trapezoidal steps for the linear model; for the corotational one the
    /// forces are corotational and the Jacobian is the rest stiffness (one solve, no iteration).
    pub fn step_newmark(&mut self, dt: f64) -> Result<(), SparseError> {
        self.prefactored_step(dt, true)
    }

    fn prefactored_step(&mut self, dt: f64, trapezoidal: bool) -> Result<(), SparseError> {
        let key = (dt, self.alpha, trapezoidal);
        // Moved out while the forces are computed, and back in (moves only: no allocation).
        let work = match self.implicit.take() {
            Some(work) if work.2 == key => work,
            stale => {
                self.implicit = stale; // kept if the new factorisation fails
                (self.prefactored_system(dt, trapezoidal)?, vec![0.0; self.x.len()], key)
            }
        };
        self.compute_forces();
        let (system, rhs, _) = self.implicit.insert(work);
        let (v_scale, f_scale) = if trapezoidal { (dt, 0.5 * dt * dt) } else { (1.0, dt) };
        for i in 0..rhs.len() {
            rhs[i] = (v_scale * self.mass[i] * self.v[i] + f_scale * self.f[i]) * self.free[i];
        }
        system.solve_in_place(rhs)?;
        for i in 0..rhs.len() {
            let solved = rhs[i] * self.free[i];
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

    /// `M (1 + dt alpha) + dt^2 K` (backward Euler) or `M (1 + dt alpha / 2) + dt^2 / 4 K` (the
    /// trapezoidal rule) with the fixed dofs decoupled, factorised.
    fn prefactored_system(&self, dt: f64, trapezoidal: bool) -> Result<SpdSystem, SparseError> {
        let (c_scale, k_scale) = if trapezoidal { (0.5 * dt, 0.25 * dt * dt) } else { (dt, dt * dt) };
        let (entries, values) = self.model.stiffness_entries();
        let (mut system, slots) = SpdSystem::new(self.x.len(), &entries)?;
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
        self.implicit.as_ref().map_or(0, |(s, r, _)| s.memory_bytes() + r.len() * 8)
    }

    /// Bytes held by the state, the element data and the factor (if built).
    pub fn memory_bytes(&self) -> usize {
        let vectors = 8 * self.x.len() * 8
            + self.rotations.len() * 64
            + self.model.elements().len() * (64 + 192)
            + 6 * 8 * self.rest.len() / 3
            + 24 * 24 * 8;
        vectors + self.factor_memory_bytes()
    }
}

/// Hands every element force component to `sub(node, component, value)` in element order, on
/// one thread: the same sums, bit for bit, however the elements were split, in either layout.
fn gather(elements: &[[usize; 8]], element_forces: &[[f64; 24]], mut sub: impl FnMut(usize, usize, f64)) {
    for (nodes, fe) in elements.iter().zip(element_forces) {
        for (a, &p) in nodes.iter().enumerate() {
            for c in 0..3 {
                sub(p, c, fe[3 * a + c]);
            }
        }
    }
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
/// updates took 6.1 iterations on average and at most 18; held still, 0.09.
pub const ROTATION_ITERATIONS: usize = 20;
/// Where the rotation extraction stops: every correction of four elements at most this, radians
/// ([`FemDynamics::rotation_tolerance`]'s default; see [`ROTATION_ITERATIONS`]).
pub const ROTATION_TOLERANCE: f64 = 1e-8;
