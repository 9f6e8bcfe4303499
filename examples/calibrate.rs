//! A calibration: the paper's hybrid GA+SA fitting the shear lattice's spring stiffnesses of
//! object B against the hex8 FEM's answer to the paper's nine clamped load cases (a smaller
//! search than `tissue-sim calibrate`'s 50 x 100, seeded: the same answer every run).
//!
//! `cargo run --release --example calibrate`

use std::sync::atomic::AtomicBool;

use tissue_core::mechanics::grid::Grid;
use tissue_core::prelude::*;
use tissue_studies::calibrate::{CaseSet, GeneSpace, Method, Problem, Settings, calibrate};

fn main() -> anyhow::Result<()> {
    let material = Material::object(Object::B);
    let (grid, topology) = (Grid::paper(), Topology::Shear);
    let problem = Problem::new(material.as_internal().clone(), grid, topology)?.with_cases(CaseSet::Paper)?;
    let space = GeneSpace::new(material.as_internal(), &grid, topology);
    let settings = Settings { method: Method::Hybrid, seed: 1, population: 20, generations: 30, ..Settings::default() };
    let result = calibrate(&problem, &space, &settings, &AtomicBool::new(false), &mut |g| {
        if g.generation % 10 == 0 {
            println!("generation {}: best cost {:.4e} m", g.generation, g.best_cost);
        }
    })?;
    let p = result.params;
    println!(
        "shear lattice of B: k1 = {:.1}, k2 = {:.1}, k3 = {:.1}, c12 = {:.1}, c23 = {:.1} N/m; cost {:.4e} m in {:.1} s",
        p.k1,
        p.k2,
        p.k3,
        p.c12.unwrap_or(0.0),
        p.c23.unwrap_or(0.0),
        result.cost,
        result.wall_s
    );
    Ok(())
}
