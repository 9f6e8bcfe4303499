//! The viewer's state without a window: what the panel shows and edits, and the one place that
//! turns the user's intent ([`Request`]s from the panel sections and the mouse tools) into
//! physics [`Command`]s and background jobs. Unit-tested without a window or a GPU.
//!
//! Rules live elsewhere and are only asked here: the transversely isotropic ties in
//! [`MsmParams::with_ties`], the integrator policy in [`crate::sim::choose_integrator`] (applied
//! on the physics thread, which publishes the integrator it runs and the explicit limit), the
//! topology in [`MsmParams::topology`]. No model is built on this side: the physics thread builds
//! it from a recipe.
//!
//! `jobs`: the background jobs a request starts; `model`: another object, material file or
//! resolution; `record`: the recording as a script; `exercise`: find the lump.

mod exercise;
mod jobs;
mod model;
mod record;

use std::sync::Arc;

use super::calibration_job::Progress;
use super::physics::{Command, Replacement};
pub use super::settings::{Applied, ProbeComparison, Shown, ToolKind, ViewSettings};
use super::worker::{Slot, State};
use crate::mechanics::cases::LoadCase;
use crate::mechanics::fem::FemModel;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::msm::{MsmParams, Topology};
use crate::sim::material_surface::compliance::SurfaceCompliance;
use crate::sim::{Integrator, Model, Tool};
use crate::study::palpate::PalpationMap;

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
    /// Compare the probe's last press with the material's force and the running model's own
    /// (in the background).
    ComparePress,
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
    /// A tool command: a drag target or nothing held.
    Tool(Tool),
    /// The probe pressed (a mouse sample).
    Press(crate::app::recording::Press),
    /// Write the recording now (`view --record`).
    SaveRecording,
    /// A new probe press: the force-depth plot starts afresh.
    ProbeStarted,
    /// A probe force sample (depth mm, force N) for the force-depth plot.
    ForceSample([f64; 2]),
    /// Find the lump: hide a new one ([`ViewSettings::inclusion_ranges`], [`ViewSettings::inclusion_seed`]).
    HideLump,
    /// Mark the hidden lump where the probe last pressed, and reveal it.
    MarkLump,
    /// End the exercise: the lump goes.
    EndExercise,
    /// The palpation map of the top face, computed in the background.
    MapFace,
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
    validation: Slot<jobs::Scored>,
    /// The model changed while a validation ran: score it again when that one ends.
    validation_stale: bool,
    comparison: Slot<Result<ProbeComparison, String>>,
    compliance: Slot<jobs::ComplianceMessage>,
    /// The material changed while a surface compliance was computed: its result is dropped and
    /// the new material's started when it ends.
    compliance_stale: bool,
    /// When the surface compliance job started what it computes now and the fraction it first
    /// reported (a resumed computation starts past 0): its estimate of the time left is the rate
    /// since.
    compliance_since: (std::time::Instant, Option<f64>),
    /// What the surface compliance job computes now.
    compliance_stage: String,
    /// The felt material's surface compliance and its background's, once loaded.
    compliances: Option<[Arc<SurfaceCompliance>; 2]>,
    /// A press that waits for the material's contact (`view --press` while recording, so that
    /// the recording holds it, on one contact from its start).
    pub deferred_press: Option<crate::sim::press::Press>,
    map: Slot<(u64, Result<PalpationMap, String>)>,
    /// Counts the materials and grids a map may be of: a map of an earlier one is dropped.
    map_generation: u64,
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
                material_contact_in: None,
                material,
                material_file: None,
                params,
                integrator: None,
                dt,
                damping_ratio: crate::response::damping::DEFAULT_DAMPING_RATIO,
                case_active: None,
                fem_answer: None,
                history: Vec::new(),
                result: None,
                calibration: None,
                applied: None,
                calibrating: false,
                calib_generations: 0,
                calib_cases: crate::calibrate::CaseSet::Touch,
                note: None,
                force_depth: Vec::new(),
                fem: None,
                validation: None,
                inclusion_validation: None,
                tool: Tool::None,
                last_probe: None,
                last_reading: None,
                comparison: None,
                comparing: false,
                inclusions: Vec::new(),
                exercise: None,
                face_map: None,
            },
            grid,
            fem: Slot::default(),
            calibration: Slot::default(),
            validation: Slot::default(),
            validation_stale: false,
            comparison: Slot::default(),
            compliance: Slot::default(),
            compliance_stale: false,
            compliance_since: (std::time::Instant::now(), None),
            compliance_stage: String::new(),
            compliances: None,
            deferred_press: None,
            map: Slot::default(),
            map_generation: 0,
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
                self.shown.modelled_material(),
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
            Request::ComparePress => self.start_comparison(),
            Request::SetResolution(n) => self.set_resolution(n, send),
            Request::SetCompute => send(Command::Replace(self.replacement())),
            Request::EditParams(p) => {
                self.shown.applied = None;
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
            Request::ApplyCalibration => self.apply_calibration(send),
            Request::Tool(t) => {
                self.shown.tool = t;
                send(Command::SetTool(t));
            }
            Request::Press(p) => {
                self.shown.tool = p.tool();
                self.shown.last_probe = Some((p.centre(), p.radius));
                send(Command::Press(p));
            }
            // The viewer writes it: the physics thread hands the recording over.
            Request::SaveRecording => {}
            Request::ProbeStarted => self.shown.force_depth.clear(),
            Request::ForceSample(s) => match self.shown.force_depth.last_mut() {
                // The same depth: the tissue settling under a still probe.
                Some(last) if (last[0] - s[0]).abs() <= 0.05 => last[1] = s[1],
                _ => self.shown.force_depth.push(s),
            },
            Request::HideLump => self.hide_inclusion(),
            Request::MarkLump => self.mark_inclusion(),
            Request::EndExercise => {
                if self.shown.exercise.take().is_some() {
                    self.start_compliance();
                }
            }
            Request::MapFace => self.start_map(),
        }
    }

    fn apply_case(&mut self, send: &mut dyn FnMut(Command)) {
        let case =
            LoadCase::clamped(&self.grid, &self.shown.material.name, self.settings.case_axis, self.settings.case_force);
        let material = self.shown.modelled_material();
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
        self.poll_map();
        let shown = &mut self.shown;
        let ended = self.calibration.poll(|msg| match msg {
            Progress::Generation(s) => shown.history.push(s),
            Progress::Done(Ok(r)) => {
                let (unit, _) = crate::calibrate::cost_meaning(r.cases, r.cost_mode);
                shown.note = Some(format!(
                    "calibration {}: cost {:.4e}{}{unit} in {:.1} s ({} evaluations){}",
                    if r.cancelled { "cancelled" } else { "done" },
                    r.cost,
                    if unit.is_empty() { "" } else { " " },
                    r.wall_s,
                    r.evaluations,
                    if r.cancelled { "; best so far kept" } else { "" }
                ));
                shown.result = Some(r.params);
                shown.calibration = Some(r);
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
        let ended = self.validation.poll(|r| match r {
            jobs::Scored::Touch(r) => shown.validation = Some(r),
            jobs::Scored::Inclusions(r) => shown.inclusion_validation = Some(r),
        });
        if let Some(State::Stopped(why)) = ended {
            self.shown.validation = Some(Err(format!("stopped unexpectedly ({why})")));
            self.shown.inclusion_validation = Some(Err(format!("stopped unexpectedly ({why})")));
        }
        if self.validation_stale && !self.validation.busy() {
            self.start_validation();
        }
        let shown = &mut self.shown;
        self.comparison.poll(|r| match r {
            Ok(v) => shown.comparison = Some(v),
            Err(e) => shown.note = Some(format!("the comparison of the press failed: {e}")),
        });
        self.shown.comparing = self.comparison.busy();
    }

    /// Runs the calibration's result, keeping what ran before to show what changed.
    fn apply_calibration(&mut self, send: &mut dyn FnMut(Command)) {
        if let Some(p) = self.shown.result {
            let from = self.shown.params;
            let before = self.shown.validation.as_ref().and_then(|v| v.as_ref().ok()).copied();
            self.handle(Request::EditParams(p), send);
            self.shown.applied = Some(Applied { from, before, to: self.shown.params });
        }
    }

    /// The felt material's surface compliance, once loaded (the probe's contact is on it).
    pub fn felt_compliance(&self) -> Option<&Arc<SurfaceCompliance>> {
        self.compliances.as_ref().map(|[felt, _]| felt)
    }

    /// The physics thread's probe of its last published step: a sample of the force-depth plot
    /// (from the first contact on, the depth and the force of that one step) and, while pressed,
    /// the press a comparison is of.
    pub fn observe_probe(&mut self, probe: Option<(crate::sim::press::Press, crate::sim::press::ProbeReading)>) {
        let Some((press, reading)) = probe else { return };
        if reading.depth_m > 0.0 {
            self.shown.last_reading = Some((press, reading));
        }
        if self.shown.force_depth.is_empty() && reading.depth_m > 0.0 {
            // The first contact: the sphere touching the surface at rest, no force yet (the first
            // reading a frame sees may be deeper: the sphere glides between the hand's samples).
            self.shown.force_depth.push([0.0, 0.0]);
        }
        if !self.shown.force_depth.is_empty() {
            self.handle(Request::ForceSample([reading.depth_m * 1e3, reading.force_n]), &mut |_| {});
        }
    }

    /// Whether a background job runs (the UI then redraws as its messages arrive).
    pub fn busy(&self) -> bool {
        self.fem.busy()
            || self.calibration.busy()
            || self.validation.busy()
            || self.comparison.busy()
            || self.compliance.busy()
    }
}

#[cfg(test)]
mod tests;
