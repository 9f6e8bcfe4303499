//! The public face: what a program that builds on the core names. [`Material`] (the paper's
//! objects or a material file), [`Simulation`] and its [`SimulationBuilder`] (the viewer's
//! defaults, each documented), the one [`Press`] and [`ProbeReading`], and the one [`Error`].
//!
//! - `error`: [`Error`].
//! - `material`: [`Material`].
//! - `simulation`: [`Simulation`], [`SimulationBuilder`].

mod error;
mod material;
mod simulation;

pub use error::Error;
pub use material::Material;
pub use simulation::{DEFAULT_DT_S, Simulation, SimulationBuilder};
