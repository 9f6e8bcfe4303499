//! The running tissue: any [`Tissue`] model stepped at a fixed time step under the step policy,
//! with the user's tools and a blow-up guard.
//!
//! The guard checks the state once a tick ([`super::TICK_S`]) under symplectic Euler, after
//! every step under an implicit one. Where the tissue's state stays on the GPU between steps
//! ([`Tissue::state_on_device`]), the guard reads the GPU's figures of a step instead of the
//! state, the last good state is kept where the state comes back ([`Simulation::sync`], to
//! draw or read it), the drag's split step runs there (its force on the hand comes back with the
//! guard's figures), and only the model's own node contact (or a drag on a fixed node) brings the
//! state back every step.
//!
//! `guard`: the blow-up guard; `tools`: the drag and the probe's contact.

use super::integrator::{DEFAULT_DYNAMIC_BUDGET, Integrator, StepLimit, choose_step};
use super::msm_tissue::MsmTissue;
use super::tissue::Tissue;
use super::tool::Tool;
use crate::mechanics::cases::LoadCase;
use crate::mechanics::msm::{MsmModel, MsmParams};

mod guard;
mod tools;

pub use guard::{BlowUp, MAX_RECOVERIES};
use tools::MarkedNodes;

/// The running tissue.
#[derive(Debug)]
pub struct Simulation {
    /// The model and its state.
    pub tissue: Box<dyn Tissue>,
    /// Integrator.
    pub integrator: Integrator,
    /// What was asked for (`None`: the automatic choice), kept for [`Simulation::set_params`].
    requested: Option<Integrator>,
    /// The step asked for, s (the automatic choice may run substeps of it).
    requested_dt: f64,
    /// Time step, s.
    pub dt: f64,
    /// The active tool.
    pub tool: Tool,
    /// Simulated time, s.
    pub time_s: f64,
    base_load: [Vec<f64>; 3],
    /// The nodes whose load the tools changed from `base_load` in the last step: only these are
    /// restored before the next.
    tool_loaded: MarkedNodes,
    /// Force of the tissue on the tool, newtons (last step).
    pub tool_force: [f64; 3],
    /// Last good state (positions, velocities, time), refreshed every 100 healthy steps (for a
    /// state on the GPU, where it comes back: [`Simulation::sync`] and any step that brings it).
    good_x: [Vec<f64>; 3],
    good_v: [Vec<f64>; 3],
    good_time: Option<f64>,
    steps_since_good: usize,
    /// Steps since the guard last checked a state that stays on the GPU.
    steps_unchecked: usize,
    /// The node the GPU holds by the drag's split step, if any (its force on the hand comes
    /// with the guard's figures).
    device_drag: Option<usize>,
    rest: [Vec<f64>; 3],
    /// Nodes on the cube's surface: the only ones the probe touches.
    surface: Vec<usize>,
    /// The probe on the material's surface compliance, when set.
    surface_probe: Option<crate::sim::material_surface::SurfaceProbe>,
    /// Whether this step's probe force came from the surface compliance.
    probe_on_surface: bool,
    contact_forces: [Vec<f64>; 3],
    /// Positions at the start of the step, for the node contact's projection.
    step_start_x: [Vec<f64>; 3],
    /// Blow-ups since the last healthy step past the previous blow-up's time.
    recoveries: u32,
    /// Simulated time of the last blow-up, s.
    last_blow_up_s: f64,
}

impl Simulation {
    /// A mass-spring `model` at rest, one face clamped by `case` (if any) with its loads.
    pub fn new(model: MsmModel, integrator: Integrator, dt: f64, case: Option<&LoadCase>) -> Self {
        let density = model.node_mass * model.grid.num_nodes() as f64 / crate::mechanics::grid::CUBE_SIDE_M.powi(3);
        Self::with_tissue(Box::new(MsmTissue::new(model, density)), integrator, dt, case)
    }

    /// Any tissue model at rest, one face clamped by `case` (if any) with its loads.
    pub fn with_tissue(mut tissue: Box<dyn Tissue>, integrator: Integrator, dt: f64, case: Option<&LoadCase>) -> Self {
        if let Some(c) = case {
            tissue.apply_case(c);
        }
        let base_load = tissue.f_ext_mut().clone();
        let grid = tissue.grid();
        let nn = grid.num_nodes();
        let zeros = || std::array::from_fn(|_| vec![0.0; nn]);
        let rest = std::array::from_fn(|c| (0..nn).map(|p| grid.position(p)[c]).collect());
        Self {
            integrator,
            requested: Some(integrator),
            requested_dt: dt,
            dt,
            tool: Tool::None,
            time_s: 0.0,
            base_load,
            tool_loaded: MarkedNodes::new(nn),
            tool_force: [0.0; 3],
            good_x: zeros(),
            good_v: zeros(),
            good_time: None,
            steps_since_good: 0,
            steps_unchecked: 0,
            device_drag: None,
            rest,
            surface: (0..nn).filter(|&p| grid.on_boundary(p)).collect(),
            surface_probe: None,
            probe_on_surface: false,
            contact_forces: zeros(),
            step_start_x: zeros(),
            recoveries: 0,
            last_blow_up_s: f64::NEG_INFINITY,
            tissue,
        }
    }

    /// The explicit stability limit of the running model (cached by the model), s.
    pub fn dt_limit(&self) -> f64 {
        self.tissue.explicit_dt_limit()
    }

    /// The limit the step policy respects: the tissue's (the tools do not bound the step).
    pub fn limit(&self) -> StepLimit {
        self.tissue.step_limit()
    }

    /// Sets the integrator and step by [`choose_step`] (the automatic choice meets the viewer's
    /// dynamic budget, [`DEFAULT_DYNAMIC_BUDGET`]), or says why it refuses (nothing changed but
    /// the request, which new parameters or damping apply again). Returns what the policy says.
    pub fn try_set_integrator(&mut self, requested: Option<Integrator>, dt: f64) -> Result<Option<String>, String> {
        self.requested = requested;
        self.requested_dt = dt;
        let (i, h, note) = choose_step(requested, dt, self.limit(), self.tissue.damping(), DEFAULT_DYNAMIC_BUDGET)?;
        (self.integrator, self.dt) = (i, h);
        Ok(note)
    }

    /// [`Simulation::try_set_integrator`]; on a refusal switches to the automatic choice
    /// (prefactored implicit Euler at `dt` if even that refuses) and says so.
    pub fn set_integrator(&mut self, requested: Option<Integrator>, dt: f64) -> Option<String> {
        match self.try_set_integrator(requested, dt) {
            Ok(note) => note,
            Err(why) => match choose_step(None, dt, self.limit(), self.tissue.damping(), DEFAULT_DYNAMIC_BUDGET) {
                Ok((i, h, _)) => {
                    (self.integrator, self.dt) = (i, h);
                    Some(format!("{why}: switched to the automatic choice, {} at {} s", i.name(), crate::io::num(h)))
                }
                Err(_) => {
                    (self.integrator, self.dt) = (Integrator::Prefactored, dt);
                    Some(format!("{why}: switched to prefactored implicit Euler"))
                }
            },
        }
    }

    /// Replaces the parameters, keeping the state (a calibration result applied live), and
    /// applies the integrator policy to the new explicit limit (what it says, if anything).
    pub fn set_params(&mut self, params: MsmParams) -> Result<Option<String>, String> {
        self.tissue.set_params(params)?;
        Ok(self.set_integrator(self.requested, self.requested_dt))
    }

    /// Damps the tissue by the ratio `zeta` at its fundamental and applies the integrator policy
    /// again (what it says, if anything).
    pub fn set_damping_ratio(&mut self, zeta: f64) -> Result<Option<String>, String> {
        self.tissue.set_damping_ratio(zeta)?;
        if let Some(probe) = &mut self.surface_probe {
            probe.set_damping_ratio(zeta);
        }
        Ok(self.set_integrator(self.requested, self.requested_dt))
    }

    /// Node displacements from rest, row = node.
    pub fn displacements(&self) -> Vec<[f64; 3]> {
        let x = self.tissue.x();
        (0..x[0].len()).map(|p| std::array::from_fn(|c| x[c][p] - self.rest[c][p])).collect()
    }

    /// Applies a load case (fixed nodes and loads), keeping the state.
    pub fn apply_case(&mut self, case: &LoadCase) {
        self.tissue.apply_case(case);
        let f = self.tissue.f_ext_mut();
        for c in 0..3 {
            self.base_load[c].copy_from_slice(&f[c]);
        }
        self.tool_loaded.clear();
        self.good_time = None;
    }

    /// Back to rest (positions and velocities), keeping fixed nodes and loads; the guard's count
    /// starts again.
    pub fn reset(&mut self) {
        self.back_to_rest();
        self.recoveries = 0;
        self.last_blow_up_s = f64::NEG_INFINITY;
    }

    fn back_to_rest(&mut self) {
        self.tissue.discard_device_state();
        let (x, v) = self.tissue.x_v_mut();
        for c in 0..3 {
            x[c].copy_from_slice(&self.rest[c]);
            v[c].fill(0.0);
        }
        if let Some(probe) = &mut self.surface_probe {
            probe.reset();
        }
        self.time_s = 0.0;
        self.good_time = None;
    }

    /// Advances one step; on a blow-up restores the last good state and says why.
    pub fn step(&mut self) -> Result<(), BlowUp> {
        // Where the state stays on the GPU, it comes back every step only where something here
        // reads or moves nodes: an implicit step (on the CPU's model, with the anchored drag),
        // the node contact, a drag on a fixed node. The drag's split step on a free node runs
        // there under symplectic Euler.
        let on_device = self.tissue.state_on_device();
        let implicit = self.integrator != Integrator::Symplectic;
        let mut stepped = if on_device && implicit { self.tissue.sync() } else { Ok(()) };
        if let Err(message) = self.apply_tool_load() {
            // The tool is let go and the run told: its force cannot be given truly.
            self.tool = Tool::None;
            self.tool_force = [0.0; 3];
            let _ = self.apply_tool_load();
            return Err(BlowUp { time_s: self.time_s, message, fatal: true });
        }
        let anchored = self.anchor_drag();
        let drag = match self.tool {
            Tool::Drag { node, target } if !implicit && self.tissue.free()[node] != 0.0 => Some((node, target)),
            _ => None,
        };
        self.device_drag = if on_device && self.tissue.hold_by_drag(drag) { drag.map(|(p, _)| p) } else { None };
        let drags_here = matches!(self.tool, Tool::Drag { .. }) && self.device_drag.is_none();
        let reads_nodes = on_device && (self.node_contact() || drags_here);
        if stepped.is_ok() && reads_nodes {
            stepped = self.tissue.sync();
        }
        if self.node_contact() {
            let x = self.tissue.x();
            for &p in &self.surface {
                for c in 0..3 {
                    self.step_start_x[c][p] = x[c][p];
                }
            }
        }
        if stepped.is_ok() {
            stepped = self.tissue.step(self.integrator, self.dt);
        }
        if stepped.is_ok() && reads_nodes {
            stepped = self.tissue.sync();
        }
        if stepped.is_ok() {
            if anchored {
                self.anchored_drag_force();
            } else if self.device_drag.is_none() {
                self.drag_step();
            }
        }
        if let Some(probe) = &mut self.surface_probe {
            probe.advance(self.dt);
        }
        self.enforce_contact();
        self.time_s += self.dt;
        // The guard reads the state after every implicit step, and every step where nodes come
        // back from the GPU; after symplectic steps, once a tick (the state here, or the GPU's
        // figures of the step that ends the tick): a check costs about as much as the axis
        // lattice's step at 24^3 (80 us), and a blow-up is caught within the tick.
        let every_step = implicit || reads_nodes;
        let here = !on_device || every_step;
        self.steps_unchecked += 1;
        if stepped.is_ok() && !every_step && self.steps_unchecked as f64 * self.dt < super::TICK_S * (1.0 - 1e-9) {
            return Ok(());
        }
        self.steps_unchecked = 0;
        let (unhealthy, brought_back) = match stepped.and_then(|()| self.check()) {
            Ok(checked) => checked,
            Err(e) => return Err(self.blow_up(Err(e), None)),
        };
        if unhealthy.is_some() {
            return Err(self.blow_up(Ok(()), unhealthy));
        }
        if self.time_s > self.last_blow_up_s {
            self.recoveries = 0;
        }
        self.steps_since_good += 1;
        if (here || brought_back) && (self.good_time.is_none() || self.steps_since_good >= 100) {
            self.keep_good();
        }
        Ok(())
    }

    /// Node positions as f32 for drawing.
    pub fn positions_f32(&self, out: &mut [[f32; 3]]) {
        let x = self.tissue.x();
        for (p, o) in out.iter_mut().enumerate() {
            *o = [x[0][p] as f32, x[1][p] as f32, x[2][p] as f32];
        }
    }
}
