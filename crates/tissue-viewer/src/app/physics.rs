//! The physics thread: steps the [`Simulation`] at a fixed time step, kept in step with the wall
//! clock in 1 ms ticks (substeps when `dt` is smaller), and publishes the latest state. The
//! renderer copies it under a briefly held lock; the viewer never steps the physics, and never
//! builds a model: a new tissue is built here, from the recipe the UI sends.

use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::recording::Timeline;
use super::worker::{Context, State, Worker};
use crate::mechanics::cases::LoadCase;
use crate::mechanics::msm::MsmParams;
use crate::sim::{Integrator, Simulation, Tissue, Tool};

/// Wall-clock length of one physics tick.
pub const TICK: Duration = Duration::from_millis(crate::sim::TICK_MS);

/// Builds a tissue model (on the physics thread).
pub type TissueRecipe = Box<dyn FnOnce() -> Result<Box<dyn Tissue>, String> + Send>;

/// A whole new simulation: the model's recipe, the integrator asked for (`None`: automatic),
/// the step and the clamp.
pub struct Replacement {
    /// Builds the model.
    pub recipe: TissueRecipe,
    /// Integrator asked for.
    pub integrator: Option<Integrator>,
    /// Time step, s.
    pub dt: f64,
    /// Fixed nodes and loads.
    pub case: LoadCase,
}

impl std::fmt::Debug for Replacement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Replacement").field("integrator", &self.integrator).field("dt", &self.dt).finish()
    }
}

/// Requests to the physics thread.
#[derive(Debug)]
pub enum Command {
    /// New parameters, applied live.
    SetParams(MsmParams),
    /// Integrator asked for (`None`: automatic) and time step; the simulation's policy decides.
    SetIntegrator(Option<Integrator>, f64),
    /// The damping ratio at the fundamental (the policy then decides again).
    SetDampingRatio(f64),
    /// The active tool: a drag target or nothing (a probe comes as [`Command::Press`]).
    SetTool(Tool),
    /// The probe pressed (a mouse sample): the sphere glides there in simulated time.
    Press(super::recording::Press),
    /// Hand over what was recorded ([`super::recording::Timeline::recording`]).
    TakeRecording(Sender<super::recording::Recording>),
    /// Clamp and load as a case, keeping the state.
    ApplyCase(LoadCase),
    /// Back to rest.
    Reset,
    /// Replace the whole simulation (another object or model).
    Replace(Replacement),
    /// The probe's contact: the material's surface compliance (`Some`, kept across
    /// replacements of the same material) or the model's surface nodes (`None`).
    SetSurfaceProbe(Option<crate::sim::material_surface::MaterialSurface>),
}

/// How fast the physics runs, over the last wall-clock second.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Rates {
    /// Ticks completed per second (target: 1000).
    pub ticks_per_s: f64,
    /// Steps completed per second.
    pub steps_per_s: f64,
    /// Mean compute time of one step, microseconds.
    pub step_us: f64,
    /// Simulated seconds per wall second (1.0 = real time).
    pub realtime: f64,
}

/// What the physics thread publishes: written by `Published::record`, copied by `clone_from`.
#[derive(Debug, Default)]
pub struct Published {
    /// Node positions, metres.
    pub positions: Vec<[f32; 3]>,
    /// Fixed nodes.
    pub fixed: Vec<bool>,
    /// Simulated time, s.
    pub time_s: f64,
    /// Rates over the last second.
    pub rates: Rates,
    /// Force of the tissue on the tool, newtons.
    pub tool_force: [f64; 3],
    /// The last blow-up message, if any.
    pub message: Option<String>,
    /// The last note on a request (an integrator switched by the policy, parameters refused).
    pub note: Option<String>,
    /// Integrator and dt in use.
    pub integrator: Option<(Integrator, f64)>,
    /// The step limit of the running model: its explicit stability limit, s, and whether its
    /// stiffness is constant ([`crate::sim::Simulation::limit`], what the step policy respects).
    pub limit: crate::sim::StepLimit,
    /// How the running model is damped.
    pub damping: Option<crate::response::damping::Damping>,
    /// The running model's parameters.
    pub params: Option<MsmParams>,
    /// Whether anything moves (a tool is active or a node is not at rest): the UI redraws then.
    pub moving: bool,
    /// How many tool commands have been applied (to measure input-to-photon latency).
    pub tool_commands: u64,
    /// Ticks since the thread started.
    pub ticks_total: u64,
    /// Steps since the thread started.
    pub steps_total: u64,
    /// Wall time since the thread started, s.
    pub running_s: f64,
    /// Counts changes of `message` and `note` (the UI redraws when it moves).
    pub revision: u64,
    /// Whether the probe's force comes from the material's surface compliance.
    pub surface_probe: bool,
    /// The probe of the last step while it is pressed: the press of that step (where the sphere
    /// is drawn) and its reading (the force shown beside it, in the panel and on the plot).
    pub probe: Option<(crate::sim::press::Press, crate::sim::press::ProbeReading)>,
    /// That step's contact on the material's surface compliance (surface node, the sphere's
    /// normal there, force; empty without one): the dent the view draws.
    pub contact: Vec<(usize, [f64; 3], f64)>,
}

/// The physics thread died (the channel is closed).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the physics thread has stopped")]
pub struct Stopped;

/// Handle to the running physics thread; stops and joins it on drop.
#[derive(Debug)]
pub struct PhysicsThread {
    tx: Sender<Command>,
    shared: Arc<Mutex<Published>>,
    worker: Worker<()>,
}

impl PhysicsThread {
    /// Starts the thread: it builds the first simulation from `first` and steps it, recording
    /// what the hand does where `recording` ([`super::recording`]).
    pub fn spawn(first: Replacement, recording: bool) -> std::io::Result<Self> {
        let (tx, rx) = channel();
        let mut published = Published::default();
        // The contact's bound, so that publishing it never allocates.
        published.contact.reserve(crate::sim::material_surface::compliance::MAX_CONTACT_NODES);
        let shared = Arc::new(Mutex::new(published));
        let out = Arc::clone(&shared);
        let worker = Worker::spawn(
            "physics",
            || {},
            move |ctx| {
                let sim = match (first.recipe)() {
                    Ok(tissue) => {
                        let mut sim =
                            Simulation::with_tissue(tissue, Integrator::Prefactored, first.dt, Some(&first.case));
                        let note = sim.set_integrator(first.integrator, first.dt);
                        (sim, note)
                    }
                    Err(e) => {
                        if let Ok(mut p) = out.lock() {
                            p.note = Some(format!("cannot build the model: {e}"));
                        }
                        return;
                    }
                };
                // On the physics pool: each step's splits are then this thread's own tasks.
                crate::mechanics::parallel::on_pool(move || run(sim, recording, &rx, &out, ctx));
            },
        )?;
        Ok(Self { tx, shared, worker })
    }

    /// Sends a command; fails once the thread has stopped.
    pub fn send(&self, c: Command) -> Result<(), Stopped> {
        self.tx.send(c).map_err(|_| Stopped)
    }

    /// `None` while the thread runs; why it ended otherwise.
    pub fn poll(&mut self) -> Option<String> {
        match self.worker.poll(|()| {}) {
            State::Running => None,
            State::Finished => Some("the physics thread has ended".into()),
            State::Stopped(why) => Some(format!("the physics thread stopped unexpectedly: {why}")),
        }
    }

    /// Copies the latest published state into `into` (reusing its buffers).
    pub fn latest(&self, into: &mut Published) {
        if let Ok(p) = self.shared.lock() {
            into.clone_from(&p);
        }
    }
}

/// The loop's own bookkeeping.
struct Loop {
    message: Option<String>,
    note: Option<String>,
    tools: u64,
    /// After the guard gives up (a fatal blow-up) stepping pauses until the user acts.
    paused: bool,
    owed: f64,
    /// The material's surface compliance for the probe, when the viewer has one.
    compliance: Option<crate::sim::material_surface::MaterialSurface>,
    /// What the hand does, in simulated time (and, recording, what it did).
    timeline: Timeline,
    /// When the last tool command came.
    last_tool_at: Option<Instant>,
}

/// A state that stays on the GPU between steps is brought back to draw at most this often
/// (about 60 Hz), not every tick.
const DRAW_PERIOD: Duration = Duration::from_millis(16);

/// The longest glide between two mouse samples: after a pause, the next sample is reached within
/// this.
const MAX_GLIDE: Duration = Duration::from_millis(50);

impl Loop {
    /// Brings a state that stays on the GPU back to draw, at most every [`DRAW_PERIOD`] (last at
    /// `drawn_at`); a failed readback pauses the loop.
    fn bring_back_to_draw(&mut self, sim: &mut Simulation, drawn_at: &mut Option<Instant>) {
        if !sim.tissue.state_on_device() || drawn_at.is_some_and(|t| t.elapsed() < DRAW_PERIOD) {
            return;
        }
        if let Err(b) = sim.sync() {
            self.blew_up(&b);
        }
        *drawn_at = Some(Instant::now());
    }

    /// Says what blew up; pauses where the guard gave up.
    fn blew_up(&mut self, b: &crate::sim::BlowUp) {
        self.message = Some(if b.fatal {
            format!("t = {:.3} s: {} Paused: change a setting, use a tool or Reset to go on.", b.time_s, b.message)
        } else {
            format!("t = {:.3} s: {}", b.time_s, b.message)
        });
        self.paused = b.fatal;
        self.owed = 0.0;
    }

    /// The probe of the running simulation on the kept surface compliance, if any.
    fn attach_surface_probe(&self, sim: &mut Simulation) {
        let probe = self.compliance.as_ref().map(|c| {
            crate::sim::material_surface::SurfaceProbe::on(c, sim.tissue.grid(), sim.tissue.damping().ratio())
        });
        sim.set_surface_probe(probe);
    }
}

impl Loop {
    fn apply(&mut self, sim: &mut Simulation, cmd: Command) {
        self.paused = false;
        match cmd {
            Command::SetParams(p) => {
                match sim.set_params(p) {
                    Ok(note) => self.note = note,
                    Err(e) => self.note = Some(format!("parameters refused: {e}")),
                }
                self.timeline.setting_changed(sim);
            }
            Command::SetIntegrator(i, dt) => {
                self.note = sim.set_integrator(i, dt);
                self.timeline.setting_changed(sim);
            }
            Command::SetDampingRatio(zeta) => {
                match sim.set_damping_ratio(zeta) {
                    Ok(note) => self.note = note,
                    Err(e) => self.note = Some(format!("damping ratio refused: {e}")),
                }
                self.timeline.setting_changed(sim);
            }
            Command::SetTool(t) => {
                self.timeline.set_tool(t, sim);
                self.last_tool_at = Some(Instant::now());
                self.tools += 1;
            }
            Command::Press(p) => {
                // The sphere glides to the sample over the time since the last one (in
                // simulated time: it moves at every step, as a script's path does).
                let now = Instant::now();
                let since = self.last_tool_at.map_or(TICK, |t| now - t).clamp(TICK, MAX_GLIDE);
                self.timeline.press(p, since.as_secs_f64(), sim);
                self.last_tool_at = Some(now);
                self.tools += 1;
            }
            Command::TakeRecording(reply) => {
                let _ = reply.send(self.timeline.recording(sim));
            }
            Command::ApplyCase(c) => {
                sim.apply_case(&c);
                self.timeline.setting_changed(sim);
            }
            Command::Reset => {
                sim.reset();
                self.timeline.restart();
                self.message = None;
            }
            Command::Replace(r) => match (r.recipe)() {
                Ok(tissue) => {
                    *sim = Simulation::with_tissue(tissue, Integrator::Symplectic, r.dt, Some(&r.case));
                    self.attach_surface_probe(sim);
                    self.timeline.restart();
                    let note = sim.set_integrator(r.integrator, r.dt);
                    self.note = match (note, sim.tissue.computed_on()) {
                        (Some(n), Some(on)) => Some(format!("{n}; {on}")),
                        (n, on) => n.or(on),
                    };
                    self.message = None;
                    self.owed = 0.0;
                }
                Err(e) => self.note = Some(format!("cannot build the model: {e}")),
            },
            Command::SetSurfaceProbe(c) => {
                self.compliance = c;
                self.attach_surface_probe(sim);
                self.timeline.setting_changed(sim);
            }
        }
    }
}

impl Clone for Published {
    fn clone(&self) -> Self {
        let mut p = Self::default();
        p.clone_from(self);
        p
    }

    /// Copies `p` into `self`, reusing its buffers (the UI's copy each frame allocates nothing).
    fn clone_from(&mut self, p: &Self) {
        let into = self;
        into.positions.clone_from(&p.positions);
        into.fixed.clone_from(&p.fixed);
        into.time_s = p.time_s;
        into.rates = p.rates;
        (into.ticks_total, into.steps_total, into.running_s) = (p.ticks_total, p.steps_total, p.running_s);
        into.tool_force = p.tool_force;
        if into.message != p.message {
            into.message.clone_from(&p.message);
        }
        if into.note != p.note {
            into.note.clone_from(&p.note);
        }
        into.integrator = p.integrator;
        into.limit = p.limit;
        into.damping = p.damping;
        into.params = p.params;
        into.moving = p.moving;
        into.tool_commands = p.tool_commands;
        into.revision = p.revision;
        into.surface_probe = p.surface_probe;
        into.probe = p.probe;
        into.contact.clone_from(&p.contact);
    }
}

impl Published {
    /// Records the running simulation's state (the physics thread's one writer of it).
    fn record(&mut self, sim: &Simulation, rates: Rates, state: &Loop, totals: (u64, u64, f64)) {
        self.probe = state.timeline.reading(sim);
        self.contact.clear();
        if self.probe.is_some() {
            // At most the contact's bound of nodes: within the capacity reserved at the start.
            self.contact
                .extend(sim.surface_contact().take(crate::sim::material_surface::compliance::MAX_CONTACT_NODES));
        }
        let p = self;
        let n = sim.tissue.grid().num_nodes();
        p.positions.resize(n, [0.0; 3]);
        sim.positions_f32(&mut p.positions);
        p.fixed.resize(n, false);
        for (f, free) in p.fixed.iter_mut().zip(sim.tissue.free()) {
            *f = *free == 0.0;
        }
        p.time_s = sim.time_s;
        p.rates = rates;
        p.tool_force = sim.tool_force;
        if p.message != state.message {
            p.message.clone_from(&state.message);
            p.revision += 1;
        }
        if p.note != state.note {
            p.note.clone_from(&state.note);
            p.revision += 1;
        }
        p.integrator = Some((sim.integrator, sim.dt));
        p.limit = sim.limit();
        p.damping = Some(sim.tissue.damping());
        p.params = sim.tissue.params();
        p.moving = !state.paused && (sim.tool != Tool::None || sim.tissue.kinetic_energy() > 1e-12);
        p.tool_commands = state.tools;
        (p.ticks_total, p.steps_total, p.running_s) = totals;
        p.surface_probe = sim.has_surface_probe();
    }
}

fn publish(sim: &Simulation, out: &Mutex<Published>, rates: Rates, state: &Loop, totals: (u64, u64, f64)) {
    if let Ok(mut p) = out.lock() {
        p.record(sim, rates, state, totals);
    }
}

fn run(
    (mut sim, note): (Simulation, Option<String>),
    recording: bool,
    rx: &Receiver<Command>,
    out: &Mutex<Published>,
    ctx: &Context<()>,
) {
    let start = Instant::now();
    let mut next = start;
    let mut state = Loop {
        message: None,
        note,
        tools: 0,
        paused: false,
        owed: 0.0,
        compliance: None,
        timeline: Timeline::new(recording),
        last_tool_at: None,
    };
    let (mut window_start, mut ticks, mut steps, mut busy) = (Instant::now(), 0u64, 0u64, Duration::ZERO);
    let mut rates = Rates::default();
    let (mut ticks_total, mut steps_total) = (0u64, 0u64);
    let mut drawn_at: Option<Instant> = None;
    while !ctx.cancelled() {
        loop {
            match rx.try_recv() {
                Ok(cmd) => state.apply(&mut sim, cmd),
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => return,
            }
        }
        // Simulated time owed to the wall clock; catch up at most 20 ticks' worth, so a slow
        // machine falls behind instead of spiralling.
        state.owed = (state.owed + TICK.as_secs_f64()).min(20.0 * TICK.as_secs_f64());
        let t0 = Instant::now();
        while !state.paused && state.owed >= sim.dt * 0.999 {
            state.timeline.before_step(&mut sim);
            if let Err(b) = sim.step() {
                state.blew_up(&b);
                break;
            }
            state.timeline.after_step(&sim);
            state.owed -= sim.dt;
            steps += 1;
            steps_total += 1;
        }
        if state.paused {
            state.owed = 0.0;
        }
        state.timeline.tick(&sim);
        state.bring_back_to_draw(&mut sim, &mut drawn_at);
        busy += t0.elapsed();
        ticks += 1;
        ticks_total += 1;
        let elapsed = window_start.elapsed();
        if elapsed >= Duration::from_secs(1) {
            let secs = elapsed.as_secs_f64();
            rates = Rates {
                ticks_per_s: ticks as f64 / secs,
                steps_per_s: steps as f64 / secs,
                step_us: if steps > 0 { busy.as_secs_f64() * 1e6 / steps as f64 } else { 0.0 },
                realtime: steps as f64 * sim.dt / secs,
            };
            (window_start, ticks, steps, busy) = (Instant::now(), 0, 0, Duration::ZERO);
        }
        publish(&sim, out, rates, &state, (ticks_total, steps_total, start.elapsed().as_secs_f64()));
        next += TICK;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        } else if now - next > Duration::from_millis(50) {
            next = now; // far behind: resynchronise rather than burst
        }
    }
}
