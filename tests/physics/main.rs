//! Whole behaviours of the physics core, one test binary: the FEM against exact answers, the
//! mass-spring statics, calibration, stability, and the touch benchmark.

#[path = "../support/test_cache.rs"]
mod test_cache;

mod calibration;
mod dynamics;
mod fem_reference;
mod gpu_step;
mod inclusion;
mod msm_statics;
mod probe_hold;
mod probe_material;
mod stability;
mod touch;
