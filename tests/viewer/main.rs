//! Whole behaviours of the interactive side, one test binary: scripted interaction (the
//! `simulate` engine), shader validation, and offscreen rendering.

mod interaction;
mod render;
mod shaders;
