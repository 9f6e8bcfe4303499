//! Layer 3, the simulation: any [`Tissue`] model stepped at a fixed time step, with the user's
//! tools (a dragging spring, a spherical probe with real contact), a blow-up guard, and the step
//! policy (the one place that decides which integrator and step a model runs). No GPU types and
//! no threads: the viewer's physics thread and the headless `simulate` command both drive this.
//!
//! - [`model`]: the one model vocabulary ([`Model`]) and how each is built; [`integrator`]: the
//!   one integrator vocabulary ([`Integrator`]) and the step policy.
//! - [`tissue`]: the seam ([`Tissue`]); [`msm_tissue`] and [`fem_tissue`]: the lattices and the
//!   FEM behind it; [`shipped`]: the calibrated tissues in `assets/`.
//! - [`explicit_form`]: a model's explicit step as plain numbers (what the GPU's step runs).
//! - [`tool`]: drag and probe; [`simulation`]: the running tissue, its tools and its guard.
//!
//! May use: [`crate::response`], [`crate::mechanics`], [`crate::io`].
//!
//! [`material_surface`]: the probe on the material's surface: its contact compliance (computed,
//! kept), its slow modes lagging behind their static answer, and the probe that joins them.

/// The interactive tick, ms: the viewer's physics loop advances the clock by one tick at a time
/// (its steps substep it), the probe's contact solve runs at most once a tick (the haptic rate),
/// and the benchmarks time one.
pub const TICK_MS: u64 = 1;
/// [`TICK_MS`] in seconds.
pub const TICK_S: f64 = TICK_MS as f64 * 1e-3;

pub mod explicit_form;
pub mod fem_tissue;
pub mod integrator;
pub mod material_surface;
pub mod model;
pub mod msm_tissue;
pub mod press;
pub mod shipped;
pub mod simulation;
pub mod tissue;
pub mod tool;

pub use fem_tissue::FemTissue;
pub use integrator::{
    AUTO_EXPLICIT_FRACTION, DEFAULT_DYNAMIC_BUDGET, DT_RANGE_S, DynamicBudget, Integrator, MAX_AUTO_SUBSTEPS,
    MAX_EXPLICIT_FRACTION, PREFACTORED_STEP_COST, StepLimit, check_dt, choose_integrator, choose_step, fewest_substeps,
    predicted_error,
};
pub use model::Model;
pub use msm_tissue::{MsmTissue, explicit_dt_limit};
pub use simulation::{BlowUp, MAX_RECOVERIES, Simulation};
pub use tissue::Tissue;
pub use tool::{DRAG_DAMPING, DRAG_STIFFNESS, Tool, drag_velocity_change};
