//! The running tissue: any [`Tissue`] model stepped at a fixed time step under the step policy,
//! with the user's tools and a blow-up guard.

use super::integrator::{DEFAULT_DYNAMIC_BUDGET, Integrator, StepLimit, choose_step};
use super::msm_tissue::MsmTissue;
use super::tissue::Tissue;
use super::tool::{DRAG_DAMPING, DRAG_STIFFNESS, Tool, drag_dt_limit};
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
    /// The nodes a drag may hold (`None`: any free node), whose lightest bounds the step.
    draggable: Option<Vec<usize>>,
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
    rest: [Vec<f64>; 3],
    /// Nodes on the cube's surface: the only ones the probe touches.
    surface: Vec<bool>,
    /// The probe on the material's surface compliance, when set.
    surface_probe: Option<super::surface_probe::SurfaceProbe>,
    /// Whether this step's probe force came from the surface compliance.
    probe_on_surface: bool,
    contact_forces: [Vec<f64>; 3],
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
            draggable: None,
            dt,
            tool: Tool::None,
            time_s: 0.0,
            base_load,
            tool_force: [0.0; 3],
            good_x: zeros(),
            good_v: zeros(),
            good_time: None,
            steps_since_good: 0,
            rest,
            surface: (0..nn).map(|p| grid.on_boundary(p)).collect(),
            surface_probe: None,
            probe_on_surface: false,
            contact_forces: zeros(),
            recoveries: 0,
            last_blow_up_s: f64::NEG_INFINITY,
            tissue,
        }
    }

    /// The explicit stability limit of the running model (cached by the model), s.
    pub fn dt_limit(&self) -> f64 {
        self.tissue.explicit_dt_limit()
    }

    /// The limits the step policy respects: the tissue's, and the dragging spring's on the
    /// lightest node a drag may hold.
    pub fn limit(&self) -> StepLimit {
        let free = self.tissue.free();
        let mass = |p: usize| if free[p] == 0.0 { f64::INFINITY } else { self.tissue.node_mass(p) };
        let lightest = match &self.draggable {
            Some(nodes) => nodes.iter().map(|&p| mass(p)).fold(f64::INFINITY, f64::min),
            None => (0..free.len()).map(mass).fold(f64::INFINITY, f64::min),
        };
        let tool = if lightest.is_finite() { drag_dt_limit(lightest) } else { f64::INFINITY };
        StepLimit { tissue: self.dt_limit(), tool }
    }

    /// Restricts the drag to `nodes` (a script's, known before it runs; by default any free node
    /// may be held); the step policy applied next counts only these.
    pub fn set_draggable(&mut self, nodes: Vec<usize>) {
        self.draggable = Some(nodes);
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
        self.apply_tool_load();
        let stepped = self.tissue.step(self.integrator, self.dt);
        if let Some(probe) = &mut self.surface_probe {
            probe.advance(self.dt);
        }
        self.enforce_contact();
        self.time_s += self.dt;
        let unhealthy = if stepped.is_ok() { self.unhealthy() } else { None };
        if stepped.is_ok() && unhealthy.is_none() {
            if self.time_s > self.last_blow_up_s {
                self.recoveries = 0;
            }
            self.steps_since_good += 1;
            if self.good_time.is_none() || self.steps_since_good >= 100 {
                let (x, v) = (self.tissue.x(), self.tissue.v());
                for c in 0..3 {
                    self.good_x[c].copy_from_slice(&x[c]);
                    self.good_v[c].copy_from_slice(&v[c]);
                }
                self.good_time = Some(self.time_s);
                self.steps_since_good = 0;
            }
            return Ok(());
        }
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
        Err(BlowUp { time_s, message, fatal })
    }

    /// What went wrong in a step that failed or left the state unhealthy, and what to change.
    fn diagnose(&self, stepped: Result<(), String>, unhealthy: Option<Unhealthy>) -> String {
        let limit = self.dt_limit();
        let dt = crate::io::num(self.dt);
        if let Err(e) = stepped {
            return format!("the implicit solve failed ({e}); the state was reset");
        }
        if self.integrator == Integrator::Symplectic && self.dt > limit {
            return format!(
                "diverged: symplectic Euler with dt = {dt} s is above its stability limit of about {} s for this \
                 stiffness; the state was reset. Lower dt or choose the implicit integrator.",
                crate::io::num(limit)
            );
        }
        if let Tool::Drag { node, target } = self.tool {
            let spring = drag_dt_limit(self.tissue.node_mass(node));
            if self.dt > spring {
                return format!(
                    "diverged: the dragging spring ({DRAG_STIFFNESS} N/m, {DRAG_DAMPING} N s/m) on node {node} is \
                     stable only below about {} s, and dt = {dt} s; the state was reset. Lower dt, or leave the \
                     integrator to the automatic choice, which takes the spring into account.",
                    crate::io::num(spring)
                );
            }
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
    fn unhealthy(&self) -> Option<Unhealthy> {
        let l = crate::mechanics::grid::CUBE_SIDE_M;
        let (x, v) = (self.tissue.x(), self.tissue.v());
        let finite = x.iter().chain(v).all(|c| c.iter().all(|v| v.is_finite()));
        if !finite {
            return Some(Unhealthy::NonFinite);
        }
        // A cube held nowhere may move as a whole (a drag carries it along): its mean
        // displacement is motion, not deformation.
        let held = self.tissue.free().contains(&0.0);
        for c in 0..3 {
            let shift = if held {
                0.0
            } else {
                x[c].iter().zip(&self.rest[c]).map(|(x, r)| x - r).sum::<f64>() / x[c].len() as f64
            };
            if x[c].iter().zip(&self.rest[c]).any(|(x, r)| (x - r - shift).abs() > l) {
                return Some(Unhealthy::OutsideCube);
            }
        }
        if self.tissue.kinetic_energy() > 0.5 * self.tissue.total_mass() * 10.0 * 10.0 {
            return Some(Unhealthy::Energy);
        }
        None
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
        let drag = match self.tool {
            Tool::Drag { node, target } => {
                let (x, v) = (self.tissue.x(), self.tissue.v());
                let f: [f64; 3] =
                    std::array::from_fn(|c| DRAG_STIFFNESS * (target[c] - x[c][node]) - DRAG_DAMPING * v[c][node]);
                Some((node, f))
            }
            _ => None,
        };
        let f_ext = self.tissue.f_ext_mut();
        for c in 0..3 {
            f_ext[c].copy_from_slice(&self.base_load[c]);
        }
        if let Some((node, f)) = drag {
            for c in 0..3 {
                f_ext[c][node] += f[c];
            }
            self.tool_force = f.map(|v| -v);
        }
        if let (Tool::Probe { centre, radius }, Some(probe)) = (self.tool, self.surface_probe.as_mut())
            && super::surface_probe::SurfaceProbe::covers(centre)
            && let Ok(force) = probe.update(centre, radius)
        {
            for &(node, f) in probe.loads() {
                for c in 0..3 {
                    f_ext[c][node] += f[c];
                }
            }
            self.tool_force = force;
            self.probe_on_surface = true;
        } else if let Some(probe) = self.surface_probe.as_mut() {
            probe.release();
        }
    }

    /// Projects nodes out of the probe sphere, removes their inward velocity, and sums the
    /// tissue's push on the probe (the inward part of each contact node's spring force).
    fn enforce_contact(&mut self) {
        let Tool::Probe { centre, radius } = self.tool else {
            return;
        };
        if self.probe_on_surface {
            return;
        }
        let mut push = [0.0; 3];
        let nn = self.rest[0].len();
        // The force on every node before any is projected.
        let computed = self.tissue.forces();
        for c in 0..3 {
            self.contact_forces[c].copy_from_slice(&computed[c]);
        }
        for p in 0..nn {
            if self.tissue.free()[p] == 0.0 || !self.surface[p] {
                continue;
            }
            let x = self.tissue.x();
            let d = [x[0][p] - centre[0], x[1][p] - centre[1], x[2][p] - centre[2]];
            let dist = DVec3::from(d).length();
            if dist >= radius {
                continue;
            }
            let n = if dist > 1e-12 { d.map(|c| c / dist) } else { [0.0, 0.0, 1.0] };
            let f = [self.contact_forces[0][p], self.contact_forces[1][p], self.contact_forces[2][p]];
            let (x, v) = self.tissue.x_v_mut();
            for c in 0..3 {
                x[c][p] = centre[c] + radius * n[c];
            }
            let vn = v[0][p] * n[0] + v[1][p] * n[1] + v[2][p] * n[2];
            if vn < 0.0 {
                for c in 0..3 {
                    v[c][p] -= vn * n[c];
                }
            }
            let fn_ = DVec3::from(f).dot(DVec3::from(n));
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
        let x = self.tissue.x();
        for (p, o) in out.iter_mut().enumerate() {
            *o = [x[0][p] as f32, x[1][p] as f32, x[2][p] as f32];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::fem::dynamics::Formulation;
    use crate::mechanics::material::Material;
    use crate::sim::model::Model;

    /// The viewer's FEM at its 1 ms step, with the drag counted on the lightest free node: the
    /// automatic choice runs 4 symplectic substeps of 0.25 ms, within both limits; a script that
    /// drags no node is bounded by the tissue alone.
    #[test]
    fn the_drag_is_in_the_step_and_only_where_a_drag_may_act() {
        let material = Material::object_a();
        let tissue = Model::Fem(Formulation::Linear).build(&material, None, 0.2).expect("fem");
        let grid = tissue.grid();
        let case = LoadCase::bottom_clamp(&grid, "A");
        let mut sim = Simulation::with_tissue(tissue, Integrator::Symplectic, 1e-3, Some(&case));
        sim.set_integrator(None, 1e-3);
        assert_eq!((sim.integrator, sim.dt), (Integrator::Symplectic, 2.5e-4));
        let limit = sim.limit();
        assert!(limit.tool.is_finite() && sim.dt <= 0.9 * limit.of(Integrator::Symplectic), "{limit:?}");
        sim.set_draggable(Vec::new());
        assert!(sim.try_set_integrator(None, 1e-3).is_ok());
        assert_eq!(sim.limit().tool, f64::INFINITY);
        // Asked for by name at 1 ms, prefactored Euler is refused for the corner node.
        sim.set_draggable(vec![grid.num_nodes() - 1]);
        let why = sim.try_set_integrator(Some(Integrator::Prefactored), 1e-3).expect_err("the corner's spring");
        assert!(why.contains("dragging spring"), "{why}");
    }
}
