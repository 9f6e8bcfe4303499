//! What a script produced: one event per action, the probe's force samples, the blow-ups.

use serde::Serialize;

use super::{Contact, PathSample};
use crate::gpu::Compute;
use crate::sim::{Integrator, Model};

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
    /// Node positions, metres: only for an action with `"record": true`, and the last.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub positions: Option<Vec<[f64; 3]>>,
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
    /// What produced the force (as [`PathSample::contact`]).
    pub contact: Contact,
}

/// What a script produced.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Outcome {
    /// Object label.
    pub object: String,
    /// Model.
    pub model: Model,
    /// Integrator used.
    pub integrator: Integrator,
    /// Time step used, s: the script's `dt`, or a substep of it that the automatic choice took
    /// (as the viewer's physics does), said in `note`.
    pub dt: f64,
    /// What the step policy said, if anything.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// Nodes per axis.
    pub nodes_per_axis: usize,
    /// The probe's contact.
    pub contact: Contact,
    /// Where the steps were computed.
    pub compute: Compute,
    /// Steps taken.
    pub steps: u64,
    /// One event per action.
    pub events: Vec<Event>,
    /// Probe force against depth.
    pub force_depth: Vec<ProbeSample>,
    /// Probe force along the probe paths.
    pub force_path: Vec<PathSample>,
    /// Blow-ups detected (and recovered from).
    pub blow_ups: Vec<String>,
    /// For a recording (a script with `recorded`): the replay's forces against the recorded ones.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replay: Option<super::Replay>,
}

impl Outcome {
    /// Checks that every number of the outcome is finite (before it is written).
    pub fn check_finite(&self) -> anyhow::Result<()> {
        for e in &self.events {
            let pos = e.positions.iter().flatten().flatten();
            if !(e.tool_force_n.iter().chain(pos).all(|v| v.is_finite()) && e.max_displacement_m.is_finite()) {
                anyhow::bail!("script: action {} ended in a non-finite state", e.action);
            }
        }
        let path = self.force_path.iter().flat_map(|s| s.force.iter().chain([&s.force_n]));
        if self.force_depth.iter().map(|s| &s.force_n).chain(path).any(|v| !v.is_finite()) {
            anyhow::bail!("script: a probe force is not finite");
        }
        Ok(())
    }
}
