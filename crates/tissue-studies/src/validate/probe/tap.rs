//! The probe tap ([`dynamic_reference::tap_centre`]) run in the viewer's simulation, its contact
//! and force readout: on the model's own surface nodes (scored against the same-mesh FEM's
//! converged tap) or on the material's surface compliance with the material's slow modes, the
//! viewer's default (scored against the material's converged tap,
//! [`crate::validate::continuum::tap`]).

use glam::DVec3;

use crate::mechanics::cases::LoadCase;
use crate::sim::material_surface::MaterialSurface;
use crate::sim::{Integrator, Tissue, Tool};
use crate::validate::transient::{self as dynamic_reference, Trajectory};

/// Most steps of one tap run.
const MAX_STEPS: usize = 400_000;

/// The magnitude of the force on the probe at every step `dt` of the tap (zero after it) on
/// `tissue` at rest, or `None` when the blow-up guard stopped the run; on `surface` where given,
/// else on the model's nodes.
pub fn run(
    tissue: Box<dyn Tissue>,
    integrator: Integrator,
    dt: f64,
    surface: Option<&MaterialSurface>,
) -> anyhow::Result<Option<Trajectory>> {
    let grid = tissue.grid();
    let clamp = LoadCase::bottom_clamp(&grid, "view");
    let mut sim = crate::sim::Simulation::with_tissue(tissue, integrator, dt, Some(&clamp));
    if let Some(s) = surface {
        let zeta = sim.tissue.damping().ratio();
        sim.set_surface_probe(Some(crate::sim::material_surface::SurfaceProbe::on(s, grid, zeta)));
    }
    let steps_for = |duration: f64| {
        let n = (duration / dt).round();
        anyhow::ensure!(
            n.is_finite() && n <= MAX_STEPS as f64,
            "{duration} s at dt = {dt} s is more than {MAX_STEPS} steps"
        );
        Ok(n.max(1.0) as usize)
    };
    let steps = steps_for(dynamic_reference::DURATION_S)?;
    let mut samples = Vec::with_capacity(steps + 1);
    samples.push(vec![0.0]);
    // Once the probe has let go nothing pushes on it: zero force from then on.
    let stepped = steps_for(dynamic_reference::TAP_DURATION_S)?.saturating_add(1).min(steps);
    for k in 1..=stepped {
        sim.tool = match dynamic_reference::tap_centre(k as f64 * dt) {
            Some(centre) => Tool::Probe { centre, radius: crate::validate::touch::PROBE_RADIUS_M },
            None => Tool::None,
        };
        if sim.step().is_err() {
            return Ok(None);
        }
        samples.push(vec![DVec3::from(sim.tool_force).length()]);
    }
    samples.resize(steps + 1, vec![0.0]);
    Ok(Some(Trajectory { dt, samples }))
}
