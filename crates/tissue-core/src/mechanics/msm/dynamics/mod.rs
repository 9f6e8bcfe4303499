//! Time integration of the mass-spring model: symplectic (semi-implicit) Euler, linearised
//! backward (implicit) Euler with the tangent of every step, and backward Euler and Newmark's
//! trapezoidal rule with the rest tangent factorised once (prefactored), solved by Newton's
//! method on that factor ([`crate::mechanics::newton_krylov`]). A held node
//! ([`Dynamics::anchor`]) is carried inside the implicit steps' solves
//! ([`crate::mechanics::anchor`]). No step allocates once the state is built.
//!
//! `symplectic`: symplectic Euler's step (f64 or f32); `lattice_step`: the implicit step's
//! equation for Newton's method.

mod lattice_step;

mod symplectic;

use lattice_step::LatticeStep;
use symplectic::symplectic_step;

use super::forces::{
    ForceScratch, TangentAssembler, accumulate_spring_forces, add_spring_forces, dispatch_avx2, dispatch_simd,
    tangent_product,
};
use super::model::MsmModel;
use super::reduction::DofMap;
use super::single::SingleForce;
use crate::mechanics::anchor::{Anchor, AnchoredSolve, Held};
use crate::mechanics::cases::LoadCase;
use crate::mechanics::newton_krylov::{
    KRYLOV_MAX_ITERATIONS, NEWTON_MAX_ITERATIONS, NewtonKrylov, NewtonSolves, StepEquation,
};
use crate::mechanics::sparse::SparseError;
use crate::mechanics::sparse::SpdSystem;

/// The state of a running mass-spring model and the buffers its steps work in.
#[derive(Debug)]
pub struct Dynamics {
    /// Node positions, metres (x, y, z arrays).
    pub x: [Vec<f64>; 3],
    /// Node velocities, m/s.
    pub v: [Vec<f64>; 3],
    /// External nodal forces, newtons.
    pub f_ext: [Vec<f64>; 3],
    /// 1.0 for a free node, 0.0 for a fixed one.
    pub free: Vec<f64>,
    /// A node held by a spring and damper, carried inside the implicit steps' solves (its pull at
    /// the step's start is the caller's, in `f_ext`); the symplectic step leaves it to its
    /// caller. Ignored on a fixed node.
    pub anchor: Option<Anchor>,
    f: [Vec<f64>; 3],
    scratch: ForceScratch,
    /// The symplectic step's spring force in `f32` ([`Dynamics::set_single_precision`]).
    single: Option<SingleForce>,
    implicit: Option<ImplicitWork>,
    prefactored: Option<PrefactoredWork>,
    /// Linear offsets of the model's spring families (the topology the buffers are built for).
    family_offsets: Vec<usize>,
    /// `1 / m` of each node.
    inv_mass: Vec<f64>,
}

/// The anchor, where its node is free.
fn held(anchor: Option<Anchor>, free: &[f64]) -> Option<Anchor> {
    anchor.filter(|a| free.get(a.node).is_some_and(|&f| f != 0.0))
}

#[derive(Debug)]
struct ImplicitWork {
    tangent: TangentAssembler,
    kv: [Vec<f64>; 3],
    rhs: Vec<f64>,
    /// `m_p + dt c_p` of each node, then folded onto the unknowns.
    node_diag: Vec<f64>,
    mass: Vec<f64>,
}

/// The prefactored step's system `M + dt D + dt^2 K_0` (`K_0`: the rest tangent), factorised for
/// the `dt` and parameters it was built with.
#[derive(Debug)]
struct PrefactoredWork {
    tangent: TangentAssembler,
    rhs: Vec<f64>,
    rest: [Vec<f64>; 3],
    /// The `dt` of the factor; NaN when it must be rebuilt (new parameters).
    dt: f64,
    /// Whether the factor is the trapezoidal rule's (else backward Euler's).
    trapezoidal: bool,
    /// `m_p + dt c_p` of each node, then folded onto the unknowns.
    node_diag: Vec<f64>,
    mass: Vec<f64>,
    /// The factor's correction for the held node.
    anchored: AnchoredSolve,
    /// Newton's corrections by conjugate gradients on the factor.
    newton: NewtonKrylov,
    /// The step's start positions and forces, and a vector and a product on the nodes.
    x0: [Vec<f64>; 3],
    f0: [Vec<f64>; 3],
    p_nodes: [Vec<f64>; 3],
    out_nodes: [Vec<f64>; 3],
}

impl PrefactoredWork {
    /// The rest tangent's pattern for the free nodes `free`, and buffers (factorised at the
    /// first step).
    fn new(model: &MsmModel, free: &[f64], trapezoidal: bool) -> Result<Self, SparseError> {
        let fixed: Vec<bool> = free.iter().map(|&f| f == 0.0).collect();
        let tangent = TangentAssembler::at_rest(model, DofMap::free(&fixed))?;
        let n = tangent.system.n();
        let g = model.grid;
        let nodes = || std::array::from_fn(|_| vec![0.0; g.num_nodes()]);
        Ok(Self {
            rhs: vec![0.0; n],
            rest: std::array::from_fn(|c| (0..g.num_nodes()).map(|p| g.position(p)[c]).collect()),
            dt: f64::NAN,
            trapezoidal,
            node_diag: vec![0.0; g.num_nodes()],
            mass: vec![0.0; n],
            anchored: AnchoredSolve::new(n),
            newton: NewtonKrylov::new(n, KRYLOV_MAX_ITERATIONS, NEWTON_MAX_ITERATIONS),
            x0: nodes(),
            f0: nodes(),
            p_nodes: nodes(),
            out_nodes: nodes(),
            tangent,
        })
    }
}

impl Dynamics {
    /// The model at rest, nothing fixed, no load.
    pub fn new(model: &MsmModel) -> Self {
        let g = model.grid;
        let nn = g.num_nodes();
        let x = std::array::from_fn(|c| (0..nn).map(|p| g.position(p)[c]).collect());
        let zeros = || std::array::from_fn(|_| vec![0.0; nn]);
        Self {
            x,
            v: zeros(),
            f_ext: zeros(),
            free: vec![1.0; nn],
            anchor: None,
            f: zeros(),
            scratch: ForceScratch::new(model),
            single: None,
            implicit: None,
            prefactored: None,
            family_offsets: model.families.iter().map(|f| f.offset).collect(),
            inv_mass: model.masses.iter().map(|m| 1.0 / m).collect(),
        }
    }

    /// Applies a load case's fixed nodes and loads (the state is kept).
    pub fn apply_case(&mut self, case: &LoadCase) {
        for (p, fixed) in case.fixed_nodes().into_iter().enumerate() {
            self.free[p] = if fixed { 0.0 } else { 1.0 };
        }
        for c in 0..3 {
            for (p, f) in self.f_ext[c].iter_mut().enumerate() {
                *f = case.load[3 * p + c];
            }
        }
        self.implicit = None;
        self.prefactored = None;
    }

    /// Switches to another model on the same grid (new parameters, e.g. a calibration result, or
    /// another topology), keeping positions, velocities, loads and fixed nodes.
    pub fn set_model(&mut self, model: &MsmModel) {
        debug_assert_eq!(model.grid.num_nodes(), self.free.len());
        let offsets: Vec<usize> = model.families.iter().map(|f| f.offset).collect();
        if offsets != self.family_offsets {
            // Another spring topology: new buffers and a new sparse pattern. (Same topology: the
            // pattern stays, stiffness is read at assembly.)
            self.scratch = ForceScratch::new(model);
            self.implicit = None;
            self.prefactored = None;
            self.family_offsets = offsets;
        }
        if self.single.is_some() {
            self.single = Some(SingleForce::new(model));
        }
        for (i, m) in self.inv_mass.iter_mut().zip(&model.masses) {
            *i = 1.0 / m;
        }
        if let Some(work) = self.prefactored.as_mut() {
            work.dt = f64::NAN; // new stiffness: refactorise at the next step
        }
    }

    /// Total spring + external force on each node at the current positions (no damping).
    pub fn forces(&mut self, model: &MsmModel) -> &[Vec<f64>; 3] {
        for c in 0..3 {
            self.f[c].copy_from_slice(&self.f_ext[c]);
        }
        add_spring_forces(model, &self.x, &mut self.f, &mut self.scratch);
        &self.f
    }

    /// Sums the symplectic step's spring force in `f32` ([`SingleForce`]: from displacements,
    /// the stiffness rounded) or, the default, in `f64`; the rest of every step stays `f64`.
    pub fn set_single_precision(&mut self, model: &MsmModel, single: bool) {
        self.single = single.then(|| SingleForce::new(model));
    }

    /// One symplectic Euler step: `v += dt/m (f(x) - c v)` (`c`: each node's damping), then
    /// `x += dt v`. Allocation-free.
    pub fn step_symplectic(&mut self, model: &MsmModel, dt: f64) {
        symplectic_step(model, self, dt);
    }

    /// One linearised backward Euler step (Baraff-Witkin):
    /// `(M + dt C + dt^2 K) dv = dt (f(x) - C v - dt K v)`, then `v += dv`, `x += dt v`
    /// (`C`: the diagonal of the nodes' damping).
    /// `K` is the tangent stiffness with each spring's geometric part clamped at zero, so the
    /// matrix is positive definite for any `dt`. The first call after [`Dynamics::apply_case`]
    /// builds the sparse pattern; later calls allocate nothing.
    pub fn step_implicit(&mut self, model: &MsmModel, dt: f64) -> Result<(), SparseError> {
        // Moved out while the forces are computed, and back in (moves only: no allocation).
        let work = match self.implicit.take() {
            Some(work) => work,
            None => {
                let fixed: Vec<bool> = self.free.iter().map(|&f| f == 0.0).collect();
                let tangent = TangentAssembler::new(model, DofMap::free(&fixed))?;
                let rhs = vec![0.0; tangent.system.n()];
                let nn = self.free.len();
                let mass = vec![0.0; tangent.system.n()];
                let node_diag = vec![0.0; nn];
                ImplicitWork { tangent, kv: std::array::from_fn(|_| vec![0.0; nn]), rhs, node_diag, mass }
            }
        };
        self.forces(model);
        let work = self.implicit.insert(work);
        for kv in work.kv.iter_mut() {
            kv.fill(0.0);
        }
        work.tangent.assemble(model, &self.x, dt * dt, 0.0, true, Some((&self.v, &mut work.kv)));
        for ((o, m), c) in work.node_diag.iter_mut().zip(&model.masses).zip(&model.damping) {
            *o = m + dt * c;
        }
        work.tangent.dofs.fold_masses(&work.node_diag, &mut work.mass);
        let held = held(self.anchor, &self.free);
        if let Some(a) = held {
            for c in 0..3 {
                work.mass[work.tangent.dofs.map[3 * a.node + c].0 as usize] += a.diagonal(dt, dt * dt);
            }
        }
        work.tangent.system.add_diagonal_scaled(1.0, &work.mass);
        work.tangent.system.factor()?;
        for (p, &free) in self.free.iter().enumerate() {
            if free != 0.0 {
                for c in 0..3 {
                    let r = work.tangent.dofs.map[3 * p + c].0 as usize;
                    let d = model.damping[p];
                    work.rhs[r] = dt * (self.f[c][p] - d * self.v[c][p] - dt * work.kv[c][p]);
                }
            }
        }
        // The anchor's damping and stiffness on the node's velocity, as the tissue's above.
        if let Some(a) = held {
            for c in 0..3 {
                let v = self.v[c][a.node];
                work.rhs[work.tangent.dofs.map[3 * a.node + c].0 as usize] -=
                    dt * (a.damping * v + dt * a.stiffness * v);
            }
        }
        work.tangent.system.solve_in_place(&mut work.rhs)?;
        for (p, &free) in self.free.iter().enumerate() {
            if free != 0.0 {
                for c in 0..3 {
                    self.v[c][p] += work.rhs[work.tangent.dofs.map[3 * p + c].0 as usize];
                    self.x[c][p] += dt * self.v[c][p];
                }
            }
        }
        Ok(())
    }

    /// One backward Euler step with the rest tangent `K_0` factorised once (`M + dt C + dt^2
    /// K_0`): Newton's method solves the step's equation with the force at its end, `(M + dt C)
    /// v' = M v + dt f(x + dt v')`, from the step linearised with the tangent of its start, each
    /// linear solve by conjugate gradients on the springs' tangent preconditioned with that factor ([`crate::mechanics::newton_krylov`]; [`Dynamics::newton_solves`] counts
    /// them), then `x += dt v'`. The factor is rebuilt when `dt`, the parameters or the fixed
    /// nodes change; a step that reuses it allocates nothing.
    pub fn step_prefactored(&mut self, model: &MsmModel, dt: f64) -> Result<(), SparseError> {
        self.prefactored_step(model, dt, false)
    }

    /// One step of Newmark's average acceleration (the trapezoidal rule: no numerical damping,
    /// second order) with the rest tangent `K_0` factorised once (`M + dt/2 C + dt^2/4 K_0`):
    /// Newton's method solves the step's equation, `(M + dt/2 C) dx = dt M v + dt^2/4 (f(x) +
    /// f(x + dx))`, as [`Dynamics::step_prefactored`] does; then
    /// `v' = 2 dx / dt - v` and `x += dx`. Linearised at rest alone it blew up under a 2 cm
    /// corner drag of the hex lattice at 8^3 and 1 ms.
    pub fn step_newmark(&mut self, model: &MsmModel, dt: f64) -> Result<(), SparseError> {
        self.prefactored_step(model, dt, true)
    }

    fn prefactored_step(&mut self, model: &MsmModel, dt: f64, trapezoidal: bool) -> Result<(), SparseError> {
        // Moved out while the step runs, and back in (moves only: no allocation).
        let mut work = match self.prefactored.take() {
            Some(work) => work,
            None => PrefactoredWork::new(model, &self.free, trapezoidal)?,
        };
        let stepped = self.prefactored_solve(model, &mut work, dt, trapezoidal);
        self.prefactored = Some(work);
        stepped
    }

    /// The prefactored step on `work`: the rest factor (rebuilt for a new `dt` or scheme), the
    /// linearised right-hand side, then Newton's method on the springs' tangent
    /// ([`crate::mechanics::newton_krylov`]).
    fn prefactored_solve(
        &mut self,
        model: &MsmModel,
        work: &mut PrefactoredWork,
        dt: f64,
        trapezoidal: bool,
    ) -> Result<(), SparseError> {
        self.forces(model);
        // Backward Euler solves for v' with (dt, dt^2); the trapezoidal rule for dx with
        // (dt/2, dt^2/4) and its right-hand side scaled by dt.
        let (c_scale, k_scale) = if trapezoidal { (0.5 * dt, 0.25 * dt * dt) } else { (dt, dt * dt) };
        if work.dt != dt || work.trapezoidal != trapezoidal {
            work.tangent.assemble(model, &work.rest, k_scale, 0.0, false, None);
            for ((o, m), c) in work.node_diag.iter_mut().zip(&model.masses).zip(&model.damping) {
                *o = m + c_scale * c;
            }
            work.tangent.dofs.fold_masses(&work.node_diag, &mut work.mass);
            work.tangent.system.add_diagonal_scaled(1.0, &work.mass);
            work.anchored.invalidate();
            work.dt = f64::NAN; // until the factor is built: a failed one is tried again
            work.tangent.system.factor()?;
            (work.dt, work.trapezoidal) = (dt, trapezoidal);
            work.newton.solves = NewtonSolves::default();
        }
        let held = match held(self.anchor, &self.free) {
            Some(a) => {
                let unknowns = std::array::from_fn(|c| work.tangent.dofs.map[3 * a.node + c].0 as usize);
                let held = Held { unknowns, diagonal: a.diagonal(c_scale, k_scale) };
                work.anchored.prepare(&mut work.tangent.system, held)?;
                Some(held)
            }
            None => None,
        };
        let (v_scale, w_n, w_e) = if trapezoidal { (dt, 0.25 * dt * dt, 0.25 * dt * dt) } else { (1.0, 0.0, dt) };
        let mut scale = 0.0;
        for (p, &free) in self.free.iter().enumerate() {
            if free != 0.0 {
                let m = model.masses[p];
                for c in 0..3 {
                    work.rhs[work.tangent.dofs.map[3 * p + c].0 as usize] =
                        v_scale * m * self.v[c][p] + (w_n + w_e) * self.f[c][p];
                    let t = v_scale * (m * self.v[c][p]).abs()
                        + (w_n + w_e) * (self.f[c][p].abs() + self.f_ext[c][p].abs());
                    scale += t * t;
                }
            }
        }
        for c in 0..3 {
            work.x0[c].copy_from_slice(&self.x[c]);
            work.f0[c].copy_from_slice(&self.f[c]);
        }
        let mut step = LatticeStep {
            model,
            dofs: &work.tangent.dofs,
            system: &mut work.tangent.system,
            anchored: &work.anchored,
            held,
            mass: &work.mass,
            x0: &work.x0,
            f0: &work.f0,
            v: &self.v,
            f_ext: &self.f_ext,
            x: &mut self.x,
            f: &mut self.f,
            p_nodes: &mut work.p_nodes,
            out_nodes: &mut work.out_nodes,
            scratch: &mut self.scratch,
            scales: [k_scale, v_scale, w_n, w_e, if trapezoidal { 1.0 } else { dt }],
        };
        let solved = work.newton.solve(&mut step, &mut work.rhs, scale.sqrt());
        for c in 0..3 {
            self.x[c].copy_from_slice(&work.x0[c]);
        }
        solved?;
        for (p, &free) in self.free.iter().enumerate() {
            if free != 0.0 {
                for c in 0..3 {
                    let solved = work.rhs[work.tangent.dofs.map[3 * p + c].0 as usize];
                    if trapezoidal {
                        self.v[c][p] = 2.0 * solved / dt - self.v[c][p];
                        self.x[c][p] += solved;
                    } else {
                        self.v[c][p] = solved;
                        self.x[c][p] += dt * solved;
                    }
                }
            }
        }
        Ok(())
    }

    /// What the prefactored steps' solves have done since their factor was built (`None` before
    /// the first).
    pub fn newton_solves(&self) -> Option<NewtonSolves> {
        self.prefactored.as_ref().map(|w| w.newton.solves)
    }

    /// Bytes held by the prefactored step's factor and buffers (0 before its first step).
    pub fn prefactored_memory_bytes(&self) -> usize {
        self.prefactored.as_ref().map_or(0, |w| {
            w.tangent.system.memory_bytes()
                + w.anchored.memory_bytes()
                + w.newton.memory_bytes()
                + (w.rhs.len() + 15 * w.rest[0].len()) * 8
        })
    }

    /// Kinetic energy, joules.
    pub fn kinetic_energy(&self, model: &MsmModel) -> f64 {
        crate::mechanics::kinetic::kinetic_energy(&model.masses, &self.v)
    }

    /// Displacements from the rest positions, row = node.
    pub fn displacements(&self, model: &MsmModel) -> Vec<[f64; 3]> {
        (0..self.free.len())
            .map(|p| {
                let r = model.grid.position(p);
                std::array::from_fn(|c| self.x[c][p] - r[c])
            })
            .collect()
    }
}
