//! Whole behaviours of the physics core, one test binary: the FEM against exact answers, the
//! mass-spring statics, calibration, and stability.

mod calibration;
mod fem_reference;
mod msm_statics;
mod stability;
