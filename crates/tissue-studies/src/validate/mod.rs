//! Layer 4, validation: how good a model is, measured against references it was not fitted to.
//!
//! - [`touch`]: the touch benchmark's cases (point loads, top-face shear, the probe, modes) and
//!   their training and validation sets; [`touch::score`]: the same-mesh FEM's answers and the
//!   scores of a model against them (`validate`).
//! - [`continuum`]: the material's answer to a probe (graded hex8 meshes refined until the force
//!   stops changing), its fast tap ([`continuum::tap`]) and where both are kept
//!   ([`continuum::cache`]).
//! - [`probe`]: the presses a probe is scored on and the score against the material, and the
//!   viewer's tap against the material's.
//! - [`dynamic`]: the converged FEM transients of a scene and a running model's period, decay
//!   and trajectory error against them (`dynamics`).
//! - [`accuracy`]: the paper's cost and error tables of static answers (`errors`).
//! - [`inclusions`]: how well a model takes a material's inclusions, against the material.
//!
//! May use: [`crate::sim`], [`crate::response`], [`crate::mechanics`], [`crate::io`].

pub mod accuracy;
pub mod continuum;
pub mod dynamic;
pub mod inclusions;
pub mod probe;
pub mod touch;
pub mod transient;
