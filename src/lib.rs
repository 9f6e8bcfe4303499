//! tissue-sim: an anisotropic soft-tissue cube, simulated by a mass-spring model calibrated
//! against a linear finite-element reference (Choi, "heuristically parameterized anisotropic
//! mass-spring model"). See `ARCHITECTURE.md` for the layers, threads and rules.
//!
//! Data flows one way: material -> FEM reference -> cost -> calibration -> model parameters ->
//! physics thread -> renderer.
//!
//! - Core: [`material`] (engineering constants, `S`, `C`), [`grid`] (nodes, elements, spring
//!   families), [`cases`] (the benchmark's load cases and their answers), [`sparse`] (faer's
//!   sparse Cholesky), [`fem`] (hex8 statics and dynamics), [`msm`] (the mass-spring lattices),
//!   [`tissue`] (the shipped calibrated tissues), [`sim`] (the interactive simulation over any
//!   tissue model), [`calibrate`] (GA+SA), [`accuracy`] (cost and error tables), [`io`] (JSON and
//!   safe output files).
//! - [`touch`]: the touch benchmark (held-out point, shear and probe touches, modes) behind
//!   `validate`.
//! - [`dynamic`]: damping as a ratio at the fundamental, the integrators' closed forms on one
//!   mode, the converged FEM transients and the dynamic measurement behind `dynamics`.
//! - Studies: [`study`] (speed against accuracy, stability, choice), [`reproduce`] (the paper's
//!   tables and figures), [`bench`](mod@bench) (timings), [`script`] (`simulate`).
//! - Presentation: [`render`] (wgpu renderer, offscreen), [`scene`] (what is drawn).
//! - [`app`]: the interactive viewer. [`cli`]: the command line.

pub mod accuracy;
pub mod app;
pub mod bench;
pub mod calibrate;
pub mod cases;
pub mod cli;
pub mod dynamic;
pub mod fem;
pub mod grid;
pub mod io;
pub mod material;
pub mod msm;
pub mod render;
pub mod reproduce;
pub mod scene;
pub mod script;
pub mod sim;
pub mod sparse;
pub mod study;
pub mod tissue;
pub mod touch;
