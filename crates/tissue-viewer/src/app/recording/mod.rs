//! What the hand does, in simulated time, on the physics thread: the probe's mouse samples become
//! the keys of a path the sphere follows at every step (the same path, point and depth
//! interpolated the same way, as a `simulate` script's `probe_path`), and with `view --record`
//! the whole interaction becomes the actions of a script that replays it, with the force samples
//! the viewer computed ([`crate::study::script::Recorded`]).
//!
//! A recording starts when the simulation does (another model, Reset). A setting a script cannot
//! change halfway (parameters, integrator, damping, the probe's contact, a load case) starts it
//! afresh once the tissue is at rest with nothing held: a script starts from rest.

use glam::DVec3;

use crate::sim::press::ProbeReading;
use crate::sim::{Integrator, Simulation, Tool};
use crate::study::script::{Action, Contact, MAX_ACTION_S, PathKey, PathSample, path_at};

/// A press as the hand makes it: the one press of scripts, the viewer and the library.
pub use crate::sim::press::Press;

/// Force samples per simulated second of a recorded probe path.
pub const SAMPLE_HZ: f64 = 100.0;
/// Keys of one probe path before it continues in the next action (a script's bound is 10,000).
const KEYS_PER_ACTION: usize = 4_000;
/// Ticks of rest, nothing held, before a recording starts afresh after a setting changed.
const REST_TICKS: u32 = 100;
/// Kinetic energy below which the tissue counts as at rest, J.
const REST_ENERGY_J: f64 = 1e-12;

/// The action going on.
#[derive(Debug, Clone)]
enum Current {
    Wait,
    /// A drag target set, its first step not yet taken.
    Drag {
        node: usize,
        to: [f64; 3],
    },
    Probe {
        radius: f64,
        direction: [f64; 3],
        keys: Vec<PathKey>,
        now: ([f64; 3], f64),
        next_sample: f64,
    },
}

/// What was recorded, as the physics thread hands it over.
#[derive(Debug, Clone)]
pub struct Recording {
    /// The actions, the one going on closed now.
    pub actions: Vec<Action>,
    /// The probe's force samples.
    pub force_path: Vec<PathSample>,
    /// The integrator and step that ran.
    pub integrator: Integrator,
    /// Time step, s.
    pub dt: f64,
    /// Damping ratio at the fundamental (none for the axis lattice's nodal damping).
    pub damping_ratio: Option<f64>,
    /// The probe's contact.
    pub contact: Contact,
    /// What the actions do not carry.
    pub note: Option<String>,
}

/// The hand's timeline on the physics thread.
#[derive(Debug, Clone)]
pub struct Timeline {
    recording: bool,
    actions: Vec<Action>,
    samples: Vec<PathSample>,
    current: Current,
    /// Steps of the current action.
    steps: u64,
    /// Ticks at rest while waiting to start afresh (`None`: not waiting).
    waiting: Option<u32>,
    note: Option<String>,
}

impl Timeline {
    /// A timeline that keeps the actions (`recording`) or only drives the probe.
    pub fn new(recording: bool) -> Self {
        // The samples' room taken once: a step that samples the force does not allocate.
        let room = if recording { crate::study::script::MAX_SAMPLES } else { 0 };
        Self {
            recording,
            actions: Vec::new(),
            samples: Vec::with_capacity(room),
            current: Current::Wait,
            steps: 0,
            waiting: None,
            note: None,
        }
    }

    /// The simulation starts again from rest: so does the recording.
    pub fn restart(&mut self) {
        self.actions.clear();
        self.samples.clear();
        self.current = Current::Wait;
        self.steps = 0;
        self.waiting = None;
        self.note = None;
    }

    /// A setting a script cannot change halfway: the recording starts afresh once the tissue is
    /// at rest with nothing held (at once where nothing was done yet: the contact arriving
    /// before the first press).
    pub fn setting_changed(&mut self, sim: &Simulation) {
        let untouched = self.actions.is_empty()
            && matches!(self.current, Current::Wait)
            && sim.tissue.kinetic_energy() < REST_ENERGY_J;
        if sim.tool == Tool::None && (sim.time_s == 0.0 || untouched) {
            self.restart();
        } else {
            // A probe held goes on being held (and read) where it is; nothing is recorded until
            // the tissue is at rest with nothing held.
            self.split(sim.dt);
            self.waiting = Some(0);
            self.note = Some(format!(
                "a setting changed at t = {:.3} s of the viewer's simulation and the tissue has not come to rest \
                 since: nothing after it is recorded yet",
                sim.time_s
            ));
        }
    }

    /// A press (a mouse sample): the sphere glides to it over `glide_s` of simulated time, or
    /// starts there when it is a new press.
    pub fn press(&mut self, p: Press, glide_s: f64, sim: &mut Simulation) {
        let dt = sim.dt;
        let now = self.steps as f64 * dt;
        let glide = (glide_s / dt).round().max(1.0) * dt;
        if let Current::Probe { radius, direction, keys, .. } = &mut self.current
            && *radius == p.radius
            && *direction == p.direction()
        {
            // From where the sphere is now (a glide not finished is cut short).
            let (at, depth) = path_at(keys, now);
            keys.retain(|k| k.t < now - 0.5 * dt);
            keys.push(PathKey { t: now, at, depth });
            keys.push(PathKey { t: now + glide, at: p.at, depth: p.depth });
            if keys.len() >= KEYS_PER_ACTION {
                self.split(dt);
            }
            return;
        }
        self.close(dt);
        let key = PathKey { t: 0.0, at: p.at, depth: p.depth };
        self.current = Current::Probe {
            radius: p.radius,
            direction: p.direction(),
            keys: vec![key],
            now: (p.at, p.depth),
            next_sample: 0.0,
        };
        sim.tool = p.tool();
    }

    /// Another tool (a drag target or nothing held; a probe is [`Timeline::press`]).
    pub fn set_tool(&mut self, tool: Tool, sim: &mut Simulation) {
        let held = sim.tool != Tool::None;
        self.close(sim.dt);
        match tool {
            Tool::Drag { node, target } => self.current = Current::Drag { node, to: target },
            Tool::None if held => self.push(Action::Release { record: false }),
            Tool::None | Tool::Probe { .. } => {}
        }
        sim.tool = tool;
    }

    /// Before a step: the probe where its path is at the step's end.
    pub fn before_step(&mut self, sim: &mut Simulation) {
        if let Current::Probe { radius, direction, keys, now, .. } = &mut self.current {
            let (at, depth) = path_at(keys, (self.steps + 1) as f64 * sim.dt);
            *now = (at, depth);
            let p = Press { at, direction: Some(*direction), radius: *radius, depth };
            sim.tool = p.tool();
        }
    }

    /// The probe of the last step while the sphere is pressed: where the sphere was (the press
    /// of that step) and its reading (its force, its component against the push, the depth and
    /// the contact), one step's both.
    pub fn reading(&self, sim: &Simulation) -> Option<(Press, ProbeReading)> {
        let Current::Probe { radius, direction, now, .. } = &self.current else { return None };
        matches!(sim.tool, Tool::Probe { .. }).then(|| {
            let p = Press { at: now.0, direction: Some(*direction), radius: *radius, depth: now.1 };
            (p, ProbeReading::of(sim, &p))
        })
    }

    /// After a step: counted, and the probe's force sampled when due (as a script samples it).
    pub fn after_step(&mut self, sim: &Simulation) {
        let dt = sim.dt;
        self.steps += 1;
        let t = self.steps as f64 * dt;
        let index = self.actions.len();
        match &mut self.current {
            Current::Drag { node, to } => {
                // The drag's one step taken: the target holds from here, as a script's drag does.
                let drag = Action::Drag { node: *node, to: *to, duration_s: dt, record: false };
                self.push(drag);
                self.current = Current::Wait;
                self.steps = 0;
                return;
            }
            Current::Probe { direction, now, next_sample, .. } if self.recording && self.waiting.is_none() => {
                let tol = 1e-6 * dt * SAMPLE_HZ;
                if t * SAMPLE_HZ >= *next_sample - tol && self.samples.len() < crate::study::script::MAX_SAMPLES {
                    let force = sim.tool_force;
                    let d = DVec3::from(*direction);
                    self.samples.push(PathSample {
                        action: index,
                        t,
                        at: now.0,
                        depth_m: now.1,
                        force_n: -DVec3::from(force).dot(d / d.length()),
                        force,
                        contact: Contact::of(sim),
                    });
                    *next_sample = (t * SAMPLE_HZ + tol).floor() + 1.0;
                }
            }
            _ => {}
        }
        if t + dt > MAX_ACTION_S {
            self.split(dt);
        }
    }

    /// Once a tick: a recording waiting for rest starts when the tissue has been at rest, nothing
    /// held, for 100 ticks.
    pub fn tick(&mut self, sim: &Simulation) {
        if let Some(n) = &mut self.waiting {
            let rest = sim.tool == Tool::None && sim.tissue.kinetic_energy() < REST_ENERGY_J;
            *n = if rest { *n + 1 } else { 0 };
            if *n >= REST_TICKS {
                self.restart();
                self.note = Some(format!(
                    "recorded from t = {:.3} s of the viewer's simulation, at rest after a setting changed",
                    sim.time_s
                ));
            }
        }
    }

    /// What was recorded, the action going on closed now.
    pub fn recording(&self, sim: &Simulation) -> Recording {
        let mut t = self.clone();
        if t.waiting.is_some() {
            t.actions.clear();
            t.samples.clear();
        } else {
            t.close(sim.dt);
        }
        if t.actions.is_empty() {
            t.actions.push(Action::Wait { duration_s: 0.0, record: false });
        }
        Recording {
            actions: t.actions,
            force_path: t.samples,
            integrator: sim.integrator,
            dt: sim.dt,
            damping_ratio: sim.tissue.damping().ratio(),
            contact: if sim.has_surface_probe() { Contact::Surface } else { Contact::Nodes },
            note: t.note,
        }
    }

    fn push(&mut self, a: Action) {
        if self.recording && self.waiting.is_none() && self.actions.len() < crate::study::script::MAX_ACTIONS - 1 {
            self.actions.push(a);
        }
    }

    /// Ends the action going on (as long as its steps), the next one a wait.
    fn close(&mut self, dt: f64) {
        let steps = std::mem::take(&mut self.steps);
        let duration_s = steps as f64 * dt;
        match std::mem::replace(&mut self.current, Current::Wait) {
            Current::Wait if steps > 0 => self.push(Action::Wait { duration_s, record: false }),
            Current::Probe { radius, direction, mut keys, .. } if steps > 0 => {
                let (at, depth) = path_at(&keys, duration_s);
                keys.retain(|k| k.t < duration_s - 0.5 * dt);
                keys.push(PathKey { t: duration_s, at, depth });
                self.push(Action::ProbePath { radius, direction, keys, sample_hz: SAMPLE_HZ, record: false });
            }
            _ => {}
        }
    }

    /// Ends the action going on now and goes on with the same in the next (a long hold or wait).
    fn split(&mut self, dt: f64) {
        let now = self.steps as f64 * dt;
        let next = match &self.current {
            Current::Probe { radius, direction, keys, now: pos, .. } => {
                let (at, depth) = path_at(keys, now);
                let mut rest = vec![PathKey { t: 0.0, at, depth }];
                rest.extend(keys.iter().filter(|k| k.t > now + 0.5 * dt).map(|k| PathKey { t: k.t - now, ..*k }));
                Current::Probe { radius: *radius, direction: *direction, keys: rest, now: *pos, next_sample: 0.0 }
            }
            _ => Current::Wait,
        };
        self.close(dt);
        self.current = next;
    }
}

#[cfg(test)]
mod tests;
