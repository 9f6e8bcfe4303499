//! The `probe_path` action: the probe moved through keys, its force sampled at a rate.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::{Outcome, step};
use crate::sim::{Simulation, Tool};

/// One key of a probe path.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PathKey {
    /// Time from the action's start, s.
    pub t: f64,
    /// The point the sphere touches at depth 0, metres.
    #[serde(deserialize_with = "crate::io::shape::numbers")]
    pub at: [f64; 3],
    /// Depth along the direction, metres.
    pub depth: f64,
}

/// The point and depth of a probe path at time `t` (held before the first key and after the
/// last; `keys` not empty).
pub fn path_at(keys: &[PathKey], t: f64) -> ([f64; 3], f64) {
    let Some(&first) = keys.first() else { return ([0.0; 3], 0.0) };
    if t <= first.t {
        return (first.at, first.depth);
    }
    for w in keys.windows(2) {
        let (a, b) = (w[0], w[1]);
        if t <= b.t {
            let f = (t - a.t) / (b.t - a.t);
            let at = std::array::from_fn(|c| a.at[c] + f * (b.at[c] - a.at[c]));
            return (at, a.depth + f * (b.depth - a.depth));
        }
    }
    let last = keys[keys.len() - 1];
    (last.at, last.depth)
}

/// One sample of a probe path.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PathSample {
    /// Index of the probe path action.
    pub action: usize,
    /// Time from the action's start, s.
    pub t: f64,
    /// The point the sphere touches at depth 0, metres.
    #[serde(deserialize_with = "crate::io::shape::numbers")]
    pub at: [f64; 3],
    /// Depth along the direction, metres.
    pub depth_m: f64,
    /// Force of the tissue on the probe along `-direction`, newtons.
    pub force_n: f64,
    /// Force of the tissue on the probe, newtons.
    #[serde(deserialize_with = "crate::io::shape::numbers")]
    pub force: [f64; 3],
    /// What produced the force: the material's surface compliance (`surface`), or the model's
    /// surface nodes (`nodes`: asked for, or off the top face).
    pub contact: super::Contact,
}

/// A probe path action `i`: `(radius, direction, keys, sample_hz)` over `n` steps.
pub(super) fn probe_path(
    i: usize,
    (radius, direction, keys, sample_hz): (f64, [f64; 3], &[PathKey], f64),
    n: u64,
    sim: &mut Simulation,
    out: &mut Outcome,
) -> anyhow::Result<()> {
    let len = DVec3::from(direction).length();
    let dir = DVec3::from(direction) / len;
    let total = keys.last().map_or(0.0, |k| k.t);
    // Sample k is due at t = k / sample_hz; counted in units of samples, with a tolerance of a
    // millionth of a step, so that rounding never takes one twice or skips one.
    let mut next_sample = 0.0f64;
    let tol = 1e-6 * sim.dt * sample_hz;
    let mut sampled = 0u64;
    for s in 1..=n {
        let t = total * s as f64 / n as f64;
        let (at, depth) = path_at(keys, t);
        let centre = crate::sim::press::centre(at, dir, radius, depth);
        sim.tool = Tool::Probe { centre, radius };
        step(sim, out)?;
        if t * sample_hz >= next_sample - tol || s == n && sampled == 0 {
            let force = sim.tool_force;
            let force_n = -DVec3::from(force).dot(dir);
            let contact = super::Contact::of(sim);
            out.force_path.push(PathSample { action: i, t, at, depth_m: depth, force_n, force, contact });
            sampled += 1;
            next_sample = (t * sample_hz + tol).floor() + 1.0;
        }
    }
    Ok(())
}
