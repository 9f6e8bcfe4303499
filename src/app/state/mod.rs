//! The viewer's state without a window: what the panel shows and edits, and the one place that
//! turns the user's intent ([`Request`]s from the panel sections and the mouse tools) into
//! physics [`Command`]s and background jobs. Unit-tested without a window or a GPU.
//!
//! Rules live elsewhere and are only asked here: the transversely isotropic ties in
//! [`MsmParams::with_ties`], the integrator policy in [`crate::sim::choose_integrator`] (applied
//! on the physics thread, which publishes the integrator it runs and the explicit limit), the
//! topology in [`MsmParams::topology`]. No model is built on this side: the physics thread builds
//! it from a recipe.

mod jobs;
mod model;

use std::sync::Arc;

use super::calibration_job::Progress;
use super::physics::{Command, Replacement};
pub use super::settings::{ProbeComparison, Shown, ToolKind, ViewSettings};
use super::worker::{Slot, State};
use crate::mechanics::cases::LoadCase;
use crate::mechanics::fem::FemModel;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::msm::{MsmParams, Topology};
use crate::sim::{Integrator, Model, Tool};

/// What the user asked for.
#[derive(Debug, Clone, PartialEq)]
pub enum Request {
    /// Load the object in the settings (a preset or the material file), with its shipped tissue.
    LoadObject,
    /// Another lattice: its shipped calibration (or the material's scale).
    SelectTopology(Topology),
    /// Another resolution: the model on a grid of this many nodes per edge.
    SetResolution(usize),
    /// The model's steps on the CPU or the GPU ([`ViewSettings::compute`]).
    SetCompute,
    /// The FEM in place of the lattice.
    SelectFem(crate::mechanics::fem::dynamics::Formulation),
    /// Solve the FEM's force for the probe's current position (in the background).
    FemProbeForce,
    /// Edited parameters.
    EditParams(MsmParams),
    /// Integrator asked for (`None`: automatic) and time step, s.
    SetIntegrator(Option<Integrator>, f64),
    /// The damping ratio at the fundamental.
    SetDampingRatio(f64),
    /// Back to rest.
    Reset,
    /// The settings' load case, with its FEM answer solved in the background.
    ApplyCase,
    /// Back to the bottom clamp without loads.
    FreeCube,
    /// Start the calibration of the current object and lattice.
    StartCalibration,
    /// Stop it.
    CancelCalibration,
    /// Run the calibration's result.
    ApplyCalibration,
    /// A tool command.
    Tool(Tool),
    /// A new probe press: the force-depth plot starts afresh.
    ProbeStarted,
    /// A probe force sample (depth mm, force N) for the force-depth plot.
    ForceSample([f64; 2]),
}

/// The viewer's state.
pub struct ViewerState {
    /// What the panel edits directly.
    pub settings: ViewSettings,
    /// What it shows.
    pub shown: Shown,
    grid: Grid,
    fem: Slot<Result<Vec<[f64; 3]>, String>>,
    calibration: Slot<Progress>,
    validation: Slot<Result<crate::sim::shipped::RecordedScores, String>>,
    /// The model changed while a validation ran: score it again when that one ends.
    validation_stale: bool,
    fem_probe: Slot<Result<ProbeComparison, String>>,
    compliance: Slot<jobs::ComplianceMessage>,
    /// The material changed while a surface compliance was computed: its result is dropped and
    /// the new material's started when it ends.
    compliance_stale: bool,
    wake: Arc<dyn Fn() + Send + Sync>,
}

/// The time step the viewer gives the FEM, s: one prefactored implicit step per 1 ms tick.
pub const FEM_DT_S: f64 = 1e-3;

/// A resting cube held by its bottom face (z = 0), the viewer's default scene.
pub fn bottom_clamp(grid: &Grid) -> LoadCase {
    LoadCase::bottom_clamp(grid, "view")
}

/// The recipe of the running model for the physics thread: the lattice with `params`, or the FEM.
/// On the GPU ([`crate::gpu::Compute`]) its symplectic steps run as compute shaders.
fn recipe(
    model: Model,
    grid: Grid,
    material: Material,
    params: MsmParams,
    zeta: f64,
    compute: crate::gpu::Compute,
) -> super::physics::TissueRecipe {
    Box::new(move || {
        let tissue = model.build_on(grid, &material, Some(params), zeta).map_err(|e| format!("{e:#}"))?;
        compute.place(tissue).map_err(|e| format!("compute \"{}\": {e}", compute.name()))
    })
}

impl ViewerState {
    /// Object A with its default tissue ([`crate::sim::shipped::DEFAULT_TOPOLOGY`]), and the simulation to start with;
    /// `wake` repaints the UI from background threads.
    pub fn new(wake: impl Fn() + Send + Sync + 'static) -> anyhow::Result<(Self, Replacement)> {
        let grid = Grid::paper();
        let material = Material::object_a();
        let params = crate::sim::shipped::default_params(&material)?;
        let dt = 1e-4;
        let state = Self {
            settings: ViewSettings::default(),
            shown: Shown {
                contact_status: None,
                material,
                params,
                integrator: None,
                dt,
                damping_ratio: crate::response::damping::DEFAULT_DAMPING_RATIO,
                case_active: None,
                fem_answer: None,
                history: Vec::new(),
                result: None,
                calibrating: false,
                calib_generations: 0,
                note: None,
                force_depth: Vec::new(),
                fem: None,
                validation: None,
                tool: Tool::None,
                last_probe: None,
                fem_probe: None,
            },
            grid,
            fem: Slot::default(),
            calibration: Slot::default(),
            validation: Slot::default(),
            validation_stale: false,
            fem_probe: Slot::default(),
            compliance: Slot::default(),
            compliance_stale: false,
            wake: Arc::new(wake),
        };
        let mut state = state;
        state.start_validation();
        state.start_compliance();
        let first = state.replacement();
        Ok((state, first))
    }

    /// The grid shown.
    pub fn grid(&self) -> Grid {
        self.grid
    }

    fn replacement(&self) -> Replacement {
        Replacement {
            recipe: recipe(
                self.shown.model(),
                self.grid,
                self.shown.material.clone(),
                self.shown.params,
                self.shown.damping_ratio,
                self.settings.compute,
            ),
            integrator: self.shown.integrator,
            dt: self.shown.dt,
            case: self.shown.case_active.clone().unwrap_or_else(|| bottom_clamp(&self.grid)),
        }
    }

    /// Carries out `request`, sending what the physics thread must do through `send`.
    pub fn handle(&mut self, request: Request, send: &mut dyn FnMut(Command)) {
        match request {
            Request::LoadObject => self.load_object(self.shown.topology(), send),
            Request::SelectTopology(t) => {
                self.shown.fem = None;
                self.load_object(t, send);
            }
            Request::SelectFem(f) => {
                self.shown.fem = Some(f);
                // One 1 ms tick asked for; the automatic choice takes the substeps that keep the
                // fundamental within the dynamic budget (the Integrator section says which).
                (self.shown.integrator, self.shown.dt) = (None, FEM_DT_S);
                self.shown.note = Some(format!(
                    "FEM: {:.0} ms steps asked for; the automatic choice substeps them to meet the dynamic budget \
                     (see Integrator)",
                    FEM_DT_S * 1e3
                ));
                self.start_validation();
                send(Command::Replace(self.replacement()));
            }
            Request::FemProbeForce => self.start_fem_probe(),
            Request::SetResolution(n) => self.set_resolution(n, send),
            Request::SetCompute => send(Command::Replace(self.replacement())),
            Request::EditParams(p) => {
                let p = p.with_ties(self.shown.material.is_transversely_isotropic());
                self.shown.params = p;
                if self.shown.fem.take().is_some() {
                    send(Command::Replace(self.replacement()));
                } else {
                    send(Command::SetParams(p));
                }
                self.start_validation();
            }
            Request::SetIntegrator(i, dt) => {
                (self.shown.integrator, self.shown.dt) = (i, dt);
                send(Command::SetIntegrator(i, dt));
            }
            Request::SetDampingRatio(zeta) => {
                self.shown.damping_ratio = zeta;
                send(Command::SetDampingRatio(zeta));
            }
            Request::Reset => {
                self.shown.force_depth.clear();
                send(Command::Reset);
            }
            Request::ApplyCase => self.apply_case(send),
            Request::FreeCube => {
                self.shown.case_active = None;
                self.shown.fem_answer = None;
                send(Command::ApplyCase(bottom_clamp(&self.grid)));
            }
            Request::StartCalibration => self.start_calibration(),
            Request::CancelCalibration => self.calibration.cancel(),
            Request::ApplyCalibration => {
                if let Some(p) = self.shown.result {
                    self.handle(Request::EditParams(p), send);
                }
            }
            Request::Tool(t) => {
                self.shown.tool = t;
                if let Tool::Probe { centre, radius } = t {
                    self.shown.last_probe = Some((centre, radius));
                }
                send(Command::SetTool(t));
            }
            Request::ProbeStarted => self.shown.force_depth.clear(),
            Request::ForceSample(s) => match self.shown.force_depth.last_mut() {
                // The same depth: the tissue settling under a still probe.
                Some(last) if (last[0] - s[0]).abs() <= 0.05 => last[1] = s[1],
                _ => self.shown.force_depth.push(s),
            },
        }
    }

    fn apply_case(&mut self, send: &mut dyn FnMut(Command)) {
        let case =
            LoadCase::clamped(&self.grid, &self.shown.material.name, self.settings.case_axis, self.settings.case_force);
        let material = self.shown.material.clone();
        let grid = self.grid;
        let solve = case.clone();
        let wake = Arc::clone(&self.wake);
        // The FEM answer, solved off the UI thread (a second one while one runs is refused).
        let started = self.fem.start(
            "FEM answer",
            move || wake(),
            move |ctx| {
                let r = FemModel::new(grid, &material)
                    .solve_cases(std::slice::from_ref(&solve))
                    .map(|mut s| s.remove(0).displacements)
                    .map_err(|e| e.to_string());
                ctx.send(r);
            },
        );
        if let Err(e) = started {
            self.shown.note = Some(format!("{e}"));
            return;
        }
        self.shown.case_active = Some(case.clone());
        self.shown.fem_answer = None;
        send(Command::SetTool(Tool::None));
        send(Command::Reset);
        send(Command::ApplyCase(case));
    }

    /// Takes what the background jobs have sent, sending what the physics thread must do
    /// through `send`.
    pub fn poll(&mut self, send: &mut dyn FnMut(Command)) {
        self.poll_compliance(send);
        let shown = &mut self.shown;
        let ended = self.calibration.poll(|msg| match msg {
            Progress::Generation(s) => shown.history.push(s),
            Progress::Done(Ok(r)) => {
                shown.note = Some(format!(
                    "calibration {}: cost {:.4e} m in {:.1} s ({} evaluations){}",
                    if r.cancelled { "cancelled" } else { "done" },
                    r.cost,
                    r.wall_s,
                    r.evaluations,
                    if r.cancelled { "; best so far kept" } else { "" }
                ));
                shown.result = Some(r.params);
            }
            Progress::Done(Err(e)) => shown.note = Some(format!("calibration failed: {e}")),
        });
        if let Some(state) = ended {
            self.shown.calibrating = false;
            if let State::Stopped(why) = state {
                self.shown.note = Some(format!("the calibration stopped unexpectedly ({why}); no result"));
            }
        }
        let shown = &mut self.shown;
        let ended = self.fem.poll(|r| match r {
            Ok(u) => shown.fem_answer = Some(u),
            Err(e) => shown.note = Some(format!("FEM solve failed: {e}")),
        });
        if let Some(State::Stopped(why)) = ended {
            self.shown.note = Some(format!("the FEM solve stopped unexpectedly ({why})"));
        }
        let shown = &mut self.shown;
        let ended = self.validation.poll(|r| shown.validation = Some(r));
        if let Some(State::Stopped(why)) = ended {
            self.shown.validation = Some(Err(format!("stopped unexpectedly ({why})")));
        }
        if self.validation_stale && !self.validation.busy() {
            self.start_validation();
        }
        let shown = &mut self.shown;
        self.fem_probe.poll(|r| match r {
            Ok(v) => shown.fem_probe = Some(v),
            Err(e) => shown.note = Some(format!("FEM probe force failed: {e}")),
        });
    }

    /// Whether a background job runs (the UI then redraws as its messages arrive).
    pub fn busy(&self) -> bool {
        self.fem.busy()
            || self.calibration.busy()
            || self.validation.busy()
            || self.fem_probe.busy()
            || self.compliance.busy()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::physics::{PhysicsThread, Published};
    use crate::sim::shipped::tissue_params;

    fn wait_until(physics: &PhysicsThread, mut ok: impl FnMut(&Published) -> bool) -> Published {
        let mut p = Published::default();
        for _ in 0..3000 {
            physics.latest(&mut p);
            if ok(&p) {
                return p;
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        p
    }

    fn started() -> (ViewerState, PhysicsThread) {
        let (state, first) = ViewerState::new(|| {}).expect("state");
        let physics = PhysicsThread::spawn(first).expect("physics");
        (state, physics)
    }

    #[test]
    fn applying_a_calibration_changes_topology_and_keeps_the_integrator_guard() {
        let (mut state, physics) = started();
        let mut send = |c| physics.send(c).expect("physics runs");
        assert_eq!(state.shown.topology(), crate::sim::shipped::DEFAULT_TOPOLOGY);
        // A result of another lattice (the paper's axis springs), applied as the panel would.
        let axis = tissue_params(&state.shown.material, Topology::Axis).expect("shipped");
        state.shown.result = Some(axis);
        state.handle(Request::ApplyCalibration, &mut send);
        assert_eq!(state.shown.topology(), Topology::Axis, "the topology follows the parameters");
        let p = wait_until(&physics, |p| p.params == Some(axis));
        assert_eq!(p.params.map(|p| p.topology()), Some(Topology::Axis), "the running model agrees");
        // The automatic choice follows the new model's limit.
        let auto = crate::sim::choose_integrator(None, state.shown.dt, p.limit).expect("auto never refuses");
        assert_eq!(p.integrator.map(|(i, _)| i), Some(auto));
        // Symplectic Euler asked for far above its limit: the policy on the physics side refuses.
        let limit = p.limit.tissue;
        assert!(limit > 0.0 && limit.is_finite());
        state.handle(Request::SetIntegrator(Some(Integrator::Symplectic), 3.0 * limit), &mut send);
        // It switches to the automatic choice: symplectic substeps, cheaper than one prefactored step.
        let p = wait_until(&physics, |p| p.note.as_deref().is_some_and(|n| n.contains("stability limit")));
        assert!(p.note.as_deref().is_some_and(|n| n.contains("automatic choice")), "{:?}", p.note);
        assert!(
            p.integrator.is_some_and(|(i, dt)| i == Integrator::Symplectic && dt <= 0.9 * limit),
            "{:?}",
            p.integrator
        );
        // Well below: accepted.
        state.handle(Request::SetIntegrator(Some(Integrator::Symplectic), 0.3 * limit), &mut send);
        let p = wait_until(&physics, |p| p.integrator.is_some_and(|(_, dt)| dt == 0.3 * limit));
        assert_eq!(p.integrator.map(|(i, _)| i), Some(Integrator::Symplectic));
    }

    #[test]
    fn another_resolution_runs_the_model_on_that_grid() {
        let (mut state, physics) = started();
        let mut send = |c| physics.send(c).expect("physics runs");
        let at8 = state.shown.params;
        state.handle(Request::SetResolution(12), &mut send);
        assert_eq!(state.grid().n(), 12);
        let p = wait_until(&physics, |p| p.positions.len() == 12 * 12 * 12);
        assert_eq!(p.positions.len(), 1728, "the physics thread runs the 12^3 model");
        // The shipped hex tissue carried over by its stiffness scale: softer springs on a finer grid.
        assert!(state.shown.params.k1 < at8.k1, "{:?} vs {at8:?}", state.shown.params);
        state.handle(Request::SetResolution(1), &mut send);
        assert_eq!(state.grid().n(), 12, "an impossible grid is refused");
    }

    #[test]
    fn the_gpu_steps_the_model_when_asked() {
        if crate::gpu::ComputeDevice::open().is_err() && std::env::var_os("CI").is_none() {
            return; // CI has software Vulkan
        }
        let (mut state, physics) = started();
        let mut send = |c| physics.send(c).expect("physics runs");
        state.settings.compute = crate::gpu::Compute::Gpu;
        state.handle(Request::SetCompute, &mut send);
        let p = wait_until(&physics, |p| p.note.as_deref().is_some_and(|n| n.contains("GPU")));
        assert!(p.note.as_deref().is_some_and(|n| n.contains("on the GPU")), "{:?}", p.note);
        let t0 = p.time_s;
        let p = wait_until(&physics, |p| p.time_s > t0 + 0.01);
        assert!(p.time_s > t0 + 0.01 && p.message.is_none(), "{:?}", p.message);
    }

    #[test]
    fn object_b_ties_are_imposed_and_a_second_calibration_is_refused() {
        let (mut state, physics) = started();
        let mut send = |c| physics.send(c).expect("physics runs");
        state.settings.object = "B".into();
        state.handle(Request::LoadObject, &mut send);
        assert_eq!(state.shown.material.name, "B");
        let mut edited = state.shown.params;
        edited.k3 = 2.0 * edited.k2;
        state.handle(Request::EditParams(edited), &mut send);
        assert_eq!(state.shown.params.k3, state.shown.params.k2, "k3 = k2 for a transversely isotropic object");
        state.settings.calib_generations = 1000;
        state.handle(Request::StartCalibration, &mut send);
        assert!(state.shown.calibrating);
        state.handle(Request::StartCalibration, &mut send);
        assert!(state.shown.note.as_deref().is_some_and(|n| n.contains("already running")), "{:?}", state.shown.note);
        state.handle(Request::CancelCalibration, &mut send);
        for _ in 0..5000 {
            state.poll(&mut send);
            if !state.shown.calibrating {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        assert!(!state.shown.calibrating, "cancelled within a generation");
    }

    #[test]
    fn the_probe_gets_the_materials_surface_compliance_in_the_background() {
        let (mut state, physics) = started();
        let mut send = |c| physics.send(c).expect("physics runs");
        // Loaded from the cache folder, or computed there (about a minute) the first time; waited
        // for up to 10 minutes on a loaded machine.
        let mut p = Published::default();
        for _ in 0..6000 {
            state.poll(&mut send);
            physics.latest(&mut p);
            if p.surface_probe {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
        assert!(p.surface_probe, "{:?}", state.shown.contact_status);
        assert!(state.shown.contact_status.is_none());
        // Pressed 4 mm into the middle of the top face at once: the cube's slow modes cannot follow
        // at first (a stiffer push), then it settles to the material's static force, about 9.7 N (A).
        let r = 0.015;
        state.handle(Request::Tool(Tool::Probe { centre: [0.05, 0.05, 0.1 + r - 0.004], radius: r }), &mut send);
        let first = wait_until(&physics, |p| p.tool_force[2] > 5.0);
        let p = wait_until(&physics, |p| (9.0..10.5).contains(&p.tool_force[2]));
        assert!((9.0..10.5).contains(&p.tool_force[2]), "{:?} (first {:?})", p.tool_force, first.tool_force);
    }

    #[test]
    fn the_fem_runs_in_place_of_the_lattice_and_back() {
        let (mut state, physics) = started();
        let mut send = |c| physics.send(c).expect("physics runs");
        state.handle(Request::SelectFem(crate::mechanics::fem::dynamics::Formulation::Corotational), &mut send);
        assert_eq!(state.shown.model().name(), "fem-corotational");
        let before = wait_until(&physics, |p| p.params.is_some()).revision;
        let p = wait_until(&physics, |p| p.params.is_none() && p.revision > before);
        assert!(p.params.is_none(), "the FEM has no spring parameters");
        state.handle(Request::SelectTopology(Topology::Hex), &mut send);
        let p = wait_until(&physics, |p| p.params.is_some());
        assert_eq!(p.params.map(|p| p.topology()), Some(Topology::Hex));
    }
}
