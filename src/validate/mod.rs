//! Layer 4, validation: how good a model is, measured against references it was not fitted to.
//!
//! - [`touch`]: the touch benchmark's cases (point loads, top-face shear, the probe, modes) and
//!   their training and validation sets; [`touch_score`]: the same-mesh FEM's answers and the
//!   scores of a model against them (`validate`).
//! - [`dynamic_reference`]: the converged FEM transients of a scene (Newmark average
//!   acceleration, the step halved until the answer changes by less than 0.1 %);
//!   [`dynamic_measure`]: a running model's period, decay and trajectory error, by time stepping
//!   the simulation (`dynamics`).
//! - [`accuracy`]: the paper's cost and error tables of static answers (`errors`).
//!
//! May use: [`crate::sim`], [`crate::response`], [`crate::mechanics`], [`crate::io`].

pub mod accuracy;
pub mod continuum;
pub mod continuum_cache;
pub mod continuum_tap;
pub mod dynamic_measure;
pub mod dynamic_reference;
pub mod presses;
pub mod probe_score;
pub mod tap;
pub mod touch;
pub mod touch_score;
