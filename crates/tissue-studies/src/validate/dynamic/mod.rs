//! Dynamic accuracy: the converged FEM transients of a scene ([`mod@reference`]: Newmark average
//! acceleration, the step halved until the answer changes by less than 0.1 %) and a running
//! model's period, decay and trajectory error against them, by time stepping the simulation
//! ([`measure`], `dynamics`).

pub mod measure;
/// The reference transients, [`crate::validate::transient`].
pub use super::transient as reference;
