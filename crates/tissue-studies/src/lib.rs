//! tissue-sim's studies, above the core: what the program measures of its models and how it fits
//! them. Layers 4 to 6, each using only those below it:
//!
//! 4. [`validate`]: the touch benchmark, the material's answer to a probe (the converged
//!    continuum) and the score against it, the dynamic reference and its measurement, static
//!    accuracy.
//! 5. [`calibrate`]: GA+SA, the polish, the load-free stiffness fit.
//! 6. [`study`]: speed against accuracy, stability, choice, the paper's tables, timings, scripts,
//!    palpation maps.
//!
//! May use: `tissue-core` and `tissue-gpu`; plotters for the figures. No window, no command line.

// The layers below, by the paths the code names them.
pub(crate) use tissue_core::{io, mechanics, response, sim};
pub(crate) use tissue_gpu as gpu;

pub mod calibrate;
pub mod study;
pub mod validate;

/// The tests' own cache folder (`tests/support/test_cache.rs`).
#[cfg(test)]
#[path = "../../../tests/support/test_cache.rs"]
mod test_cache;
