//! Time integration of the mass-spring model: symplectic (semi-implicit) Euler, linearised
//! backward (implicit) Euler with the tangent of every step, and the same with the rest tangent
//! factorised once (prefactored). No step allocates once the state is built.

use super::forces::{ForceScratch, TangentAssembler, accumulate_spring_forces, add_spring_forces, dispatch_avx2};
use super::model::MsmModel;
use super::reduction::DofMap;
use crate::mechanics::cases::LoadCase;
use crate::mechanics::sparse::SparseError;

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
    f: [Vec<f64>; 3],
    scratch: ForceScratch,
    implicit: Option<ImplicitWork>,
    prefactored: Option<PrefactoredWork>,
    /// Linear offsets of the model's spring families (the topology the buffers are built for).
    family_offsets: Vec<usize>,
    /// `1 / m` of each node.
    inv_mass: Vec<f64>,
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
            f: zeros(),
            scratch: ForceScratch::new(model),
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

    /// One linearised backward Euler step with the rest tangent `K_0`, factorised once:
    /// `(M + dt C + dt^2 K_0) v' = M v + dt f(x)`, then `x += dt v'`. The spring forces `f(x)` are
    /// the full nonlinear ones; only the Jacobian is frozen at rest, so the step is as accurate
    /// as [`Dynamics::step_implicit`] for small strains and rotations and costs one force pass
    /// and one pair of triangular solves. The factor is rebuilt when `dt`, the parameters or
    /// the fixed nodes change; a step that reuses it allocates nothing.
    pub fn step_prefactored(&mut self, model: &MsmModel, dt: f64) -> Result<(), SparseError> {
        self.prefactored_step(model, dt, false)
    }

    /// One step of Newmark's average acceleration (the trapezoidal rule: no numerical damping,
    /// second order) linearised with the rest tangent `K_0`, factorised once:
    /// `(M + dt/2 C + dt^2/4 K_0) dx = dt M v + dt^2/2 f(x)`, then `v' = 2 dx / dt - v` and
    /// `x += dx`. Exact trapezoidal steps for a linear model; one force pass and one solve.
    pub fn step_newmark(&mut self, model: &MsmModel, dt: f64) -> Result<(), SparseError> {
        self.prefactored_step(model, dt, true)
    }

    fn prefactored_step(&mut self, model: &MsmModel, dt: f64, trapezoidal: bool) -> Result<(), SparseError> {
        // Moved out while the forces are computed, and back in (moves only: no allocation).
        let work = match self.prefactored.take() {
            Some(work) => work,
            None => {
                let fixed: Vec<bool> = self.free.iter().map(|&f| f == 0.0).collect();
                let tangent = TangentAssembler::at_rest(model, DofMap::free(&fixed))?;
                let rhs = vec![0.0; tangent.system.n()];
                let g = model.grid;
                let rest = std::array::from_fn(|c| (0..g.num_nodes()).map(|p| g.position(p)[c]).collect());
                let mass = vec![0.0; tangent.system.n()];
                let node_diag = vec![0.0; g.num_nodes()];
                PrefactoredWork { tangent, rhs, rest, dt: f64::NAN, trapezoidal, node_diag, mass }
            }
        };
        self.forces(model);
        let work = self.prefactored.insert(work);
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
            work.tangent.system.factor()?;
            (work.dt, work.trapezoidal) = (dt, trapezoidal);
        }
        let (v_scale, f_scale) = if trapezoidal { (dt, 0.5 * dt * dt) } else { (1.0, dt) };
        for (p, &free) in self.free.iter().enumerate() {
            if free != 0.0 {
                let m = model.masses[p];
                for c in 0..3 {
                    work.rhs[work.tangent.dofs.map[3 * p + c].0 as usize] =
                        v_scale * m * self.v[c][p] + f_scale * self.f[c][p];
                }
            }
        }
        work.tangent.system.solve_in_place(&mut work.rhs)?;
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

    /// Bytes held by the prefactored step's factor and buffers (0 before its first step).
    pub fn prefactored_memory_bytes(&self) -> usize {
        self.prefactored
            .as_ref()
            .map_or(0, |w| w.tangent.system.memory_bytes() + (w.rhs.len() + 3 * w.rest[0].len()) * 8)
    }

    /// Kinetic energy, joules.
    pub fn kinetic_energy(&self, model: &MsmModel) -> f64 {
        let s: f64 = (0..self.free.len())
            .map(|p| model.masses[p] * (0..3).map(|c| self.v[c][p] * self.v[c][p]).sum::<f64>())
            .sum();
        0.5 * s
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

#[inline(always)]
fn symplectic_step_generic(model: &MsmModel, s: &mut Dynamics, dt: f64) {
    for f in &mut s.f {
        f.fill(0.0);
    }
    accumulate_spring_forces::<true>(model, &s.x, &mut s.f, &mut s.scratch);
    for c in 0..3 {
        let (x, v, f, fe) = (&mut s.x[c], &mut s.v[c], &s.f[c], &s.f_ext[c]);
        for ((((((x, v), f), fe), free), inv_m), d) in
            x.iter_mut().zip(v.iter_mut()).zip(f.iter()).zip(fe).zip(&s.free).zip(&s.inv_mass).zip(&model.damping)
        {
            let vn = (*v + dt * inv_m * (f + fe - d * *v)) * free;
            *v = vn;
            *x += dt * vn;
        }
    }
}

fn symplectic_step(model: &MsmModel, s: &mut Dynamics, dt: f64) {
    dispatch_avx2!(symplectic_step_generic, symplectic_step_avx2, (model: &MsmModel, s: &mut Dynamics, dt: f64));
}
