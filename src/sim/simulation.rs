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

use super::integrator::{DEFAULT_DYNAMIC_BUDGET, Integrator, StepLimit, choose_step};
use super::msm_tissue::MsmTissue;
use super::tissue::Tissue;
use super::tool::{DRAG_DAMPING, DRAG_STIFFNESS, Tool, drag_velocity_change};
use crate::mechanics::anchor::Anchor;
use crate::mechanics::cases::LoadCase;
use crate::mechanics::msm::{MsmModel, MsmParams};
use glam::DVec3;

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

/// A state whose kinetic energy is that of the whole mass moving at this speed has run away,
/// m/s.
const RUNAWAY_SPEED_M_S: f64 = 10.0;

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
    surface_probe: Option<super::surface_probe::SurfaceProbe>,
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
        self.apply_tool_load();
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

    /// The guard: why the state now is not good, read where it lives (the GPU's figures of its
    /// last step, or, for a cube held nowhere, whose motion as a whole only the state shows,
    /// the state brought back); and whether the state was brought back for it.
    fn check(&mut self) -> Result<(Option<Unhealthy>, bool), String> {
        match self.tissue.step_health() {
            Some(health) if self.tissue.free().contains(&0.0) => {
                let health = health?;
                self.device_drag_force(health);
                Ok((self.unhealthy_figures(health), false))
            }
            Some(health) => Ok((self.bring_back(health)?, true)),
            None => Ok((self.unhealthy(), false)),
        }
    }

    /// The state brought back from the GPU after its last step's figures `health` (the drag's
    /// force), and why it is not good, if it is not.
    fn bring_back(&mut self, health: Result<super::tissue::StepHealth, String>) -> Result<Option<Unhealthy>, String> {
        self.device_drag_force(health?);
        self.tissue.sync()?;
        Ok(self.unhealthy())
    }

    /// After a failed step or an unhealthy state: restores the last good state (or rest after
    /// [`MAX_RECOVERIES`] in a row) and says why.
    fn blow_up(&mut self, stepped: Result<(), String>, unhealthy: Option<Unhealthy>) -> BlowUp {
        let message = self.diagnose(stepped, unhealthy);
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
        BlowUp { time_s, message, fatal }
    }

    /// The state now as the last good one.
    fn keep_good(&mut self) {
        let (x, v) = (self.tissue.x(), self.tissue.v());
        for c in 0..3 {
            self.good_x[c].copy_from_slice(&x[c]);
            self.good_v[c].copy_from_slice(&v[c]);
        }
        self.good_time = Some(self.time_s);
        self.steps_since_good = 0;
    }

    /// Brings the tissue's state back where its steps left it on the GPU (nothing to do on the
    /// CPU, or where it has not stepped since), to draw or read it, and checks it: a healthy
    /// state is kept as the last good one, an unhealthy one is a blow-up as in
    /// [`Simulation::step`].
    pub fn sync(&mut self) -> Result<(), BlowUp> {
        let Some(health) = self.tissue.step_health() else {
            return Ok(());
        };
        match self.bring_back(health) {
            Ok(None) => {
                self.keep_good();
                Ok(())
            }
            Ok(unhealthy) => Err(self.blow_up(Ok(()), unhealthy)),
            Err(e) => Err(self.blow_up(Err(e), None)),
        }
    }

    /// What went wrong in a step that failed or left the state unhealthy, and what to change.
    fn diagnose(&self, stepped: Result<(), String>, unhealthy: Option<Unhealthy>) -> String {
        let limit = self.dt_limit();
        let dt = crate::io::num(self.dt);
        if let Err(e) = stepped {
            return if self.tissue.state_on_device() && self.integrator == Integrator::Symplectic {
                format!("the GPU's step or its readback failed ({e}); the state was reset")
            } else {
                format!("the implicit solve failed ({e}); the state was reset")
            };
        }
        if self.integrator == Integrator::Symplectic && self.dt > limit {
            return format!(
                "diverged: symplectic Euler with dt = {dt} s is above its stability limit of about {} s for this \
                 stiffness; the state was reset. Lower dt or choose the implicit integrator.",
                crate::io::num(limit)
            );
        }
        if let Tool::Drag { node, target } = self.tool {
            let reach = DVec3::from(target).distance(DVec3::from(std::array::from_fn(|c| self.rest[c][node])));
            if unhealthy == Some(Unhealthy::OutsideCube) && reach > crate::mechanics::grid::CUBE_SIDE_M {
                return "the dragged node was pulled more than the cube's side (0.1 m) from rest; the state was \
                        reset. Keep the drag target near the cube (positions are in metres)."
                    .to_owned();
            }
        }
        match unhealthy {
            Some(Unhealthy::OutsideCube) => "a node moved more than the cube's side (0.1 m) from rest; the state was \
                 reset. Lower the loads or dt, or choose the implicit integrator."
                .to_owned(),
            _ => "diverged (non-finite or runaway energy); the state was reset. Lower dt, soften the tool, or choose \
                  the implicit integrator."
                .to_owned(),
        }
    }

    fn restore(&mut self) {
        match self.good_time {
            Some(t) => {
                self.tissue.discard_device_state();
                let (x, v) = self.tissue.x_v_mut();
                for c in 0..3 {
                    x[c].copy_from_slice(&self.good_x[c]);
                    v[c].copy_from_slice(&self.good_v[c]);
                }
                self.time_s = t;
            }
            None => self.back_to_rest(),
        }
        if let Some(probe) = &mut self.surface_probe {
            probe.reset();
        }
        self.tool = Tool::None;
        self.tool_force = [0.0; 3];
    }

    /// Why the state is not good, if it is not: a NaN, a node more than the cube's side from
    /// its rest position (bounded relative to the cube, not to some absolute size), or a kinetic
    /// energy of the whole mass moving at 10 m/s.
    ///
    /// The guard runs every tick on a state here, so its common case reads each array once (the positions twice
    /// for a cube held nowhere, whose mean shift comes first): a NaN or infinity fails the
    /// displacement's and the energy's comparisons too (both are written to fail on a NaN), and
    /// only a state that fails them is searched for one, to name the cause.
    fn unhealthy(&self) -> Option<Unhealthy> {
        let l = crate::mechanics::grid::CUBE_SIDE_M;
        let (x, v) = (self.tissue.x(), self.tissue.v());
        // A cube held nowhere may move as a whole (a drag carries it along): its mean
        // displacement is motion, not deformation.
        let held = self.tissue.free().contains(&0.0);
        // False on a NaN.
        let within = |d: f64, bound: f64| d <= bound;
        let outside = (0..3).any(|c| {
            let shift = if held {
                0.0
            } else {
                x[c].iter().zip(&self.rest[c]).map(|(x, r)| x - r).sum::<f64>() / x[c].len() as f64
            };
            // A fold without an early exit: the compiler vectorises it.
            x[c].iter().zip(&self.rest[c]).fold(false, |out, (x, r)| out | !within((x - r - shift).abs(), l))
        });
        let energetic = !within(self.tissue.kinetic_energy(), self.runaway_energy());
        if !(outside || energetic) {
            return None;
        }
        let finite = x.iter().chain(v).all(|c| c.iter().all(|v| v.is_finite()));
        Some(if !finite {
            Unhealthy::NonFinite
        } else if outside {
            Unhealthy::OutsideCube
        } else {
            Unhealthy::Energy
        })
    }

    /// The force on the hand of the drag the GPU steps, `-m dv / dt` from its last step.
    fn device_drag_force(&mut self, health: super::tissue::StepHealth) {
        if let Some(node) = self.device_drag {
            let m = self.tissue.node_mass(node);
            self.tool_force = health.held_velocity_change_m_s.map(|d| -m * d / self.dt);
        }
    }

    /// The kinetic energy of a state that has run away, J.
    fn runaway_energy(&self) -> f64 {
        0.5 * self.tissue.total_mass() * RUNAWAY_SPEED_M_S * RUNAWAY_SPEED_M_S
    }

    /// [`Simulation::unhealthy`] from the GPU's figures of a step, for a held cube: a NaN, a node
    /// more than the cube's side from rest, or a runaway energy.
    fn unhealthy_figures(&self, health: super::tissue::StepHealth) -> Option<Unhealthy> {
        if !(health.kinetic_energy_j.is_finite() && health.largest_displacement_m.is_finite()) {
            Some(Unhealthy::NonFinite)
        } else if health.largest_displacement_m > crate::mechanics::grid::CUBE_SIDE_M {
            Some(Unhealthy::OutsideCube)
        } else if health.kinetic_energy_j > self.runaway_energy() {
            Some(Unhealthy::Energy)
        } else {
            None
        }
    }

    /// Sets the probe's contact: on the material's surface compliance (`Some`), or the running
    /// model's surface nodes (`None`).
    pub fn set_surface_probe(&mut self, probe: Option<super::surface_probe::SurfaceProbe>) {
        self.surface_probe = probe;
    }

    /// Whether the probe pushes back through the material's surface compliance.
    pub fn has_surface_probe(&self) -> bool {
        self.surface_probe.is_some()
    }

    fn apply_tool_load(&mut self) {
        if self.tool == Tool::None {
            self.tool_force = [0.0; 3];
        }
        self.probe_on_surface = false;
        let carries = self.tissue.carries_contact_loads();
        // The load is taken only where it changes (a GPU step sends it again when taken).
        if let Some(nodes) = span(self.tool_loaded.nodes().iter().copied()) {
            let f_ext = self.tissue.f_ext_mut_nodes(nodes);
            for &p in self.tool_loaded.nodes() {
                for c in 0..3 {
                    f_ext[c][p] = self.base_load[c][p];
                }
            }
            self.tool_loaded.clear();
        }
        if let (Tool::Probe { centre, radius }, Some(probe)) = (self.tool, self.surface_probe.as_mut())
            && super::surface_probe::SurfaceProbe::covers(centre)
            && let Ok(force) = probe.update(centre, radius)
        {
            if carries && let Some(nodes) = span(probe.loads().iter().map(|&(node, _)| node)) {
                let f_ext = self.tissue.f_ext_mut_nodes(nodes);
                for &(node, f) in probe.loads() {
                    for c in 0..3 {
                        f_ext[c][node] += f[c];
                    }
                    self.tool_loaded.mark(node);
                }
            }
            self.tool_force = force;
            self.probe_on_surface = true;
        } else if let Some(probe) = self.surface_probe.as_mut() {
            probe.release();
        }
    }

    /// Under an implicit scheme, the dragging spring goes inside the tissue's solve
    /// ([`crate::mechanics::anchor`]): its node anchored, its pull at the step's start added to
    /// the node's load. Says whether it did (not under symplectic Euler, on a fixed node or for
    /// a model without implicit steps: then [`Simulation::drag_step`] follows the step).
    fn anchor_drag(&mut self) -> bool {
        let held = match self.tool {
            Tool::Drag { node, target }
                if self.integrator != Integrator::Symplectic && self.tissue.free()[node] != 0.0 =>
            {
                Some((node, target))
            }
            _ => None,
        };
        let Some((node, target)) = held else {
            self.tissue.set_anchor(None);
            return false;
        };
        if !self.tissue.set_anchor(Some(Anchor { node, stiffness: DRAG_STIFFNESS, damping: DRAG_DAMPING })) {
            return false;
        }
        let pull: [f64; 3] = std::array::from_fn(|c| DRAG_STIFFNESS * (target[c] - self.tissue.x()[c][node]));
        let f_ext = self.tissue.f_ext_mut_nodes(node..node + 1);
        for c in 0..3 {
            f_ext[c][node] += pull[c];
        }
        self.tool_loaded.mark(node);
        true
    }

    /// The anchored drag's force on the hand: minus the spring and damper's on the node at the
    /// step's end.
    fn anchored_drag_force(&mut self) {
        let Tool::Drag { node, target } = self.tool else {
            return;
        };
        let (x, v) = (self.tissue.x(), self.tissue.v());
        self.tool_force =
            std::array::from_fn(|c| -(DRAG_STIFFNESS * (target[c] - x[c][node]) - DRAG_DAMPING * v[c][node]));
    }

    /// The dragging spring's split step on its node after the tissue's symplectic Euler step
    /// ([`drag_velocity_change`]), and its force on the hand. A fixed node does not move: the
    /// hand feels the spring's static pull.
    fn drag_step(&mut self) {
        let Tool::Drag { node, target } = self.tool else {
            return;
        };
        let (x, v) = (self.tissue.x(), self.tissue.v());
        let (xn, vn): ([f64; 3], [f64; 3]) = (std::array::from_fn(|c| x[c][node]), std::array::from_fn(|c| v[c][node]));
        if self.tissue.free()[node] == 0.0 {
            self.tool_force = std::array::from_fn(|c| -DRAG_STIFFNESS * (target[c] - xn[c]));
            return;
        }
        let m = self.tissue.node_mass(node);
        let dv = drag_velocity_change(target, xn, vn, m, self.dt);
        let (x, v) = self.tissue.x_v_mut();
        for c in 0..3 {
            v[c][node] += dv[c];
            x[c][node] += self.dt * dv[c];
        }
        self.tool_force = dv.map(|d| -m * d / self.dt);
    }

    /// Whether this step's probe acts by the model's own node contact: with the surface
    /// compliance the hand feels its force, and only a model that cannot carry its loads shows
    /// the press by its own nodes.
    fn node_contact(&self) -> bool {
        matches!(self.tool, Tool::Probe { .. }) && !(self.probe_on_surface && self.tissue.carries_contact_loads())
    }

    /// Moves nodes inside the probe sphere onto it (along their normal at the step's start),
    /// gives their velocity that move, removes their inward velocity, and sums the tissue's push
    /// on the probe (the inward part of each contact node's spring force).
    fn enforce_contact(&mut self) {
        let Tool::Probe { centre, radius } = self.tool else {
            return;
        };
        if !self.node_contact() {
            return;
        }
        let mut push = [0.0; 3];
        // The force on every node before any is projected, for the push on the probe; not needed
        // where the probe's force comes from the material's surface compliance.
        let reads_push = !self.probe_on_surface;
        if reads_push {
            let computed = self.tissue.forces();
            for c in 0..3 {
                self.contact_forces[c].copy_from_slice(&computed[c]);
            }
        }
        for &p in &self.surface {
            if self.tissue.free()[p] == 0.0 {
                continue;
            }
            let x = self.tissue.x();
            let d = [x[0][p] - centre[0], x[1][p] - centre[1], x[2][p] - centre[2]];
            let dist = DVec3::from(d).length();
            if dist >= radius {
                continue;
            }
            // Moved onto the sphere along its normal at the step's start, not radially (SHAKE's
            // projection), and the velocity given the move over the step: a radial projection
            // scaled the node's slide over the sphere without a matching velocity, which fed
            // energy in (a 16^3 FEM under a held 4 mm press rang at 10 to 15 m/s).
            let start = DVec3::from(std::array::from_fn(|c| self.step_start_x[c][p])) - DVec3::from(centre);
            let n0 = if start.length() > 1e-12 { start / start.length() } else { DVec3::Z };
            let (inside, along) = (DVec3::from(d), DVec3::from(d).dot(n0));
            let mu = -along + (along * along - inside.length_squared() + radius * radius).max(0.0).sqrt();
            let on = inside + mu * n0;
            let n = (on / on.length()).to_array();
            let dt = self.dt;
            let (x, v) = self.tissue.x_v_mut();
            for c in 0..3 {
                let projected = centre[c] + radius * n[c];
                v[c][p] += (projected - x[c][p]) / dt;
                x[c][p] = projected;
            }
            let vn = v[0][p] * n[0] + v[1][p] * n[1] + v[2][p] * n[2];
            if vn < 0.0 {
                for c in 0..3 {
                    v[c][p] -= vn * n[c];
                }
            }
            if reads_push {
                let f = DVec3::from(std::array::from_fn(|c| self.contact_forces[c][p]));
                let fn_ = f.dot(DVec3::from(n));
                if fn_ < 0.0 {
                    for c in 0..3 {
                        push[c] += fn_ * n[c];
                    }
                }
            }
        }
        if reads_push {
            self.tool_force = push;
        }
    }

    /// Node positions as f32 for drawing.
    pub fn positions_f32(&self, out: &mut [[f32; 3]]) {
        let x = self.tissue.x();
        for (p, o) in out.iter_mut().enumerate() {
            *o = [x[0][p] as f32, x[1][p] as f32, x[2][p] as f32];
        }
    }
}

/// The range from the least to the greatest of `nodes` (`None` for none).
fn span(nodes: impl Iterator<Item = usize>) -> Option<std::ops::Range<usize>> {
    nodes.fold(None, |r: Option<std::ops::Range<usize>>, p| {
        Some(r.map_or(p..p + 1, |r| r.start.min(p)..r.end.max(p + 1)))
    })
}

/// A set of nodes, each listed once, that allocates nothing after it is made.
#[derive(Debug)]
struct MarkedNodes {
    nodes: Vec<usize>,
    marked: Vec<bool>,
}

impl MarkedNodes {
    fn new(num_nodes: usize) -> Self {
        Self { nodes: Vec::with_capacity(num_nodes), marked: vec![false; num_nodes] }
    }

    fn mark(&mut self, node: usize) {
        if !std::mem::replace(&mut self.marked[node], true) {
            self.nodes.push(node);
        }
    }

    fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    fn clear(&mut self) {
        for &p in &self.nodes {
            self.marked[p] = false;
        }
        self.nodes.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::fem::dynamics::Formulation;
    use crate::mechanics::material::Material;
    use crate::sim::model::Model;

    /// The drag does not bound the step: the viewer's FEM at its 1 ms tick runs the tissue's own
    /// substeps, prefactored Euler asked for at 1 ms is accepted, and a cube corner dragged at
    /// 16^3 (a 37 mg node, whose damper alone once held the step to 70 us) settles where the
    /// spring's pull balances the tissue's push, which the hand feels.
    #[test]
    fn the_drag_does_not_bound_the_step() {
        let material = Material::object_a();
        let tissue = Model::Fem(Formulation::Linear).build(&material, None, 0.2).expect("fem");
        let grid = tissue.grid();
        let case = LoadCase::bottom_clamp(&grid, "A");
        let mut sim = Simulation::with_tissue(tissue, Integrator::Symplectic, 1e-3, Some(&case));
        assert!(sim.try_set_integrator(Some(Integrator::Prefactored), 1e-3).is_ok());
        sim.set_integrator(None, 1e-3);
        assert_eq!(sim.integrator, Integrator::Symplectic);
        assert!(sim.dt <= sim.limit().auto_fraction() * sim.dt_limit() && sim.dt > 0.5 * sim.dt_limit(), "{}", sim.dt);

        let grid = crate::mechanics::grid::Grid::new(16).expect("grid");
        let tissue = Model::Lattice(crate::mechanics::msm::Topology::Hex).build_on(grid, &material, None, 0.2);
        let case = LoadCase::bottom_clamp(&grid, "A");
        let mut sim = Simulation::with_tissue(tissue.expect("hex"), Integrator::Symplectic, 1e-3, Some(&case));
        sim.set_integrator(None, 1e-3);
        let corner = grid.num_nodes() - 1;
        let rest = grid.position(corner);
        let target = [rest[0] + 0.01, rest[1], rest[2]];
        sim.tool = Tool::Drag { node: corner, target };
        let mut forces = Vec::new();
        for _ in 0..(0.4 / sim.dt).round() as usize {
            sim.step().expect("no blow-up");
            forces.push(sim.tool_force[0]);
        }
        let x = sim.tissue.x()[0][corner];
        let pull = DRAG_STIFFNESS * (target[0] - x);
        let last = forces[forces.len() - 1];
        assert!(pull > 0.5 && (last + pull).abs() < 1e-3 * pull, "pull {pull} N, felt {last} N");
        assert!(forces.iter().all(|f| f.abs() <= 1.2 * DRAG_STIFFNESS * 0.01), "{forces:?}");
    }

    /// The probe's loads on the nodes (restored node by node, not copied whole each step) go
    /// when it lifts: the loads are the case's again, bit for bit.
    #[test]
    fn the_probes_loads_go_when_it_lifts() {
        let material = Material::object_a();
        let grid = crate::mechanics::grid::Grid::new(6).expect("grid");
        let tissue = Model::Lattice(crate::mechanics::msm::Topology::Hex).build_on(grid, &material, None, 0.2);
        let case = LoadCase::bottom_clamp(&grid, "A");
        let mut sim = Simulation::with_tissue(tissue.expect("hex"), Integrator::Symplectic, 1e-4, Some(&case));
        let base = sim.tissue.f_ext_mut().clone();
        let compliance =
            crate::response::surface_compliance::SurfaceCompliance::compute(&material, 10, &mut |_| true).expect("c");
        let surface = crate::sim::surface_probe::MaterialSurface {
            compliance: std::sync::Arc::new(compliance),
            modes: std::sync::Arc::new(crate::sim::modal_lag::ModalBasis::of_material(&material).expect("modes")),
        };
        sim.set_surface_probe(Some(crate::sim::surface_probe::SurfaceProbe::on(&surface, grid, Some(0.2))));
        for i in 0..20 {
            let centre = [0.03 + 1e-3 * i as f64, 0.05, 0.1 + 0.015 - 0.003];
            sim.tool = Tool::Probe { centre, radius: 0.015 };
            sim.step().expect("step");
            assert!(sim.tissue.f_ext_mut() != &base, "the probe loads the nodes under it");
        }
        sim.tool = Tool::None;
        sim.step().expect("step");
        assert!(sim.tissue.f_ext_mut() == &base, "the case's loads once the probe lifts");
    }
}
