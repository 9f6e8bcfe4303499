//! A press: a 15 mm probe pressed 4 mm into the middle of object A's top face, held for a second,
//! and the force the material pushes back with (about 9.7 N).
//!
//! `cargo run --release --example press`

use tissue_core::prelude::*;

fn main() -> Result<(), Error> {
    let material = Material::object(Object::A); // or Material::from_file("my_tissue.toml")?
    let mut sim = Simulation::builder(&material).build()?; // the viewer's defaults
    sim.press(Press::normal([0.05, 0.05, 0.10], 0.015).depth(0.004));
    sim.run_for(1.0)?;
    let r = sim.probe().expect("pressed"); // Option<ProbeReading>
    println!("{:.2} N at {:.1} mm ({:?})", r.force_n, r.depth_m * 1e3, r.contact);
    Ok(())
}
