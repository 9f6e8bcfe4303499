//! Layer 2, the linear response shared by calibration, validation, dynamics and the simulation:
//! what a model does at rest, in small displacements, on the viewer's scene (face z = 0 clamped).
//!
//! - [`contact`]: the one contact of a rigid sphere with surface nodes (an active set over any
//!   [`contact::Compliance`]), and the sphere's gap.
//! - [`linear`]: a lattice's stiffness as a sum over spring groups, the scene's sparse solver, the
//!   probe on it (node contact through [`contact`]).
//! - [`modes`]: the lowest natural modes of a scene solver; [`modal`]: a model's rest stiffness
//!   and lumped masses, its modes on any clamp.
//! - [`stiffest_mode`]: the largest eigenvalue of `M^-1 K` (Lanczos), with an upper estimate
//!   for the explicit step limits.
//! - [`damping`]: damping as a ratio `zeta` at the fundamental (mass-proportional Rayleigh
//!   damping, `C = 2 zeta omega_1 M`); [`single_mode`]: what each integrator does to one damped
//!   mode, in closed form.
//!
//! May use: [`crate::mechanics`], [`crate::io`].

pub mod contact;
pub mod damping;
pub mod linear;
pub mod modal;
pub mod modes;
pub mod single_mode;
pub mod stiffest_mode;
