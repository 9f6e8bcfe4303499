//! The viewer's scene with the probe moving as a hand moves it, and its 1 ms tick timed: object
//! A held by its bottom face, the 15 mm probe on the material's surface compliance (and slow
//! modes), moved at every step (the viewer's glide), at the step the automatic choice takes for
//! the viewer's 0.1 ms request. Two motions: *pressing* (in to 4 mm and out again along `sin^2`,
//! 0.4 s a cycle, on the top face) and *sliding* (4 mm deep across the top face, x = 30 to 70 mm
//! and back at 40 mm/s).

use std::collections::BTreeMap;

use crate::mechanics::cases::LoadCase;
use crate::mechanics::fem::dynamics::Formulation;
use crate::mechanics::grid::{CUBE_SIDE_M, Grid};
use crate::mechanics::material::Material;
use crate::sim::material_surface::{MaterialSurface, SurfaceProbe};
use crate::sim::{Integrator, Model, Simulation, TICK_S, Tool};

/// How deep the probe presses, m.
const DEPTH_M: f64 = 0.004;

/// The step the viewer asks for, s (the automatic choice may substep it further).
const REQUESTED_DT_S: f64 = 1e-4;

/// How the probe moves.
#[derive(Debug, Clone, Copy)]
enum Motion {
    Pressing,
    Sliding,
}

impl Motion {
    fn name(self) -> &'static str {
        match self {
            Motion::Pressing => "pressing",
            Motion::Sliding => "sliding",
        }
    }

    /// The sphere's centre at time `t`, s.
    fn centre(self, t: f64, radius: f64) -> [f64; 3] {
        let top = CUBE_SIDE_M + radius;
        match self {
            Motion::Pressing => {
                let s = (std::f64::consts::PI * t / 0.4).sin();
                [0.05, 0.05, top - DEPTH_M * s * s]
            }
            Motion::Sliding => {
                // A triangle wave between 30 and 70 mm at 40 mm/s (2 s a cycle).
                let phase = (t / 2.0).fract();
                let x = 0.03 + 0.04 * (1.0 - (2.0 * phase - 1.0).abs());
                [x, 0.05, top - DEPTH_M]
            }
        }
    }
}

/// The mean 1 ms tick, seconds, keyed `model/nodes/motion`: the default tissue at 8 and 12
/// nodes a side and the corotational FEM at 8, each pressing and sliding. The viewer keeps 1 kHz
/// where a tick is below 1 ms (with the drawing on the other core).
pub fn run() -> anyhow::Result<BTreeMap<String, f64>> {
    let material = Material::object_a();
    let mut report = crate::sim::material_surface::stderr_report();
    let surface =
        MaterialSurface::load_or_compute(&material, crate::io::cache_dir().as_deref(), &mut |e| report.event(e))?;
    let mut out = BTreeMap::new();
    let default = Model::Lattice(crate::sim::shipped::DEFAULT_TOPOLOGY);
    for (model, nodes) in [(default, 8), (default, 12), (Model::Fem(Formulation::Corotational), 8)] {
        for motion in [Motion::Pressing, Motion::Sliding] {
            let t = crate::mechanics::parallel::on_pool(|| tick(&material, &surface, model, nodes, motion))?;
            out.insert(format!("{}/{nodes}/{}", model.name(), motion.name()), t);
        }
    }
    Ok(out)
}

/// The mean tick of `model` on `nodes` a side, moving as `motion` says, over 1 s of wall time
/// after 0.2 s simulated.
fn tick(
    material: &Material,
    surface: &MaterialSurface,
    model: Model,
    nodes: usize,
    motion: Motion,
) -> anyhow::Result<f64> {
    let grid = Grid::new(nodes)?;
    let tissue = model.build_on(grid, material, None, crate::response::damping::DEFAULT_DAMPING_RATIO)?;
    let mut sim = Simulation::with_tissue(
        tissue,
        Integrator::Symplectic,
        REQUESTED_DT_S,
        Some(&LoadCase::bottom_clamp(&grid, "A")),
    );
    sim.try_set_integrator(None, REQUESTED_DT_S).map_err(anyhow::Error::msg)?;
    let zeta = sim.tissue.damping().ratio();
    sim.set_surface_probe(Some(SurfaceProbe::on(surface, grid, zeta)));
    let r = crate::validate::touch::PROBE_RADIUS_M;
    let substeps = (TICK_S / sim.dt).round().max(1.0) as usize;
    let (mut t, mut failed) = (0.0, None);
    let mut one_tick = |sim: &mut Simulation| {
        for _ in 0..substeps {
            t += sim.dt;
            sim.tool = Tool::Probe { centre: motion.centre(t, r), radius: r };
            if let Err(e) = sim.step() {
                failed.get_or_insert(e.message);
            }
        }
    };
    for _ in 0..200 {
        one_tick(&mut sim);
    }
    let start = std::time::Instant::now();
    let mut ticks = 0usize;
    while ticks < 100 || start.elapsed().as_secs_f64() < 1.0 {
        one_tick(&mut sim);
        ticks += 1;
    }
    let mean = start.elapsed().as_secs_f64() / ticks as f64;
    match failed {
        Some(m) => anyhow::bail!("{} on {nodes}^3 {}: {m}", model.name(), motion.name()),
        None => Ok(mean),
    }
}

/// The rows of [`run`]'s figures, a line each.
pub fn to_text(ticks: &BTreeMap<String, f64>) -> String {
    ticks
        .iter()
        .map(|(key, t)| {
            format!(
                "{:<46}: {:10.2} us ({:.0} ticks/s possible)\n",
                format!("viewer 1 ms tick, probe moving, {key}"),
                t * 1e6,
                1.0 / t
            )
        })
        .collect()
}
