//! `tissue-sim simulate`: a scripted sequence of tool actions run on the interactive simulation
//! with no rendering, for regression tests of interaction. Deterministic: the same script gives
//! the same bytes.
//!
//! ```json
//! { "object": "A", "model": "hex", "dt": 1e-4, "integrator": "symplectic",
//!   "damping_ratio": 0.2, "clamp": "bottom",
//!   "actions": [
//!     { "drag":    { "node": 511, "to": [0.11, 0.1, 0.1], "duration_s": 0.2 } },
//!     { "release": {} },
//!     { "probe":   { "at": [0.05, 0.05, 0.1], "direction": [0, 0, -1], "radius": 0.01,
//!                    "depth": 0.004, "duration_s": 0.2, "samples": 8 } },
//!     { "probe_path": { "radius": 0.015, "direction": [0, 0, -1], "sample_hz": 100,
//!                       "keys": [ { "t": 0.0, "at": [0.03, 0.05, 0.1], "depth": 0.0 },
//!                                 { "t": 0.2, "at": [0.03, 0.05, 0.1], "depth": 0.004 },
//!                                 { "t": 1.2, "at": [0.07, 0.05, 0.1], "depth": 0.004 } ] } },
//!     { "wait":    { "duration_s": 0.5 } } ] }
//! ```
//! `contact` is `surface` (default, the viewer's: the probe's force comes from the material's
//! surface compliance on a 2 mm grid of the top face, [`crate::sim::material_surface`], computed
//! once per material and kept in the cache folder) or `nodes` (the running model's surface nodes
//! are projected out of the sphere). `nodes` is the grid's nodes per axis (default 8, the viewer's; 4 to [`MAX_SCRIPT_NODES`]): a
//! lattice takes its shipped 8^3 tissue carried to that grid
//! ([`crate::sim::shipped::msm_params_at`]), and `drag`'s node ids are on that grid.
//! `compute` is `cpu` (default) or `gpu`: the lattices' and the linear FEM's symplectic Euler
//! step as wgpu compute shaders in f32 ([`crate::gpu`]); without an adapter that computes, or for
//! a model or integrator it has no step for, the run stops with a one-line error.
//! `damping_ratio` is the ratio at the fundamental (mass-proportional, see
//! [`crate::response::damping`]; default 0.2; not for the axis lattice, which keeps the paper's
//! nodal `d`). `clamp` is `bottom` (face z = 0 held, the viewer's default), `none`, or a case id such as
//! `A_clamped_ax1_F10` (its fixed face and loads). A drag moves its target linearly from the
//! node's position to `to` over `duration_s` and holds it there until `release`; a probe starts
//! touching `at` and is pushed along `direction` to `depth` over `duration_s`, recording the
//! force on it at `samples` evenly spaced depths, and stays until `release`. A probe path moves
//! the sphere through its keys (`t` from the action's start, increasing; between keys the point
//! and depth move linearly in time; the sphere touches `at` at depth 0 and moves `depth` along
//! `direction` as `probe` does), recording `{"action", "t", "at", "depth_m", "force_n", "force"}`
//! into `force_path` at `sample_hz` (the first step at or after each sample time), and stays at
//! its last key until `release`.
//!
//! Every action takes an optional `"record": true`: its event then carries all node positions
//! (the last action's event always does). Bounds that no script can exceed, each named in its
//! error: [`MAX_TOTAL_STEPS`] steps in all, [`MAX_ACTIONS`] actions, [`MAX_RECORDED`] recorded
//! events, [`MAX_SAMPLES`] probe samples; the output (compact JSON) is then at most a few MB.
//! Points and sizes are in metres and must lie near the cube (within one side of it). The blow-up
//! guard stops the run with an error after [`crate::sim::MAX_RECOVERIES`] blow-ups in a row, and
//! a symplectic integrator forced above its stability limit is refused before any step.
//!
//! `check`: the whole script checked before any work; `path`: the probe path's samples.

use glam::DVec3;

mod check;
mod outcome;
mod path;
mod recorded;

pub use outcome::{Event, Outcome, ProbeSample};
pub use path::{PathKey, PathSample, path_at};
pub use recorded::{Recorded, Replay};

use check::{check_script, check_steps};
use serde::{Deserialize, Serialize};

use crate::gpu::Compute;
use crate::mechanics::cases::{LoadCase, parse_case_id};
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::sim::{Integrator, Model, Simulation, Tool};

/// A script.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Script {
    /// `A` or `B` (or `material`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub object: Option<crate::mechanics::object::Object>,
    /// A material file (TOML or JSON, as `--material` reads) in place of `object`; a relative path
    /// is taken from the script's folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<std::path::PathBuf>,
    /// `hex` (the default tissue), `shear`, `axis`, `fem-linear` or `fem-corotational`.
    #[serde(default = "default_model")]
    pub model: Model,
    /// Time step, s (default 1e-4).
    #[serde(default = "default_dt")]
    pub dt: f64,
    /// Integrator (default: symplectic when safe for `dt`, implicit otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub integrator: Option<Integrator>,
    /// Damping ratio at the fundamental (default [`crate::response::damping::DEFAULT_DAMPING_RATIO`]);
    /// the paper's axis lattice keeps its nodal `d` and refuses one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping_ratio: Option<f64>,
    /// `bottom`, `none` or a case id (default `bottom`).
    #[serde(default = "default_clamp")]
    pub clamp: String,
    /// Nodes per axis (default 8, the viewer's grid).
    #[serde(default = "default_nodes")]
    pub nodes: usize,
    /// The probe's contact (default `surface`, the viewer's).
    #[serde(default)]
    pub contact: Contact,
    /// Where the steps are computed: `cpu` (default), `cpu-f32` (the lattices' and the linear FEM's symplectic
    /// step with its force in f32) or `gpu` (symplectic Euler of the lattices and the linear FEM
    /// in f32, [`crate::gpu`]).
    #[serde(default)]
    pub compute: Compute,
    /// The actions, in order.
    pub actions: Vec<Action>,
    /// What a recording of the viewer (`view --record`) saw: the replay is compared with it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub recorded: Option<Recorded>,
}

fn default_model() -> Model {
    Model::Lattice(crate::sim::shipped::DEFAULT_TOPOLOGY)
}
fn default_dt() -> f64 {
    1e-4
}
fn default_clamp() -> String {
    "bottom".into()
}
fn default_nodes() -> usize {
    Grid::paper().n()
}

pub use crate::sim::press::Contact;

/// The largest grid a script runs on, nodes per axis.
pub const MAX_SCRIPT_NODES: usize = 32;

/// Total steps of a script, all actions together.
pub const MAX_TOTAL_STEPS: u64 = 10_000_000;
/// Actions of a script.
pub const MAX_ACTIONS: usize = 100_000;
/// Events that carry node positions (`"record": true`, and the last).
pub const MAX_RECORDED: usize = 200;
/// Probe samples, all probe actions together.
pub const MAX_SAMPLES: usize = 100_000;
/// Blow-up messages listed (the guard stops a run long before, unless blow-ups keep recurring
/// after healthy stretches).
pub const MAX_BLOW_UPS: usize = 100;

/// One scripted action.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
#[allow(missing_docs)]
pub enum Action {
    /// Pull a node towards a point.
    Drag {
        node: usize,
        #[serde(deserialize_with = "crate::io::shape::numbers")]
        to: [f64; 3],
        duration_s: f64,
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        record: bool,
    },
    /// Push the spherical probe into the tissue.
    Probe {
        #[serde(deserialize_with = "crate::io::shape::numbers")]
        at: [f64; 3],
        #[serde(deserialize_with = "crate::io::shape::numbers")]
        direction: [f64; 3],
        radius: f64,
        depth: f64,
        duration_s: f64,
        #[serde(default = "default_samples")]
        samples: usize,
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        record: bool,
    },
    /// Move the probe along a path of keys, sampling its force.
    #[serde(rename = "probe_path")]
    ProbePath {
        radius: f64,
        #[serde(deserialize_with = "crate::io::shape::numbers")]
        direction: [f64; 3],
        keys: Vec<PathKey>,
        sample_hz: f64,
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        record: bool,
    },
    /// Let go of whatever tool is held.
    Release {
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        record: bool,
    },
    /// Let time pass.
    Wait {
        duration_s: f64,
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        record: bool,
    },
}

impl Action {
    /// Whether the action asks for node positions in its event.
    pub fn record(&self) -> bool {
        match self {
            Action::Drag { record, .. }
            | Action::Probe { record, .. }
            | Action::ProbePath { record, .. }
            | Action::Release { record }
            | Action::Wait { record, .. } => *record,
        }
    }

    fn duration_s(&self) -> f64 {
        match self {
            Action::Drag { duration_s, .. } | Action::Probe { duration_s, .. } | Action::Wait { duration_s, .. } => {
                *duration_s
            }
            Action::ProbePath { keys, .. } => keys.last().map_or(0.0, |k| k.t),
            Action::Release { .. } => 0.0,
        }
    }
}

fn default_samples() -> usize {
    10
}

/// The script's model of `material` on `grid`, damped as it says, where it computes.
fn tissue(script: &Script, grid: Grid, material: &Material) -> anyhow::Result<Box<dyn crate::sim::Tissue>> {
    if script.damping_ratio.is_some() && !script.model.takes_damping_ratio() {
        anyhow::bail!(
            "script: \"damping_ratio\" is not for the axis lattice: {}",
            crate::response::modal::AXIS_HAS_NO_MODES
        );
    }
    let zeta = script.damping_ratio.unwrap_or(crate::response::damping::DEFAULT_DAMPING_RATIO);
    let tissue = script.model.build_on(grid, material, None, zeta).map_err(|e| anyhow::anyhow!("script: {e:#}"))?;
    script.compute.place(tissue).map_err(|e| anyhow::anyhow!("script: compute \"{}\": {e}", script.compute.name()))
}

impl Script {
    /// The script's material: its object's, or its material file's (a relative path from
    /// `folder`, the script's).
    pub fn material_from(&self, folder: &std::path::Path) -> anyhow::Result<Material> {
        match (&self.object, &self.material) {
            (Some(o), None) => Ok(o.material()),
            (None, Some(file)) => {
                let path = folder.join(file);
                let material = Material::from_file(&path)
                    .map_err(|e| anyhow::anyhow!("script: material {}: {e:#}", path.display()))?;
                Ok(material)
            }
            (Some(_), Some(_)) => anyhow::bail!("script: give \"object\" or \"material\", not both"),
            (None, None) => anyhow::bail!("script: \"object\" (A or B) or \"material\" (a material file) is needed"),
        }
    }
}

/// Runs a script (a material file's relative path taken from the working folder).
pub fn run(script: &Script) -> anyhow::Result<Outcome> {
    run_from(script, std::path::Path::new(""))
}

/// Runs a script read from `folder` (where a relative material path starts).
pub fn run_from(script: &Script, folder: &std::path::Path) -> anyhow::Result<Outcome> {
    let material = script.material_from(folder)?;
    check_script(script, &material.name)?;
    let grid = Grid::new(script.nodes)?;
    // The model takes the inclusions (its elements or springs), and so does the probe's contact.
    let tissue = tissue(script, grid, &material)?;
    let case = clamp_case(&grid, &material.name, &script.clamp)?;
    let mut sim = Simulation::with_tissue(tissue, Integrator::Symplectic, script.dt, case.as_ref());
    // The viewer's step policy: refused before the first step.
    let note = sim.try_set_integrator(script.integrator, script.dt).map_err(|why| {
        anyhow::anyhow!("script: {why}; lower dt, or leave \"integrator\" out (the automatic choice substeps dt)")
    })?;
    let integrator = sim.integrator;
    if script.compute != Compute::Cpu && integrator != Integrator::Symplectic {
        anyhow::bail!(
            "script: compute \"{}\" is for symplectic Euler only, and at dt {} s the step policy chose {}: \
             lower dt, or set \"integrator\": \"symplectic\"",
            script.compute.name(),
            crate::io::num(script.dt),
            integrator.name()
        );
    }
    check_steps(script, sim.dt)?;
    let probes = script.actions.iter().any(|a| matches!(a, Action::Probe { .. } | Action::ProbePath { .. }));
    if script.contact == Contact::Surface && probes {
        let mut report = crate::sim::material_surface::stderr_report();
        let surface = crate::sim::material_surface::MaterialSurface::load_or_compute(
            &material,
            crate::io::cache_dir().as_deref(),
            &mut |e| report.event(e),
        )
        .map_err(|e| anyhow::anyhow!("script: the probe's surface compliance: {e:#}"))?;
        let zeta = sim.tissue.damping().ratio();
        sim.set_surface_probe(Some(crate::sim::material_surface::SurfaceProbe::on(&surface, grid, zeta)));
    }
    let rest = grid.positions();
    let mut out = Outcome {
        object: material.name.clone(),
        model: script.model,
        integrator,
        dt: sim.dt,
        note,
        nodes_per_axis: grid.n(),
        contact: script.contact,
        compute: script.compute,
        steps: 0,
        events: Vec::new(),
        force_depth: Vec::new(),
        force_path: Vec::new(),
        blow_ups: Vec::new(),
        replay: None,
    };
    let last = script.actions.len().saturating_sub(1);
    for (i, action) in script.actions.iter().enumerate() {
        let kind = run_action(i, action, &mut sim, &mut out)?;
        // A state on the GPU comes back at the end of each action (the event's positions), and
        // is checked as a step is.
        record_blow_up(sim.sync(), &mut out)?;
        let x = sim.tissue.x();
        let position = |p: usize| -> [f64; 3] { std::array::from_fn(|c| x[c][p]) };
        let max_displacement_m = rest
            .iter()
            .enumerate()
            .map(|(p, r)| {
                let x = position(p);
                DVec3::from(x).distance(DVec3::from(*r))
            })
            .fold(0.0, f64::max);
        let positions = (action.record() || i == last).then(|| (0..grid.num_nodes()).map(position).collect());
        out.events.push(Event {
            action: i,
            kind: kind.into(),
            time_s: sim.time_s,
            tool_force_n: sim.tool_force,
            max_displacement_m,
            positions,
        });
    }
    out.replay = script.recorded.as_ref().map(|r| recorded::compare(&r.force_path, &out.force_path, sim.dt));
    Ok(out)
}

/// Longest action, s.
pub const MAX_ACTION_S: f64 = 100.0;

/// Steps of an action lasting `d` seconds at `dt` (both checked).
fn steps_for(d: f64, dt: f64) -> u64 {
    (d / dt).round() as u64
}

/// The fixed nodes and loads a script's `clamp` names.
fn clamp_case(grid: &Grid, object: &str, clamp: &str) -> anyhow::Result<Option<LoadCase>> {
    Ok(match clamp {
        "none" => None,
        "bottom" => Some(LoadCase::bottom_clamp(grid, object)),
        id => {
            let case = parse_case_id(grid, id).map_err(|e| anyhow::anyhow!("script: clamp: {e}"))?.1;
            if case.bc != crate::mechanics::cases::Bc::Clamped {
                anyhow::bail!(
                    "script: clamp: {id} is a patch case; its roller supports hold single components, which the \
                     mass-spring model does not represent (use a clamped case)"
                );
            }
            Some(case)
        }
    })
}

/// Runs action `i` (checked by [`check_script`]); returns its kind.
fn run_action(i: usize, action: &Action, sim: &mut Simulation, out: &mut Outcome) -> anyhow::Result<&'static str> {
    let n = steps_for(action.duration_s(), sim.dt);
    match action {
        Action::Drag { node, to, .. } => {
            let from: [f64; 3] = std::array::from_fn(|c| sim.tissue.x()[c][*node]);
            let n = n.max(1);
            for s in 1..=n {
                let f = s as f64 / n as f64;
                sim.tool = Tool::Drag { node: *node, target: std::array::from_fn(|c| from[c] + f * (to[c] - from[c])) };
                step(sim, out)?;
            }
            Ok("drag")
        }
        Action::Probe { at, direction, radius, depth, samples, .. } => {
            probe(i, (*at, *direction, *radius, *depth), n.max(1), *samples as u64, sim, out)?;
            Ok("probe")
        }
        Action::ProbePath { radius, direction, keys, sample_hz, .. } => {
            path::probe_path(i, (*radius, *direction, keys, *sample_hz), n.max(1), sim, out)?;
            Ok("probe_path")
        }
        Action::Release { .. } => {
            sim.tool = Tool::None;
            sim.tool_force = [0.0; 3];
            Ok("release")
        }
        Action::Wait { .. } => {
            for _ in 0..n {
                step(sim, out)?;
            }
            Ok("wait")
        }
    }
}

/// A probe action `i`: `(at, direction, radius, depth)` in metres, over `n` steps, `samples`
/// force samples.
fn probe(
    i: usize,
    (at, direction, radius, depth): ([f64; 3], [f64; 3], f64, f64),
    n: u64,
    samples: u64,
    sim: &mut Simulation,
    out: &mut Outcome,
) -> anyhow::Result<()> {
    let dir = DVec3::from(direction).normalize();
    for s in 1..=n {
        let d = depth * s as f64 / n as f64;
        let centre = crate::sim::press::centre(at, dir, radius, d);
        sim.tool = Tool::Probe { centre, radius };
        step(sim, out)?;
        if s * samples % n < samples {
            let along = -DVec3::from(sim.tool_force).dot(dir);
            out.force_depth.push(ProbeSample { action: i, depth_m: d, force_n: along, contact: Contact::of(sim) });
        }
    }
    Ok(())
}

/// One step; a blow-up is listed, and one the guard gave up on stops the script.
fn step(sim: &mut Simulation, out: &mut Outcome) -> anyhow::Result<()> {
    out.steps += 1;
    record_blow_up(sim.step(), out)
}

/// A blow-up of a step or of a state brought back from the GPU is listed, and one the guard gave
/// up on stops the script.
fn record_blow_up(result: Result<(), crate::sim::BlowUp>, out: &mut Outcome) -> anyhow::Result<()> {
    if let Err(b) = result {
        if b.fatal {
            anyhow::bail!("simulation stopped at t = {:.4} s: {}", b.time_s, b.message);
        }
        if out.blow_ups.len() >= MAX_BLOW_UPS {
            anyhow::bail!(
                "simulation stopped at t = {:.4} s: {MAX_BLOW_UPS} blow-ups in all; the last: {}",
                b.time_s,
                b.message
            );
        }
        out.blow_ups.push(format!("t = {:.4} s: {}", b.time_s, b.message));
    }
    Ok(())
}
