//! Whole behaviours of the interactive side, one test binary: the probe gesture, scripted interaction (the
//! `simulate` engine), shader validation, and offscreen rendering.

#[path = "../support/test_cache.rs"]
mod test_cache;

mod gesture;
mod interaction;
mod render;
mod shaders;
