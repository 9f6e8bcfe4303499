//! The paper's mass-spring model (MSM) and its richer lattices.
//!
//! Nodes carry equal lumped masses; springs follow `f = k (|l| - l0)` along the spring; every node
//! feels the damping force `-d v`. [`model`] holds the parameters and springs, [`forces`] the force
//! and tangent kernels, [`statics`] the exact equilibrium, [`dynamics`] the time integrators.
//!
//! [`reduction`]: the clamped cases' mirror-symmetric unknowns; [`single`]: the force in `f32`;
//! [`inclusions`]: the springs' rule for a material's inclusions.

pub mod dynamics;
pub mod forces;
pub mod inclusions;
pub mod model;
pub mod reduction;
pub mod single;
pub mod statics;

pub use dynamics::Dynamics;
pub use model::{MsmModel, MsmParams, ParamError, Topology};
