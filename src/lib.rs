//! tissue-sim: an anisotropic soft-tissue cube, simulated by a mass-spring model calibrated
//! against a linear finite-element reference (Choi, "heuristically parameterized anisotropic
//! mass-spring model"). See `ARCHITECTURE.md` for the layers, threads and rules, and `docs/` for
//! the methods.
//!
//! Data flows one way: material -> FEM reference -> cost -> calibration -> model parameters ->
//! physics thread -> renderer. The folders are the layers, bottom to top; each uses only those
//! below it:
//!
//! 0. [`io`]: bounded reading, atomic writing, numbers in messages.
//! 1. [`mechanics`]: grid, material, load cases, sparse solver, the hex8 FEM, the mass-spring
//!    lattices.
//! 2. [`response`]: the linear response shared above (stiffness groups, the scene solver and its
//!    contact, modes, damping, integrators on one mode).
//! 3. [`sim`]: the models the simulation steps (one model and one integrator vocabulary), the
//!    step policy, tools, the blow-up guard, the shipped tissues.
//!    [`gpu`] (3b): the lattices' and the linear FEM's explicit step as wgpu compute shaders,
//!    behind the simulation's seam.
//! 4. [`validate`]: the touch benchmark, the material's answer to a probe (the converged
//!    continuum) and the score against it, the dynamic reference and its measurement, static
//!    accuracy.
//! 5. [`calibrate`]: GA+SA, the polish, the load-free stiffness fit.
//! 6. [`study`]: speed against accuracy, stability, choice, the paper's tables, timings, scripts.
//! 7. [`render`]: the wgpu renderer, offscreen images, what a static scene draws.
//! 8. [`app`]: the interactive viewer.
//! 9. [`cli`]: the command line, which parses and prints.

pub mod app;
pub mod calibrate;
pub mod cli;
pub mod gpu;
pub mod io;
pub mod mechanics;
pub mod render;
pub mod response;
pub mod sim;
pub mod study;
pub mod validate;
