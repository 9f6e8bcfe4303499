//! The `tissue-sim` program: its command line ([`cli`]), over the workspace's crates.
//!
//! Data flows one way: material -> FEM reference -> cost -> calibration -> model parameters ->
//! physics thread -> renderer. The crates are the layers, bottom to top; each uses only those
//! below it:
//!
//! - `tissue-core`: io, mechanics (grid, material, load cases, the hex8 FEM, the lattices),
//!   response (stiffness groups, the contact, modes, damping), sim (models, integrators, tools,
//!   the material's surface) and the public face other programs build on (`tissue_core::prelude`).
//! - `tissue-gpu`: the lattices' and the linear FEM's explicit step as wgpu compute shaders,
//!   behind the simulation's seam.
//! - `tissue-studies`: validate, calibrate, study (chart, bench, scripts, reproduce, palpate).
//! - `tissue-viewer`: render and app, the interactive viewer.
//! - this crate: [`cli`], the command line, which parses and prints.
//!
//! See `ARCHITECTURE.md` for the layers, threads and rules, and `docs/` for the methods.

// The layers below, by the paths the code names them.
pub(crate) use tissue_core::{io, mechanics, response, sim};
pub(crate) use tissue_gpu as gpu;
pub(crate) use tissue_studies::{calibrate, study, validate};
pub(crate) use tissue_viewer::{app, render};

pub mod cli;

/// The tests' own cache folder (`tests/support/test_cache.rs`).
#[cfg(test)]
#[path = "../tests/support/test_cache.rs"]
mod test_cache;
