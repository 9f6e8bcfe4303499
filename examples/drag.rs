//! A drag: object B's top corner pulled 4 mm along x by the mouse's spring, held, let go; the
//! corner's path and the pull the hand feels.
//!
//! `cargo run --release --example drag`

use tissue_core::prelude::*;

fn main() -> Result<(), Error> {
    let material = Material::object(Object::B);
    let mut sim = Simulation::builder(&material).build()?;
    let corner = sim.positions().len() - 1; // (0.1, 0.1, 0.1): x fastest, then y, then z
    sim.drag(corner, [0.104, 0.1, 0.1]);
    for _ in 0..5 {
        sim.run_for(0.1)?;
        let x = sim.positions()[corner];
        println!("t = {:.1} s: corner at x = {:.3} mm, pull {:.3} N", sim.time_s(), x[0] * 1e3, sim.tool_force()[0]);
    }
    sim.release();
    sim.run_for(0.5)?;
    println!("released, t = {:.1} s: corner at x = {:.3} mm", sim.time_s(), sim.positions()[corner][0] * 1e3);
    Ok(())
}
