//! The physics thread: steps the [`Simulation`] at a fixed time step, kept in step with the wall
//! clock in 1 ms ticks (substeps when `dt` is smaller), and publishes the latest state. The
//! renderer copies it under a briefly held lock; the viewer never steps the physics.

use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::cases::LoadCase;
use crate::msm::MsmParams;
use crate::sim::{Integrator, Simulation, Tool};

/// Wall-clock length of one physics tick.
pub const TICK: Duration = Duration::from_millis(1);

/// Requests to the physics thread.
#[derive(Debug)]
pub enum Command {
    /// New parameters, applied live.
    SetParams(MsmParams),
    /// Integrator and time step.
    SetIntegrator(Integrator, f64),
    /// The active tool.
    SetTool(Tool),
    /// Clamp and load as a benchmark case (or free and unloaded with `None`).
    ApplyCase(Option<LoadCase>),
    /// Back to rest.
    Reset,
    /// Replace the whole simulation (another object or model).
    Replace(Box<Simulation>),
}

/// What the physics thread publishes.
#[derive(Debug, Clone, Default)]
pub struct Published {
    /// Node positions, metres.
    pub positions: Vec<[f32; 3]>,
    /// Fixed nodes.
    pub fixed: Vec<bool>,
    /// Simulated time, s.
    pub time_s: f64,
    /// Ticks completed in the last wall-clock second (target: 1000).
    pub ticks_per_s: f64,
    /// Steps completed in the last wall-clock second.
    pub steps_per_s: f64,
    /// Mean compute time of one step, microseconds.
    pub step_us: f64,
    /// Simulated seconds per wall second over the last second (1.0 = real time).
    pub realtime: f64,
    /// Force of the tissue on the tool, newtons.
    pub tool_force: [f64; 3],
    /// The last blow-up message, if any.
    pub message: Option<String>,
    /// Integrator and dt in use.
    pub integrator: Option<(Integrator, f64)>,
    /// How many tool commands have been applied (to measure input-to-photon latency).
    pub tool_commands: u64,
    /// Ticks since the thread started.
    pub ticks_total: u64,
    /// Steps since the thread started.
    pub steps_total: u64,
    /// Wall time since the thread started, s.
    pub running_s: f64,
}

/// Handle to the running physics thread; stops and joins it on drop.
#[derive(Debug)]
pub struct PhysicsThread {
    tx: Sender<Option<Command>>,
    shared: Arc<Mutex<Published>>,
    handle: Option<JoinHandle<()>>,
}

impl PhysicsThread {
    /// Starts stepping `sim`.
    pub fn spawn(sim: Simulation) -> std::io::Result<Self> {
        let (tx, rx) = channel();
        let shared = Arc::new(Mutex::new(Published::default()));
        let out = Arc::clone(&shared);
        let handle = std::thread::Builder::new().name("physics".into()).spawn(move || run(sim, &rx, &out))?;
        Ok(Self { tx, shared, handle: Some(handle) })
    }

    /// Sends a command (ignored if the thread has stopped).
    pub fn send(&self, c: Command) {
        let _ = self.tx.send(Some(c));
    }

    /// Copies the latest published state into `into` (reusing its buffers).
    pub fn latest(&self, into: &mut Published) {
        if let Ok(p) = self.shared.lock() {
            into.positions.clone_from(&p.positions);
            into.fixed.clone_from(&p.fixed);
            into.time_s = p.time_s;
            into.ticks_per_s = p.ticks_per_s;
            into.steps_per_s = p.steps_per_s;
            into.step_us = p.step_us;
            into.realtime = p.realtime;
            (into.ticks_total, into.steps_total, into.running_s) = (p.ticks_total, p.steps_total, p.running_s);
            into.tool_force = p.tool_force;
            into.message.clone_from(&p.message);
            into.integrator = p.integrator;
            into.tool_commands = p.tool_commands;
        }
    }
}

impl Drop for PhysicsThread {
    fn drop(&mut self) {
        let _ = self.tx.send(None);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

fn publish(
    sim: &Simulation,
    out: &Mutex<Published>,
    stats: (f64, f64, f64, f64),
    message: &Option<String>,
    tools: u64,
) {
    if let Ok(mut p) = out.lock() {
        let n = sim.model.grid.num_nodes();
        p.positions.resize(n, [0.0; 3]);
        sim.positions_f32(&mut p.positions);
        p.fixed.resize(n, false);
        for (f, free) in p.fixed.iter_mut().zip(&sim.dynamics.free) {
            *f = *free == 0.0;
        }
        p.time_s = sim.time_s;
        (p.ticks_per_s, p.steps_per_s, p.step_us, p.realtime) = stats;
        p.tool_force = sim.tool_force;
        if p.message != *message {
            p.message.clone_from(message);
        }
        p.integrator = Some((sim.integrator, sim.dt));
        p.tool_commands = tools;
    }
}

fn run(mut sim: Simulation, rx: &Receiver<Option<Command>>, out: &Mutex<Published>) {
    let start = Instant::now();
    let mut next = start;
    let mut message: Option<String> = None;
    let (mut window_start, mut ticks, mut steps, mut busy) = (Instant::now(), 0u64, 0u64, Duration::ZERO);
    let mut sim_at_window = sim.time_s;
    let mut stats = (0.0, 0.0, 0.0, 0.0);
    // Simulated time owed to the wall clock.
    let mut owed = 0.0f64;
    let mut tools = 0u64;
    // After the guard gives up (a fatal blow-up) stepping pauses until the user acts.
    let mut paused = false;
    let (mut ticks_total, mut steps_total) = (0u64, 0u64);
    loop {
        while let Ok(cmd) = rx.try_recv() {
            let Some(cmd) = cmd else { return };
            paused = false;
            match cmd {
                Command::SetParams(p) => {
                    if let Err(e) = sim.set_params(p) {
                        message = Some(format!("parameters refused: {e}"));
                    }
                }
                Command::SetIntegrator(i, dt) => {
                    sim.integrator = i;
                    sim.dt = dt;
                }
                Command::SetTool(t) => {
                    sim.tool = t;
                    tools += 1;
                }
                Command::ApplyCase(Some(c)) => sim.apply_case(&c),
                Command::ApplyCase(None) => {
                    let free = LoadCase {
                        id: "free".into(),
                        bc: crate::cases::Bc::Clamped,
                        axis: 1,
                        force_n: 0.0,
                        fixed: vec![false; 3 * sim.model.grid.num_nodes()],
                        load: vec![0.0; 3 * sim.model.grid.num_nodes()],
                    };
                    sim.apply_case(&free);
                }
                Command::Reset => {
                    sim.reset();
                    message = None;
                }
                Command::Replace(s) => {
                    sim = *s;
                    message = None;
                    owed = 0.0;
                }
            }
        }
        owed += TICK.as_secs_f64();
        let t0 = Instant::now();
        // Catch up at most 20 ticks' worth, so a slow machine falls behind instead of spiralling.
        owed = owed.min(20.0 * TICK.as_secs_f64());
        while !paused && owed >= sim.dt * 0.999 {
            if let Err(b) = sim.step() {
                message = Some(if b.fatal {
                    format!("t = {:.3} s: {} Paused: change a setting, use a tool or Reset to go on.", b.time_s, b.message)
                } else {
                    format!("t = {:.3} s: {}", b.time_s, b.message)
                });
                paused = b.fatal;
                owed = 0.0;
                break;
            }
            owed -= sim.dt;
            steps += 1;
            steps_total += 1;
        }
        if paused {
            owed = 0.0;
        }
        busy += t0.elapsed();
        ticks += 1;
        ticks_total += 1;
        let elapsed = window_start.elapsed();
        if elapsed >= Duration::from_secs(1) {
            let secs = elapsed.as_secs_f64();
            stats = (
                ticks as f64 / secs,
                steps as f64 / secs,
                if steps > 0 { busy.as_secs_f64() * 1e6 / steps as f64 } else { 0.0 },
                (sim.time_s - sim_at_window) / secs,
            );
            (window_start, ticks, steps, busy, sim_at_window) = (Instant::now(), 0, 0, Duration::ZERO, sim.time_s);
        }
        publish(&sim, out, stats, &message, tools);
        if let Ok(mut p) = out.lock() {
            (p.ticks_total, p.steps_total, p.running_s) = (ticks_total, steps_total, start.elapsed().as_secs_f64());
        }
        next += TICK;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        } else if now - next > Duration::from_millis(50) {
            next = now; // far behind: resynchronise rather than burst
        }
    }
}
