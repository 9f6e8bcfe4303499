//! The blow-up guard: whether a state is good, the last good state kept, and a blow-up
//! undone and explained.

use super::Simulation;
use crate::sim::integrator::Integrator;
use crate::sim::tool::Tool;
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

impl std::fmt::Display for BlowUp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "simulation blew up at t = {:.4} s: {}", self.time_s, self.message)
    }
}

impl std::error::Error for BlowUp {}

/// Consecutive recoveries after which the guard stops a run ([`BlowUp::fatal`]).
pub const MAX_RECOVERIES: u32 = 3;

/// A state whose kinetic energy is that of the whole mass moving at this speed has run away,
/// m/s.
const RUNAWAY_SPEED_M_S: f64 = 10.0;

/// Why a state is not good.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Unhealthy {
    NonFinite,
    OutsideCube,
    Energy,
}

impl Simulation {
    /// The guard: why the state now is not good, read where it lives (the GPU's figures of its
    /// last step, or, for a cube held nowhere, whose motion as a whole only the state shows,
    /// the state brought back); and whether the state was brought back for it.
    pub(super) fn check(&mut self) -> Result<(Option<Unhealthy>, bool), String> {
        match self.tissue.step_health() {
            Some(health) if self.tissue.free().contains(&0.0) => {
                let health = health?;
                self.device_drag_force(health);
                Ok((self.unhealthy_figures(health), false))
            }
            Some(health) => Ok((self.bring_back(health)?, true)),
            None => Ok((self.unhealthy(), false)),
        }
    }

    /// The state brought back from the GPU after its last step's figures `health` (the drag's
    /// force), and why it is not good, if it is not.
    pub(super) fn bring_back(
        &mut self,
        health: Result<crate::sim::tissue::StepHealth, String>,
    ) -> Result<Option<Unhealthy>, String> {
        self.device_drag_force(health?);
        self.tissue.sync()?;
        Ok(self.unhealthy())
    }

    /// After a failed step or an unhealthy state: restores the last good state (or rest after
    /// [`MAX_RECOVERIES`] in a row) and says why.
    pub(super) fn blow_up(&mut self, stepped: Result<(), String>, unhealthy: Option<Unhealthy>) -> BlowUp {
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
        BlowUp { time_s, message, fatal }
    }

    /// The state now as the last good one.
    pub(super) fn keep_good(&mut self) {
        let (x, v) = (self.tissue.x(), self.tissue.v());
        for c in 0..3 {
            self.good_x[c].copy_from_slice(&x[c]);
            self.good_v[c].copy_from_slice(&v[c]);
        }
        self.good_time = Some(self.time_s);
        self.steps_since_good = 0;
    }

    /// Brings the tissue's state back where its steps left it on the GPU (nothing to do on the
    /// CPU, or where it has not stepped since), to draw or read it, and checks it: a healthy
    /// state is kept as the last good one, an unhealthy one is a blow-up as in
    /// [`Simulation::step`].
    pub fn sync(&mut self) -> Result<(), BlowUp> {
        let Some(health) = self.tissue.step_health() else {
            return Ok(());
        };
        match self.bring_back(health) {
            Ok(None) => {
                self.keep_good();
                Ok(())
            }
            Ok(unhealthy) => Err(self.blow_up(Ok(()), unhealthy)),
            Err(e) => Err(self.blow_up(Err(e), None)),
        }
    }

    /// What went wrong in a step that failed or left the state unhealthy, and what to change.
    pub(super) fn diagnose(&self, stepped: Result<(), String>, unhealthy: Option<Unhealthy>) -> String {
        let limit = self.dt_limit();
        let dt = crate::io::num(self.dt);
        if let Err(e) = stepped {
            return if self.tissue.state_on_device() && self.integrator == Integrator::Symplectic {
                format!("the GPU's step or its readback failed ({e}); the state was reset")
            } else {
                format!("the implicit solve failed ({e}); the state was reset")
            };
        }
        if self.integrator == Integrator::Symplectic && self.dt > limit {
            return format!(
                "diverged: symplectic Euler with dt = {dt} s is above its stability limit of about {} s for this \
                 stiffness; the state was reset. Lower dt or choose the implicit integrator.",
                crate::io::num(limit)
            );
        }
        if let Tool::Drag { node, target } = self.tool {
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

    pub(super) fn restore(&mut self) {
        match self.good_time {
            Some(t) => {
                self.tissue.discard_device_state();
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
    ///
    /// The guard runs every tick on a state here, so its common case reads each array once (the positions twice
    /// for a cube held nowhere, whose mean shift comes first): a NaN or infinity fails the
    /// displacement's and the energy's comparisons too (both are written to fail on a NaN), and
    /// only a state that fails them is searched for one, to name the cause.
    pub(super) fn unhealthy(&self) -> Option<Unhealthy> {
        let l = crate::mechanics::grid::CUBE_SIDE_M;
        let (x, v) = (self.tissue.x(), self.tissue.v());
        // A cube held nowhere may move as a whole (a drag carries it along): its mean
        // displacement is motion, not deformation.
        let held = self.tissue.free().contains(&0.0);
        // False on a NaN.
        let within = |d: f64, bound: f64| d <= bound;
        let outside = (0..3).any(|c| {
            let shift = if held {
                0.0
            } else {
                x[c].iter().zip(&self.rest[c]).map(|(x, r)| x - r).sum::<f64>() / x[c].len() as f64
            };
            // A fold without an early exit: the compiler vectorises it.
            x[c].iter().zip(&self.rest[c]).fold(false, |out, (x, r)| out | !within((x - r - shift).abs(), l))
        });
        let energetic = !within(self.tissue.kinetic_energy(), self.runaway_energy());
        if !(outside || energetic) {
            return None;
        }
        let finite = x.iter().chain(v).all(|c| c.iter().all(|v| v.is_finite()));
        Some(if !finite {
            Unhealthy::NonFinite
        } else if outside {
            Unhealthy::OutsideCube
        } else {
            Unhealthy::Energy
        })
    }

    /// The force on the hand of the drag the GPU steps, `-m dv / dt` from its last step.
    pub(super) fn device_drag_force(&mut self, health: crate::sim::tissue::StepHealth) {
        if let Some(node) = self.device_drag {
            let m = self.tissue.node_mass(node);
            self.tool_force = health.held_velocity_change_m_s.map(|d| -m * d / self.dt);
        }
    }

    /// The kinetic energy of a state that has run away, J.
    pub(super) fn runaway_energy(&self) -> f64 {
        0.5 * self.tissue.total_mass() * RUNAWAY_SPEED_M_S * RUNAWAY_SPEED_M_S
    }

    /// [`Simulation::unhealthy`] from the GPU's figures of a step, for a held cube: a NaN, a node
    /// more than the cube's side from rest, or a runaway energy.
    pub(super) fn unhealthy_figures(&self, health: crate::sim::tissue::StepHealth) -> Option<Unhealthy> {
        if !(health.kinetic_energy_j.is_finite() && health.largest_displacement_m.is_finite()) {
            Some(Unhealthy::NonFinite)
        } else if health.largest_displacement_m > crate::mechanics::grid::CUBE_SIDE_M {
            Some(Unhealthy::OutsideCube)
        } else if health.kinetic_energy_j > self.runaway_energy() {
            Some(Unhealthy::Energy)
        } else {
            None
        }
    }
}
