//! Whole behaviours of the interactive side, one test binary: the probe gesture, scripted interaction (the
//! `simulate` engine), shader validation, and offscreen rendering.

mod gesture;
mod interaction;
mod render;
mod shaders;
