//! A palpation map: object A with a lump five times as stiff, 8 mm in radius, under the top face
//! (`assets/examples/lump_5x_r8.toml`), pressed by a 15 mm probe 4 mm deep at 7 x 7 points of the
//! top face; the force at each, and how much stiffer the lump makes it there.
//!
//! `cargo run --release --example palpate`

use tissue_core::prelude::*;
use tissue_core::sim::material_surface::with_background;
use tissue_studies::study::palpate::{Face, Palpation, PalpationMap};

fn main() -> anyhow::Result<()> {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/examples/lump_5x_r8.toml");
    let material = Material::from_file(file)?;
    let palpation =
        Palpation { face: Face::parse("+z").map_err(anyhow::Error::msg)?, radius: 0.015, depth: 0.004, grid: 7 };
    palpation.check().map_err(anyhow::Error::msg)?;
    let dir = tissue_core::io::cache_dir();
    // The material's surface compliance without and with the lump (computed once, then kept).
    let (background, lumpy) = with_background(material.as_internal(), dir.as_deref(), &mut |_| true)?;
    let forces = palpation.forces(&lumpy, &mut || {}).map_err(anyhow::Error::msg)?;
    let without = palpation.forces(&background, &mut || {}).map_err(anyhow::Error::msg)?;
    let map = PalpationMap::new(material.as_internal(), &palpation, forces, without);
    for row in 0..map.grid {
        let line: Vec<String> = (0..map.grid)
            .map(|col| {
                let i = row * map.grid + col;
                format!("{:5.2} N {:+5.1}%", map.forces[i], map.contrast[i])
            })
            .collect();
        println!("{}", line.join("  "));
    }
    if let Some((contrast, at)) = map.peak() {
        println!("largest contrast {contrast:+.1} % at ({:.0}, {:.0}) mm", at[0] * 1e3, at[1] * 1e3);
    }
    Ok(())
}
