//! tissue-core: an anisotropic soft-tissue cube that a program presses, drags and steps in real
//! time, with the force the material pushes back with.
//!
//! A program builds a [`Simulation`] of a [`Material`] (the paper's objects A and B, or a material
//! file), presses a rigid spherical probe into it ([`Press`]), runs it and reads the force
//! ([`ProbeReading`]). The probe's force is the material's own (its surface compliance from a
//! converged hex8 FEM and its slow modes), whatever model shows the tissue; the model (by default a
//! hex mass-spring lattice calibrated against the FEM by the paper's GA+SA) deforms under it.
//!
//! ```
//! use tissue_core::prelude::*;
//!
//! let material = Material::object(Object::A);
//! let mut sim = Simulation::builder(&material).build()?; // the viewer's defaults
//! // A 15 mm sphere pressed 4 mm into the middle of the top face.
//! sim.press(Press::normal([0.05, 0.05, 0.10], 0.015).depth(0.004));
//! sim.run_for(1.0)?;
//! let r = sim.probe().expect("pressed");
//! println!("{:.2} N at {:.1} mm ({:?})", r.force_n, r.depth_m * 1e3, r.contact);
//! // The material (the converged continuum) pushes back with 9.7 N; the probe within 7 %.
//! assert!((r.force_n - 9.7).abs() < 0.07 * 9.7, "{r:?}");
//! assert_eq!(r.contact, Contact::Surface);
//! # Ok::<(), Error>(())
//! ```
//!
//! The first press of a material computes its surface compliance (about a minute on one core)
//! and keeps it in the cache folder; later runs read it back in a fraction of a second.
//!
//! Everything a program names is in [`prelude`]. Errors are one type, [`Error`], each with a
//! one-line message. Units are SI throughout (metres, newtons, pascals, seconds); the cube is
//! 0.1 m a side with its bottom face (z = 0) held.
#![cfg_attr(not(feature = "internals"), allow(dead_code, unused_imports))]

/// Declares the layers: public for tissue-sim's own crates (feature `internals`), else internal.
macro_rules! layers {
    ($($(#[$doc:meta])* $name:ident),* $(,)?) => {
        $(
            $(#[$doc])*
            #[cfg(feature = "internals")]
            pub mod $name;
            #[cfg(not(feature = "internals"))]
            mod $name;
        )*
    };
}

layers! {
    io,
    mechanics,
    response,
    sim,
}

mod face;

pub use face::{DEFAULT_DT_S, Error, Material, Simulation, SimulationBuilder};
pub use mechanics::fem::dynamics::Formulation;
pub use mechanics::material::{EngineeringConstants, MaterialError};
pub use mechanics::msm::Topology;
pub use mechanics::object::Object;
pub use sim::press::{Contact, Press, ProbeReading};
pub use sim::{BlowUp, Integrator, Model};

/// What a program that builds on the core names: `use tissue_core::prelude::*;`.
pub mod prelude {
    pub use crate::{
        Contact, Error, Formulation, Integrator, Material, Model, Object, Press, ProbeReading, Simulation,
        SimulationBuilder, Topology,
    };
}

/// The tests' own cache folder (`tests/support/test_cache.rs`).
#[cfg(test)]
#[path = "../../../tests/support/test_cache.rs"]
mod test_cache;
