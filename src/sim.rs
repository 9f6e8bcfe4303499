//! The interactive simulation: a mass-spring tissue stepped at a fixed time step, with the user's
//! tools (a dragging spring, a spherical probe with real contact) and a blow-up guard. No GPU
//! types and no threads: the viewer's physics thread and the headless `simulate` command both
//! drive this.

use crate::cases::LoadCase;
use crate::msm::{Dynamics, MsmModel, MsmParams};

/// Time integrator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Integrator {
    /// Symplectic (semi-implicit) Euler: cheap, stable below a critical time step.
    Symplectic,
    /// Linearised backward Euler: stable for any time step, one sparse factorisation per step.
    Implicit,
    /// Linearised backward Euler with the rest tangent factorised once: one solve per step.
    Prefactored,
}

impl Integrator {
    /// The lower-case name used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Symplectic => "symplectic",
            Integrator::Implicit => "implicit",
            Integrator::Prefactored => "prefactored",
        }
    }
}

/// A user tool acting on the tissue.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tool {
    /// Nothing held.
    None,
    /// A node pulled towards `target` (metres) by a stiff spring.
    Drag {
        /// The held node.
        node: usize,
        /// Where the mouse puts it, metres.
        target: [f64; 3],
    },
    /// A rigid sphere; no node may be inside it.
    Probe {
        /// Centre, metres.
        centre: [f64; 3],
        /// Radius, metres.
        radius: f64,
    },
}

/// Stiffness of the dragging spring, N/m, and its damping, N s/m.
pub const DRAG_STIFFNESS: f64 = 1000.0;
const DRAG_DAMPING: f64 = 1.0;

/// What a blow-up looked like, and what to change.
#[derive(Debug, Clone, PartialEq)]
pub struct BlowUp {
    /// Simulated time at detection, s.
    pub time_s: f64,
    /// What went wrong and what to change.
    pub message: String,
    /// The guard gave up: this was the [`MAX_RECOVERIES`]-th blow-up in a row (no healthy step
    /// past the previous one's time), so the state went back to rest, the tool was let go, and
    /// stepping on would only repeat it. The caller stops (a script fails; the viewer pauses).
    pub fatal: bool,
}

/// Consecutive recoveries after which the guard stops a run ([`BlowUp::fatal`]).
pub const MAX_RECOVERIES: u32 = 3;

/// Why a state is not good.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Unhealthy {
    NonFinite,
    OutsideCube,
    Energy,
}

/// The running tissue.
#[derive(Debug)]
pub struct Simulation {
    /// The model.
    pub model: MsmModel,
    /// Its state.
    pub dynamics: Dynamics,
    /// Integrator.
    pub integrator: Integrator,
    /// Time step, s.
    pub dt: f64,
    /// The active tool.
    pub tool: Tool,
    /// Simulated time, s.
    pub time_s: f64,
    base_load: [Vec<f64>; 3],
    /// Force of the tissue on the tool, newtons (last step).
    pub tool_force: [f64; 3],
    /// Last good state (positions, velocities, time), refreshed every 100 healthy steps.
    good_x: [Vec<f64>; 3],
    good_v: [Vec<f64>; 3],
    good_time: Option<f64>,
    steps_since_good: usize,
    contact_forces: [Vec<f64>; 3],
    /// [`Simulation::explicit_dt_limit`] of the current model.
    dt_limit: f64,
    /// Blow-ups since the last healthy step past the previous blow-up's time.
    recoveries: u32,
    /// Simulated time of the last blow-up, s.
    last_blow_up_s: f64,
}

impl Simulation {
    /// The model at rest, one face clamped by `case` (if any) with its loads.
    pub fn new(model: MsmModel, integrator: Integrator, dt: f64, case: Option<&LoadCase>) -> Self {
        let mut dynamics = Dynamics::new(&model);
        if let Some(c) = case {
            dynamics.apply_case(c);
        }
        let base_load = dynamics.f_ext.clone();
        let zeros = || std::array::from_fn(|_| vec![0.0; model.grid.num_nodes()]);
        Self {
            integrator,
            dt,
            tool: Tool::None,
            time_s: 0.0,
            base_load,
            tool_force: [0.0; 3],
            good_x: zeros(),
            good_v: zeros(),
            good_time: None,
            steps_since_good: 0,
            contact_forces: zeros(),
            dt_limit: Self::explicit_dt_limit(&model),
            recoveries: 0,
            last_blow_up_s: f64::NEG_INFINITY,
            model,
            dynamics,
        }
    }

    /// [`Simulation::explicit_dt_limit`] of the running model (cached).
    pub fn dt_limit(&self) -> f64 {
        self.dt_limit
    }

    /// Estimated critical time step of symplectic Euler, `2 / omega_max`, from Gershgorin's
    /// bound `omega_max^2 <= max_i sum_j |K_ij| / m` on the rest stiffness (conservative).
    pub fn explicit_dt_limit(model: &MsmModel) -> f64 {
        let mut row = vec![0.0f64; model.grid.num_nodes()];
        for s in model.springs() {
            let k = model.families[s.family].stiffness[s.a];
            let d = model.families[s.family].family.offset.map(|o| f64::from(o.abs()));
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            // Row sums of k d d^T (and its off-diagonal copy) for the worst component.
            let w = (0..3).map(|c| d[c] / len * (d[0] + d[1] + d[2]) / len).fold(0.0, f64::max);
            row[s.a] += 2.0 * k * w;
            row[s.b] += 2.0 * k * w;
        }
        let lambda = row.iter().copied().fold(0.0, f64::max) / model.node_mass;
        // Damping narrows the window: for v' = -(d/m) v the explicit limit is 2 m / d.
        let damping_limit = if model.params.d > 0.0 { 2.0 * model.node_mass / model.params.d } else { f64::INFINITY };
        (2.0 / lambda.sqrt()).min(damping_limit)
    }

    /// The integrator to use by default for `dt`: symplectic when `dt` is safely below its
    /// limit, implicit otherwise.
    pub fn default_integrator(model: &MsmModel, dt: f64) -> Integrator {
        Self::integrator_for(dt, Self::explicit_dt_limit(model))
    }

    /// Symplectic when `dt` is at most half the explicit limit `limit`, prefactored implicit otherwise.
    pub fn integrator_for(dt: f64, limit: f64) -> Integrator {
        if dt <= 0.5 * limit { Integrator::Symplectic } else { Integrator::Prefactored }
    }

    /// Replaces the parameters, keeping the state (a calibration result applied live).
    pub fn set_params(&mut self, params: MsmParams) -> Result<(), crate::msm::ParamError> {
        let density = self.model.node_mass * self.model.grid.num_nodes() as f64 / crate::grid::CUBE_SIDE_M.powi(3);
        self.model = MsmModel::new(self.model.grid, params, density)?;
        self.dynamics.set_model(&self.model);
        self.dt_limit = Self::explicit_dt_limit(&self.model);
        Ok(())
    }

    /// Applies a load case (fixed nodes and loads), keeping the state.
    pub fn apply_case(&mut self, case: &LoadCase) {
        self.dynamics.apply_case(case);
        for c in 0..3 {
            self.base_load[c].copy_from_slice(&self.dynamics.f_ext[c]);
        }
        self.good_time = None;
    }

    /// Back to rest (positions and velocities), keeping fixed nodes and loads; the guard's count
    /// starts again.
    pub fn reset(&mut self) {
        self.to_rest();
        self.recoveries = 0;
        self.last_blow_up_s = f64::NEG_INFINITY;
    }

    fn to_rest(&mut self) {
        let grid = self.model.grid;
        for p in 0..grid.num_nodes() {
            let r = grid.position(p);
            for c in 0..3 {
                self.dynamics.x[c][p] = r[c];
                self.dynamics.v[c][p] = 0.0;
            }
        }
        self.time_s = 0.0;
        self.good_time = None;
    }

    /// Advances one step; on a blow-up restores the last good state and says why.
    pub fn step(&mut self) -> Result<(), BlowUp> {
        self.apply_tool_load();
        let stepped = match self.integrator {
            Integrator::Symplectic => {
                self.dynamics.step_symplectic(&self.model, self.dt);
                Ok(())
            }
            Integrator::Implicit => self.dynamics.step_implicit(&self.model, self.dt),
            Integrator::Prefactored => self.dynamics.step_prefactored(&self.model, self.dt),
        };
        self.enforce_contact();
        self.time_s += self.dt;
        let unhealthy = if stepped.is_ok() { self.unhealthy() } else { None };
        if stepped.is_ok() && unhealthy.is_none() {
            if self.time_s > self.last_blow_up_s {
                self.recoveries = 0;
            }
            self.steps_since_good += 1;
            if self.good_time.is_none() || self.steps_since_good >= 100 {
                for c in 0..3 {
                    self.good_x[c].copy_from_slice(&self.dynamics.x[c]);
                    self.good_v[c].copy_from_slice(&self.dynamics.v[c]);
                }
                self.good_time = Some(self.time_s);
                self.steps_since_good = 0;
            }
            return Ok(());
        }
        let limit = self.dt_limit;
        let dragging = matches!(self.tool, Tool::Drag { .. });
        let message = match (stepped, self.integrator, unhealthy) {
            (Err(e), _, _) => format!("the implicit solve failed ({e}); the state was reset"),
            (Ok(()), Integrator::Symplectic, _) if self.dt > limit => format!(
                "diverged: symplectic Euler with dt = {:.3e} s is above its stability limit of about {limit:.3e} s \
                 for this stiffness; the state was reset. Lower dt or choose the implicit integrator.",
                self.dt
            ),
            (Ok(()), _, Some(Unhealthy::OutsideCube)) if dragging => "a node was pulled more than the cube's side \
                 (0.1 m) from rest; the state was reset. Drag targets are in metres: keep them near the cube."
                .to_owned(),
            (Ok(()), _, Some(Unhealthy::OutsideCube)) => "a node moved more than the cube's side (0.1 m) from rest; \
                 the state was reset. Lower the loads or dt, or choose the implicit integrator."
                .to_owned(),
            (Ok(()), _, _) => "diverged (non-finite or runaway energy); the state was reset. Lower dt, soften the \
                            tool, or choose the implicit integrator."
                .to_owned(),
        };
        let time_s = self.time_s;
        if time_s > self.last_blow_up_s {
            self.last_blow_up_s = time_s;
        }
        self.recoveries += 1;
        let fatal = self.recoveries >= MAX_RECOVERIES;
        if fatal {
            self.good_time = None;
            self.last_blow_up_s = f64::NEG_INFINITY;
            self.recoveries = 0;
        }
        self.restore();
        let message = if fatal {
            format!("stopped after {MAX_RECOVERIES} blow-ups in a row, back at rest: {message}")
        } else {
            message
        };
        Err(BlowUp { time_s, message, fatal })
    }

    fn restore(&mut self) {
        match self.good_time {
            Some(t) => {
                for c in 0..3 {
                    self.dynamics.x[c].copy_from_slice(&self.good_x[c]);
                    self.dynamics.v[c].copy_from_slice(&self.good_v[c]);
                }
                self.time_s = t;
            }
            None => self.to_rest(),
        }
        self.tool = Tool::None;
        self.tool_force = [0.0; 3];
    }

    /// Why the state is not good, if it is not: a NaN, a node more than the cube's side from
    /// its rest position (bounded relative to the cube, not to some absolute size), or a kinetic
    /// energy of the whole mass moving at 10 m/s.
    fn unhealthy(&self) -> Option<Unhealthy> {
        let l = crate::grid::CUBE_SIDE_M;
        let finite = self.dynamics.x.iter().chain(&self.dynamics.v).all(|c| c.iter().all(|v| v.is_finite()));
        if !finite {
            return Some(Unhealthy::NonFinite);
        }
        let grid = self.model.grid;
        for p in 0..grid.num_nodes() {
            let r = grid.position(p);
            if (0..3).any(|c| (self.dynamics.x[c][p] - r[c]).abs() > l) {
                return Some(Unhealthy::OutsideCube);
            }
        }
        let mass = self.model.node_mass * grid.num_nodes() as f64;
        if self.dynamics.kinetic_energy(&self.model) > 0.5 * mass * 10.0 * 10.0 {
            return Some(Unhealthy::Energy);
        }
        None
    }

    fn apply_tool_load(&mut self) {
        for c in 0..3 {
            self.dynamics.f_ext[c].copy_from_slice(&self.base_load[c]);
        }
        if self.tool == Tool::None {
            self.tool_force = [0.0; 3];
        }
        if let Tool::Drag { node, target } = self.tool {
            let mut f = [0.0; 3];
            for c in 0..3 {
                f[c] =
                    DRAG_STIFFNESS * (target[c] - self.dynamics.x[c][node]) - DRAG_DAMPING * self.dynamics.v[c][node];
                self.dynamics.f_ext[c][node] += f[c];
            }
            self.tool_force = f.map(|v| -v);
        }
    }

    /// Projects nodes out of the probe sphere, removes their inward velocity, and sums the
    /// tissue's push on the probe (the inward part of each contact node's spring force).
    fn enforce_contact(&mut self) {
        let Tool::Probe { centre, radius } = self.tool else {
            return;
        };
        let mut push = [0.0; 3];
        let computed = self.dynamics.forces(&self.model);
        for c in 0..3 {
            self.contact_forces[c].copy_from_slice(&computed[c]);
        }
        let forces = &self.contact_forces;
        let x = &mut self.dynamics.x;
        let v = &mut self.dynamics.v;
        for p in 0..x[0].len() {
            if self.dynamics.free[p] == 0.0 {
                continue;
            }
            let d = [x[0][p] - centre[0], x[1][p] - centre[1], x[2][p] - centre[2]];
            let dist = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if dist >= radius {
                continue;
            }
            let n = if dist > 1e-12 { d.map(|c| c / dist) } else { [0.0, 0.0, 1.0] };
            for c in 0..3 {
                x[c][p] = centre[c] + radius * n[c];
            }
            let vn = v[0][p] * n[0] + v[1][p] * n[1] + v[2][p] * n[2];
            if vn < 0.0 {
                for c in 0..3 {
                    v[c][p] -= vn * n[c];
                }
            }
            let fn_ = forces[0][p] * n[0] + forces[1][p] * n[1] + forces[2][p] * n[2];
            if fn_ < 0.0 {
                for c in 0..3 {
                    push[c] += fn_ * n[c];
                }
            }
        }
        self.tool_force = push;
    }

    /// Node positions as f32 for drawing.
    pub fn positions_f32(&self, out: &mut [[f32; 3]]) {
        for (p, o) in out.iter_mut().enumerate() {
            *o = [self.dynamics.x[0][p] as f32, self.dynamics.x[1][p] as f32, self.dynamics.x[2][p] as f32];
        }
    }
}
