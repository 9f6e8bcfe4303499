//! `tissue-sim simulate`: a scripted sequence of tool actions run on the interactive simulation
//! with no rendering, for regression tests of interaction. Deterministic: the same script gives
//! the same bytes.
//!
//! ```json
//! { "object": "A", "model": "shear", "dt": 1e-4, "integrator": "symplectic",
//!   "clamp": "bottom",
//!   "actions": [
//!     { "drag":    { "node": 511, "to": [0.11, 0.1, 0.1], "duration_s": 0.2 } },
//!     { "release": {} },
//!     { "probe":   { "at": [0.05, 0.05, 0.1], "direction": [0, 0, -1], "radius": 0.01,
//!                    "depth": 0.004, "duration_s": 0.2, "samples": 8 } },
//!     { "wait":    { "duration_s": 0.5 } } ] }
//! ```
//! `clamp` is `bottom` (face z = 0 held, the viewer's default), `none`, or a case id such as
//! `A_clamped_ax1_F10` (its fixed face and loads). A drag moves its target linearly from the
//! node's position to `to` over `duration_s` and holds it there until `release`; a probe starts
//! touching `at` and is pushed along `direction` to `depth` over `duration_s`, recording the
//! force on it at `samples` evenly spaced depths, and stays until `release`.

use serde::{Deserialize, Serialize};

use crate::cases::{LoadCase, parse_case_id};
use crate::grid::Grid;
use crate::material::Material;
use crate::msm::{MsmModel, Topology};
use crate::scene::tissue_params;
use crate::sim::{Integrator, Simulation, Tool};

/// A script.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Script {
    /// `A` or `B`.
    pub object: String,
    /// `shear` (default) or `axis`.
    #[serde(default = "default_model")]
    pub model: Topology,
    /// Time step, s (default 1e-4).
    #[serde(default = "default_dt")]
    pub dt: f64,
    /// Integrator (default: symplectic when safe for `dt`, implicit otherwise).
    pub integrator: Option<Integrator>,
    /// `bottom`, `none` or a case id (default `bottom`).
    #[serde(default = "default_clamp")]
    pub clamp: String,
    /// The actions, in order.
    pub actions: Vec<Action>,
}

fn default_model() -> Topology {
    Topology::Shear
}
fn default_dt() -> f64 {
    1e-4
}
fn default_clamp() -> String {
    "bottom".into()
}

/// One scripted action.
#[derive(Debug, Clone, Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
#[allow(missing_docs)]
pub enum Action {
    /// Pull a node towards a point.
    Drag { node: usize, to: [f64; 3], duration_s: f64 },
    /// Push the spherical probe into the tissue.
    Probe {
        at: [f64; 3],
        direction: [f64; 3],
        radius: f64,
        depth: f64,
        duration_s: f64,
        #[serde(default = "default_samples")]
        samples: usize,
    },
    /// Let go of whatever tool is held.
    Release {},
    /// Let time pass.
    Wait { duration_s: f64 },
}

fn default_samples() -> usize {
    10
}

/// The state at the end of an action.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Event {
    /// Index of the action.
    pub action: usize,
    /// `drag`, `probe`, `release` or `wait`.
    pub kind: String,
    /// Simulated time, s.
    pub time_s: f64,
    /// Force of the tissue on the tool, newtons.
    pub tool_force_n: [f64; 3],
    /// Largest distance of a node from its rest position, metres.
    pub max_displacement_m: f64,
    /// Node positions, metres.
    pub positions: Vec<[f64; 3]>,
}

/// One probe sample.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProbeSample {
    /// Index of the probe action.
    pub action: usize,
    /// Indentation depth, metres.
    pub depth_m: f64,
    /// Force of the tissue on the probe along `-direction`, newtons.
    pub force_n: f64,
}

/// What a script produced.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Outcome {
    /// Object label.
    pub object: String,
    /// Model.
    pub model: Topology,
    /// Integrator used.
    pub integrator: Integrator,
    /// Time step, s.
    pub dt: f64,
    /// Nodes per axis.
    pub nodes_per_axis: usize,
    /// Steps taken.
    pub steps: u64,
    /// One event per action.
    pub events: Vec<Event>,
    /// Probe force against depth.
    pub force_depth: Vec<ProbeSample>,
    /// Blow-ups detected (and recovered from).
    pub blow_ups: Vec<String>,
}

fn check(name: &str, v: f64, positive: bool) -> anyhow::Result<()> {
    if !v.is_finite() || v < 0.0 || (positive && v == 0.0) {
        anyhow::bail!(
            "script: {name} must be a {} finite number, got {v}",
            if positive { "positive" } else { "non-negative" }
        );
    }
    Ok(())
}

/// Runs a script.
pub fn run(script: &Script) -> anyhow::Result<Outcome> {
    let grid = Grid::paper();
    let material = Material::preset(&script.object)
        .ok_or_else(|| anyhow::anyhow!("script: object must be A or B, got {:?}", script.object))?;
    check("dt", script.dt, true)?;
    if !(1e-6..=0.05).contains(&script.dt) {
        anyhow::bail!("script: dt = {} s is out of range (1e-6 to 0.05 s)", script.dt);
    }
    let params = tissue_params(&material, script.model)?;
    let model = MsmModel::new(grid, params, material.density)?;
    let integrator = script.integrator.unwrap_or_else(|| Simulation::default_integrator(&model, script.dt));
    let case: Option<LoadCase> = match script.clamp.as_str() {
        "none" => None,
        "bottom" => {
            let mut c = LoadCase::clamped(&grid, &material.name, 3, 0.0);
            c.load.fill(0.0);
            Some(c)
        }
        id => {
            let case = parse_case_id(&grid, id).map_err(|e| anyhow::anyhow!("script: clamp: {e}"))?.1;
            if case.bc != crate::cases::Bc::Clamped {
                anyhow::bail!(
                    "script: clamp: {id} is a patch case; its roller supports hold single components, which the mass-spring model does not represent (use a clamped case)"
                );
            }
            Some(case)
        }
    };
    let mut sim = Simulation::new(model, integrator, script.dt, case.as_ref());
    let rest = grid.positions();
    let mut out = Outcome {
        object: material.name.clone(),
        model: script.model,
        integrator,
        dt: script.dt,
        nodes_per_axis: grid.n(),
        steps: 0,
        events: Vec::new(),
        force_depth: Vec::new(),
        blow_ups: Vec::new(),
    };
    let steps_for = |d: f64| -> anyhow::Result<u64> {
        check("duration_s", d, false)?;
        if d > 100.0 {
            anyhow::bail!("script: duration_s = {d} s is too long (at most 100 s)");
        }
        let steps = (d / script.dt).round();
        if steps > 1e7 {
            anyhow::bail!("script: duration_s = {d} s at dt = {} s is more than 1e7 steps", script.dt);
        }
        Ok(steps as u64)
    };
    for (i, action) in script.actions.iter().enumerate() {
        let kind;
        match action {
            Action::Drag { node, to, duration_s } => {
                kind = "drag";
                if *node >= grid.num_nodes() {
                    anyhow::bail!("script: action {i}: node {node} does not exist (0..{})", grid.num_nodes());
                }
                for (c, v) in to.iter().enumerate() {
                    if !v.is_finite() {
                        anyhow::bail!("script: action {i}: to[{c}] is not finite");
                    }
                }
                let from: [f64; 3] = std::array::from_fn(|c| sim.dynamics.x[c][*node]);
                let n = steps_for(*duration_s)?.max(1);
                for s in 1..=n {
                    let f = s as f64 / n as f64;
                    sim.tool =
                        Tool::Drag { node: *node, target: std::array::from_fn(|c| from[c] + f * (to[c] - from[c])) };
                    step(&mut sim, &mut out);
                }
            }
            Action::Probe { at, direction, radius, depth, duration_s, samples } => {
                kind = "probe";
                check("radius", *radius, true)?;
                check("depth", *depth, false)?;
                let len = direction.iter().map(|d| d * d).sum::<f64>().sqrt();
                if !(len.is_finite() && len > 0.0) || at.iter().any(|v| !v.is_finite()) {
                    anyhow::bail!("script: action {i}: probe needs a finite point and a non-zero direction");
                }
                let dir = direction.map(|d| d / len);
                let n = steps_for(*duration_s)?.max(1);
                let samples = (*samples).clamp(1, 10_000) as u64;
                for s in 1..=n {
                    let d = depth * s as f64 / n as f64;
                    let centre = std::array::from_fn(|c| at[c] - radius * dir[c] + d * dir[c]);
                    sim.tool = Tool::Probe { centre, radius: *radius };
                    step(&mut sim, &mut out);
                    if s * samples % n < samples {
                        let f = sim.tool_force;
                        let along = -(f[0] * dir[0] + f[1] * dir[1] + f[2] * dir[2]);
                        out.force_depth.push(ProbeSample { action: i, depth_m: d, force_n: along });
                    }
                }
            }
            Action::Release {} => {
                kind = "release";
                sim.tool = Tool::None;
                sim.tool_force = [0.0; 3];
            }
            Action::Wait { duration_s } => {
                kind = "wait";
                for _ in 0..steps_for(*duration_s)? {
                    step(&mut sim, &mut out);
                }
            }
        }
        let positions: Vec<[f64; 3]> =
            (0..grid.num_nodes()).map(|p| std::array::from_fn(|c| sim.dynamics.x[c][p])).collect();
        let max_displacement_m = positions
            .iter()
            .zip(&rest)
            .map(|(x, r)| ((x[0] - r[0]).powi(2) + (x[1] - r[1]).powi(2) + (x[2] - r[2]).powi(2)).sqrt())
            .fold(0.0, f64::max);
        out.events.push(Event {
            action: i,
            kind: kind.into(),
            time_s: sim.time_s,
            tool_force_n: sim.tool_force,
            max_displacement_m,
            positions,
        });
    }
    Ok(out)
}

fn step(sim: &mut Simulation, out: &mut Outcome) {
    if let Err(b) = sim.step() {
        out.blow_ups.push(format!("t = {:.4} s: {}", b.time_s, b.message));
    }
    out.steps += 1;
}
