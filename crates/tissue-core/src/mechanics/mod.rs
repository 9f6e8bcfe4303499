//! Layer 1, the mechanics: the cube, its material, its load cases and the two models of it.
//!
//! - [`grid`]: nodes, elements and spring families of the cube; [`material`]: engineering
//!   constants, `S` and `C`; [`inclusion`]: spheres of another stiffness in it; [`cases`]: the benchmark's load cases and their answers;
//!   [`displacement_file`]: the spec's JSON of case answers; [`object`]: the paper's objects A and
//!   B by name.
//! - [`sparse`]: faer's sparse Cholesky behind one SPD system type.
//! - [`fem`]: hex8 statics and dynamics; [`msm`]: the mass-spring lattices, statics and dynamics.
//! - [`parallel`]: the physics' own thread pool; [`anchor`]: a node held by a spring inside an
//!   implicit step's solve; [`newton_krylov`]: the nonlinear models' implicit steps, Newton by
//!   conjugate gradients on the rest factor; [`kinetic`]: the kinetic energy of lumped masses.
//!
//! May use: [`crate::io`] only. Knows no simulation, calibration, GPU or command line.

pub mod anchor;
pub mod cases;
pub mod displacement_file;
pub mod fem;
pub mod grid;
pub mod inclusion;
pub mod kinetic;
pub mod material;
pub mod msm;
pub mod newton_krylov;
pub mod object;
pub mod parallel;
pub mod sparse;
