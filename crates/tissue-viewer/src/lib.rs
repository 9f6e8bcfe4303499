//! tissue-sim's viewer: layers 7 and 8, above the core and the studies.
//!
//! 7. [`render`]: the wgpu renderer, offscreen images, what a static scene draws.
//! 8. [`app`]: the interactive viewer (winit, egui): the window, the panel, the physics thread
//!    and the background jobs.
//!
//! May use: `tissue-core`, `tissue-gpu`, `tissue-studies`; wgpu, winit, egui.

// The layers below, by the paths the code names them.
pub(crate) use tissue_core::{io, mechanics, response, sim};
pub(crate) use tissue_gpu as gpu;
pub(crate) use tissue_studies::{calibrate, study, validate};

pub mod app;
pub mod render;

/// The tests' own cache folder (`tests/support/test_cache.rs`).
#[cfg(test)]
#[path = "../../../tests/support/test_cache.rs"]
mod test_cache;
