//! The seam between the interactive simulation and a tissue model: [`Tissue`] is what
//! the simulation (tools, contact, blow-up guard), the physics thread and `simulate` need
//! of a model, whatever it is. The mass-spring lattices (`MsmTissue`) and the FEM
//! (`FemTissue`) implement it.
//!
//! State is node-wise in structure-of-arrays form: positions `x[c][p]`, velocities `v[c][p]`,
//! external forces `f_ext[c][p]` (components `c = 0..3`, node `p`), and `free[p]` (1 for a free
//! node, 0 for a fixed one). Steps must not allocate after their first call.
//!
//! A tissue whose state stays on another device between steps (the GPU's,
//! [`Tissue::state_on_device`]) keeps these arrays as a copy that follows only at
//! [`Tissue::sync`] and before anything writes them; its steps report the guard's figures
//! ([`Tissue::step_health`]) without the state.

use super::integrator::Integrator;
use crate::mechanics::cases::LoadCase;
use crate::mechanics::grid::Grid;
use crate::mechanics::msm::MsmParams;
use crate::response::damping::Damping;

/// The guard's figures of a step, from where the state lives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepHealth {
    /// Kinetic energy, J (NaN where a velocity is).
    pub kinetic_energy_j: f64,
    /// The largest displacement component of any node from rest, m (NaN where one is).
    pub largest_displacement_m: f64,
    /// The velocity change the dragging spring gave its node in the last step, where the device
    /// steps the drag ([`Tissue::hold_by_drag`]), m/s; zero otherwise.
    pub held_velocity_change_m_s: [f64; 3],
}

/// A tissue model the interactive simulation can step.
pub trait Tissue: Send + std::fmt::Debug {
    /// The grid its nodes lie on.
    fn grid(&self) -> Grid;
    /// Mass of the whole cube, kg.
    fn total_mass(&self) -> f64;
    /// Lumped mass of node `p`, kg.
    fn node_mass(&self, p: usize) -> f64;
    /// Positions, metres.
    fn x(&self) -> &[Vec<f64>; 3];
    /// Positions, for tools and the guard to write.
    fn x_mut(&mut self) -> &mut [Vec<f64>; 3];
    /// Velocities, m/s.
    fn v(&self) -> &[Vec<f64>; 3];
    /// Velocities, for tools and the guard to write.
    fn v_mut(&mut self) -> &mut [Vec<f64>; 3];
    /// Both at once (contact writes positions and velocities together).
    fn x_v_mut(&mut self) -> (&mut [Vec<f64>; 3], &mut [Vec<f64>; 3]);
    /// External nodal forces, newtons (the load case plus the tools).
    fn f_ext_mut(&mut self) -> &mut [Vec<f64>; 3];
    /// 1.0 for a free node, 0.0 for a fixed one.
    fn free(&self) -> &[f64];
    /// Internal plus external force on every node at the current positions, newtons.
    fn forces(&mut self) -> &[Vec<f64>; 3];
    /// One step of `integrator` with time step `dt`.
    fn step(&mut self, integrator: Integrator, dt: f64) -> Result<(), String>;
    /// Kinetic energy, joules.
    fn kinetic_energy(&self) -> f64;
    /// The critical time step of the explicit integrator (an estimate on the safe side), s.
    fn explicit_dt_limit(&self) -> f64;
    /// The limit the step policy respects: [`Tissue::explicit_dt_limit`] of a tissue that may
    /// stiffen as it deforms, unless the tissue says its stiffness is constant.
    fn step_limit(&self) -> super::integrator::StepLimit {
        super::integrator::StepLimit::tissue(self.explicit_dt_limit())
    }
    /// Fixes and loads nodes as `case` says (the state is kept).
    fn apply_case(&mut self, case: &LoadCase);
    /// The running mass-spring parameters, if the model has them.
    fn params(&self) -> Option<MsmParams>;
    /// Replaces the parameters, keeping the state (a calibration result applied live); a damping
    /// ratio set stays set (at the new fundamental).
    fn set_params(&mut self, params: MsmParams) -> Result<(), String>;
    /// Damps the model by the ratio `zeta` at its fundamental on the viewer's scene, mass
    /// proportionally ([`crate::response::damping`]); refused for the paper's axis lattice.
    fn set_damping_ratio(&mut self, zeta: f64) -> Result<(), String>;
    /// How the model is damped now.
    fn damping(&self) -> Damping;
    /// Its rest stiffness and masses (its small-displacement dynamics), or why it has none.
    fn modal(&self) -> Result<crate::response::modal::ModalModel, String>;
    /// Whether it can carry the probe's contact forces as loads on its surface nodes. The paper's
    /// axis lattice cannot: nothing resists a layer sliding over the one below, and under a
    /// press its columns fold over (a node 6 cm off after 0.3 s at 8^3); it shows the press by
    /// its own node contact while the hand still feels the material's surface compliance.
    fn carries_contact_loads(&self) -> bool {
        true
    }
    /// Where its steps run when not on this CPU (the GPU's adapter), in words.
    fn computed_on(&self) -> Option<String> {
        None
    }
    /// What the prefactored implicit steps' Newton corrections and conjugate gradients have done
    /// since their factor was built ([`crate::mechanics::newton_krylov::NewtonSolves`]): the
    /// corotational FEM's and the lattices'; `None` for the linear FEM (one exact solve a step)
    /// or before the first prefactored step.
    fn newton_solves(&self) -> Option<crate::mechanics::newton_krylov::NewtonSolves> {
        None
    }
    /// Holds a node by a spring and damper inside its implicit steps' solves (`None` lets go;
    /// the pull at the step's start is the caller's, in [`Tissue::f_ext_mut`]), and says whether
    /// it does: a model without implicit steps leaves the drag to the caller's split step.
    fn set_anchor(&mut self, anchor: Option<crate::mechanics::anchor::Anchor>) -> bool {
        let _ = anchor;
        false
    }
    /// Sums its symplectic step's internal force in `f32` (`single`) or in `f64` (the default),
    /// the rest of the step in `f64`; refused, saying why, by a model without an `f32` force.
    fn set_single_precision(&mut self, single: bool) -> Result<(), String> {
        if single { Err("this model has no f32 step: the lattices and the linear FEM have one".into()) } else { Ok(()) }
    }
    /// Its symplectic Euler step as plain numbers (for the GPU's step), or why it has none.
    fn explicit_form(&self) -> Result<super::explicit_form::ExplicitForm, String>;
    /// The load, of which only the nodes `nodes` change before the next step (a tissue whose
    /// steps run on the GPU sends only those).
    fn f_ext_mut_nodes(&mut self, nodes: std::ops::Range<usize>) -> &mut [Vec<f64>; 3] {
        let _ = nodes;
        self.f_ext_mut()
    }
    /// Whether its symplectic steps leave the state on another device (the GPU), so that
    /// [`Tissue::x`], [`Tissue::v`] and [`Tissue::kinetic_energy`] are those of the last
    /// [`Tissue::sync`] (what writes the state brings it back first).
    fn state_on_device(&self) -> bool {
        false
    }
    /// Brings the state back from where the steps left it (nothing to do on the CPU).
    fn sync(&mut self) -> Result<(), String> {
        Ok(())
    }
    /// The state is about to be written whole (a reset, a restore): the device's is dropped
    /// without being brought back, and so is a failed readback already reported.
    fn discard_device_state(&mut self) {}
    /// Takes the dragging spring's split step ([`super::drag_velocity_change`]) on `node`
    /// towards `target` after each symplectic step where the state lives (`None`: lets go), and
    /// says whether it does: a tissue whose state is here leaves it to the caller.
    fn hold_by_drag(&mut self, drag: Option<(usize, [f64; 3])>) -> bool {
        let _ = drag;
        false
    }
    /// Where the state is on another device: the guard's figures of its last step, read there
    /// (a few bytes, not the state). `None` where the state is here (the guard reads it).
    fn step_health(&mut self) -> Option<Result<StepHealth, String>> {
        None
    }
}
