//! Dynamics that are right, not only stable.
//!
//! * [`damping`]: damping as a physical quantity, a ratio `zeta` at the fundamental, applied by
//!   one stated scheme (mass-proportional Rayleigh damping, `C = 2 zeta omega_1 M`).
//! * [`modal`]: a model's rest stiffness and lumped masses, its lowest modes on a clamp.
//! * [`single_mode`]: what each integrator does to one damped mode, in closed form.
//! * [`reference`](mod@reference): the converged FEM transients of a scene (Newmark average acceleration, the
//!   step halved until the answer changes by less than 0.1 %).
//! * [`measure`]: a running model's period, decay and trajectory error, by time stepping.
//!
//! Only [`measure`] steps a [`crate::sim::Tissue`]; the rest sits below the simulation.

pub mod damping;
pub mod measure;
pub mod modal;
pub mod reference;
pub mod single_mode;
