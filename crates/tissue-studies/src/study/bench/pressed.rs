//! The viewer's scene with the probe pressed, and its 1 ms tick timed (`bench`'s sweep on the
//! CPU and its GPU figures): object A held by its bottom face, the 15 mm probe pressed 4 mm into
//! the top face with the material's surface compliance, pressed along `sin^2` over 30 ticks and
//! held until its ringing dies down before the ticks are timed.

use crate::mechanics::cases::LoadCase;
use crate::sim::material_surface::{MaterialSurface, SurfaceProbe};
use crate::sim::{Integrator, Simulation, TICK_S, Tissue, Tool};

/// How deep the probe presses, m.
const PROBE_DEPTH_M: f64 = 0.004;

/// The viewer's scene for `tissue` (object A's), with the material's surface compliance.
pub fn scene(tissue: Box<dyn Tissue>, surface: &MaterialSurface) -> Simulation {
    let grid = tissue.grid();
    let mut sim =
        Simulation::with_tissue(tissue, Integrator::Symplectic, TICK_S, Some(&LoadCase::bottom_clamp(&grid, "A")));
    let zeta = sim.tissue.damping().ratio();
    sim.set_surface_probe(Some(SurfaceProbe::on(surface, grid, zeta)));
    sim
}

/// One tick of `integrator` at `substeps`: from rest the probe is pressed to its 4 mm along
/// `sin^2` over 30 ticks (3 where one tick takes over 50 ms) and held for 300 ticks or 1 s of
/// wall time (at least 2), then the median of ticks timed one by one over about 0.2 s (at least
/// 3).
/// On the physics pool, as the viewer's loop runs.
pub fn time_tick(sim: &mut Simulation, integrator: Integrator, substeps: usize) -> Result<f64, String> {
    crate::mechanics::parallel::on_pool(|| time_tick_here(sim, integrator, substeps))
}

fn time_tick_here(sim: &mut Simulation, integrator: Integrator, substeps: usize) -> Result<f64, String> {
    sim.reset();
    sim.try_set_integrator(Some(integrator), TICK_S / substeps as f64)?;
    let r = crate::validate::touch::PROBE_RADIUS_M;
    let top = crate::mechanics::grid::CUBE_SIDE_M + r;
    let mut failed = None;
    let mut tick = |sim: &mut Simulation, depth: f64| {
        sim.tool = Tool::Probe { centre: [0.03, 0.05, top - depth], radius: r };
        let start = std::time::Instant::now();
        for _ in 0..substeps {
            if let Err(e) = sim.step() {
                failed.get_or_insert(e.message);
            }
        }
        start.elapsed().as_secs_f64()
    };
    let first = tick(sim, 0.0);
    let ramp = if first > 0.05 { 3 } else { 30 };
    for i in 1..=ramp {
        let s = (0.5 * std::f64::consts::PI * i as f64 / ramp as f64).sin();
        tick(sim, PROBE_DEPTH_M * s * s);
    }
    // Held until the press's ringing has died down (the probe's contact solve takes more
    // iterations while the material's modes ring: 2.3x the steady tick just after the press).
    let (held_since, mut held) = (std::time::Instant::now(), 0);
    while held < 2 || (held < 300 && held_since.elapsed().as_secs_f64() < 1.0) {
        tick(sim, PROBE_DEPTH_M);
        held += 1;
    }
    let (mut times, mut spent) = (Vec::new(), 0.0);
    while times.len() < 3 || (spent < 0.2 && times.len() < 1000) {
        let t = tick(sim, PROBE_DEPTH_M);
        spent += t;
        times.push(t);
    }
    times.sort_by(f64::total_cmp);
    failed.map_or(Ok(times[times.len() / 2]), Err)
}
