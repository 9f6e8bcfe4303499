//! Speed against accuracy: every model at every resolution and integrator on one footing.
//!
//! * Accuracy: the static answers of the three 10 N clamped cases (one per axis), sampled at the
//!   same physical points for every resolution (the 64 nodes of the 4^3 lattice, at multiples of
//!   L/3; trilinear interpolation of nodal displacements, which is the hex8 field), against the
//!   linear FEM on the finest grid [`REFERENCE_N`]^3. Errors are the paper's average and maximum
//!   nodal distance, in percent of the paper's spacing `h = L / 7` so that all resolutions share
//!   one unit. Dynamics settle to these static answers, so explicit and implicit points of one
//!   model and resolution share their error.
//! * Speed: median wall time of one step (symplectic Euler, or the prefactored backward Euler
//!   step), one thread; the explicit critical step `2 / omega_max` (Lanczos); time of the
//!   static answer of one case; bytes held by the state, the model and any factor.
//! * Models: the mass-spring lattices (the paper's axis springs, shear, hex) with the shipped
//!   calibrated 8^3 parameters carried to other resolutions by their stiffness scale (`k ~ E L^2 /
//!   (n^2 h)` per chain for axis and shear, `k ~ E h` per element for hex; damping with the node
//!   mass), and the linear and corotational FEM.
//!
//! [`point`]: one point and its files' names; [`measure`]: the measurement of one model;
//! [`pareto`]: the fronts; [`plot`]: the SVGs.

pub mod measure;
pub mod pareto;
pub mod plot;
pub mod point;

use std::time::Instant;

use super::timing::time_per_call;
use crate::mechanics::fem::FemModel;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::object::Object;
use crate::mechanics::sparse::SparseError;
pub use crate::response::single_mode::damped_explicit_limit;
use crate::sim::Model;
use crate::sim::material_surface::compliance::SurfaceContactScratch;
pub use crate::sim::shipped::msm_params_at;
use crate::validate::continuum::cache::ContinuumCache;
use crate::validate::probe::score::worst_validation_error;
pub use measure::{ERROR_UNIT_M, sample};
use measure::{MAX_COUPLED_IMPLICIT_N, ProbeFigures, cases, errors, model_points, sampled};
pub use pareto::{crossing, mark_pareto};
pub use point::{CHART_DAMPING_RATIO, CHARTED, ChartPoint, IMPLICIT_STEPS_S, NEWMARK_STEPS_S, integrator_chart_name};

/// Nodes per axis of the reference FEM.
pub const REFERENCE_N: usize = 40;

/// What to compute.
#[derive(Debug, Clone)]
pub struct ChartOptions {
    /// Objects (`A`, `B`).
    pub objects: Vec<Object>,
    /// Resolutions, nodes per axis.
    pub resolutions: Vec<usize>,
    /// Timing budget per measured step, s.
    pub timing_s: f64,
    /// Set (by another thread) to stop between points with an error.
    pub cancel: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
}

impl Default for ChartOptions {
    fn default() -> Self {
        Self { objects: Object::ALL.to_vec(), resolutions: vec![4, 8, 16, 32], timing_s: 0.15, cancel: None }
    }
}

impl ChartOptions {
    /// The default options for `objects` (trimmed, upper case; the presets A and B) at
    /// `resolutions` (at least one, each in 2..=32 nodes per axis).
    pub fn new(objects: Vec<String>, resolutions: Vec<usize>) -> anyhow::Result<Self> {
        let objects = objects
            .iter()
            .map(|o| {
                o.parse::<Object>()
                    .map_err(|_| anyhow::anyhow!("unknown object {o:?}: the chart covers the presets A and B"))
            })
            .collect::<anyhow::Result<Vec<Object>>>()?;
        if resolutions.is_empty() {
            anyhow::bail!("give at least one resolution");
        }
        for &n in &resolutions {
            if !(2..=32).contains(&n) {
                anyhow::bail!(
                    "resolution {n} is out of range: nodes per axis must be in 2..=32 (the reference FEM is 40^3)"
                );
            }
        }
        Ok(Self { objects, resolutions, ..Default::default() })
    }
}

/// The mass-proportional rate of `kind` for `material`: the chart's damping ratio at the
/// model's own 8^3 fundamental.
fn damping_rate(material: &Material, kind: Model) -> anyhow::Result<f64> {
    // The running tissue's own rate (its one home: `Tissue::set_damping_ratio`).
    Ok(kind.build(material, None, CHART_DAMPING_RATIO)?.damping().rate())
}

/// The FEM's dynamic reference of `material` at the chart's damping ratio, with a note on how
/// each transient converged.
fn dynamic_references(
    material: &Material,
    notes: &mut Vec<String>,
) -> anyhow::Result<crate::validate::dynamic::measure::References> {
    let refs = crate::validate::dynamic::measure::References::new(material, CHART_DAMPING_RATIO)?;
    for r in &refs.transients {
        let (h, change) = r.history.last().copied().unwrap_or((f64::NAN, f64::NAN));
        notes.push(format!(
            "object {}: the FEM's {} transient (Newmark average acceleration, damping ratio {}) converged at a step \
             of {} s: halving it changed the answer by {:.3} %",
            material.name,
            r.transient.name(),
            CHART_DAMPING_RATIO,
            crate::io::num(h),
            100.0 * change
        ));
    }
    Ok(refs)
}

/// The material's surface compliance as the probe's contact: its worst validation error against
/// the material, percent, and its time per 1 ms tick with the probe sliding (one contact solve).
fn surface_probe_figures(material: &Material, kept: &mut ContinuumCache) -> anyhow::Result<ProbeFigures> {
    let mut report = crate::sim::material_surface::stderr_report();
    let compliance =
        crate::sim::material_surface::load_or_compute(material, crate::io::cache_dir().as_deref(), &mut |e| {
            report.event(e)
        })?;
    let mut scratch = SurfaceContactScratch::default();
    let worst = worst_validation_error(material, kept, &mut |press| {
        crate::validate::probe::score::compliance_force_n(&compliance, &mut scratch, press)
    })?;
    // The 15 mm sphere 4 mm deep sliding along x at 40 mm/s.
    let (r, z) = (0.015, crate::mechanics::grid::CUBE_SIDE_M + 0.015 - 0.004);
    let mut x = 0.03;
    let mut failed = None;
    let tick = time_per_call(0.3, || {
        x = if x > 0.07 { 0.03 } else { x + 4e-5 };
        if let Err(e) = compliance.press([x, 0.05, z], r, &mut scratch) {
            failed = Some(e);
        }
    });
    if let Some(e) = failed {
        return Err(e.into());
    }
    Ok(ProbeFigures { nodes_pct: f64::NAN, surface_pct: 100.0 * worst, surface_tick_s: tick })
}

/// The worst validation error against the material of `model` at `grid` with its own
/// surface-node contact, percent (NaN for the axis lattice, which has no small-displacement
/// answer to a sideways touch).
fn node_probe_error(material: &Material, model: Model, grid: Grid, kept: &mut ContinuumCache) -> anyhow::Result<f64> {
    let params = match model {
        Model::Lattice(crate::mechanics::msm::Topology::Axis) => return Ok(f64::NAN),
        Model::Lattice(t) => Some(msm_params_at(material, t, &grid)?),
        Model::Fem(_) => None,
    };
    let (mut responder, _) = crate::validate::touch::score::responder(model, params, material, grid)?;
    let worst = worst_validation_error(material, kept, &mut |press| {
        crate::validate::probe::score::responder_force_n(&mut responder, press)
    })?;
    Ok(100.0 * worst)
}

/// Whether `e` is a sparse factor refused for its memory ([`SparseError::TooLarge`]).
fn over_factor_bound(e: &anyhow::Error) -> bool {
    e.chain().any(|c| matches!(c.downcast_ref::<SparseError>(), Some(SparseError::TooLarge { .. })))
}

/// Computes every point: for each object, model, resolution and integrator.
pub fn compute(opts: &ChartOptions, progress: &mut dyn FnMut(&str)) -> anyhow::Result<(Vec<ChartPoint>, Vec<String>)> {
    let mut points = Vec::new();
    let mut notes = Vec::new();
    let start = Instant::now();
    if opts.resolutions.iter().any(|&n| n > MAX_COUPLED_IMPLICIT_N) {
        notes.push(format!(
            "implicit steps of the shear and hex lattices and of the FEM are measured up to {MAX_COUPLED_IMPLICIT_N}^3 only: \
             their sparse factorisation's work grows like n^6 (about 1.2 GB and tens of seconds a factor at 32^3 on this \
             machine)"
        ));
    }
    for &object in &opts.objects {
        let material = object.material();
        progress(&format!("object {object}: reference FEM {REFERENCE_N}^3"));
        let ref_grid = Grid::new(REFERENCE_N)?;
        let reference: Vec<Vec<[f64; 3]>> = FemModel::new(ref_grid, &material)
            .solve_cases(&cases(&ref_grid, object.name()))?
            .into_iter()
            .map(|s| s.displacements)
            .collect();
        let reference = sampled(&ref_grid, &reference);
        let alpha = |kind: Model| damping_rate(&material, kind);
        progress(&format!("object {object}: the probe against the material (surface compliance)"));
        let mut kept = ContinuumCache::open(&material, crate::io::cache_dir().as_deref());
        let surface = surface_probe_figures(&material, &mut kept)?;
        for &n in &opts.resolutions {
            let grid = Grid::new(n)?;
            let (touch, dynamics) = if n == Grid::paper().n() {
                progress(&format!("object {object}: touch benchmark and dynamic reference FEM at {n}^3"));
                let refs = dynamic_references(&material, &mut notes)?;
                (Some(crate::validate::touch::score::Reference::new(&material, grid)?), Some(refs))
            } else {
                (None, None)
            };
            for kind in CHARTED {
                if opts.cancel.as_ref().is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed)) {
                    anyhow::bail!("the chart was cancelled");
                }
                progress(&format!(
                    "object {object}: {} at {n}^3 ({:.1} s)",
                    kind.chart_name(),
                    start.elapsed().as_secs_f64()
                ));
                let refs = (&reference[..], touch.as_ref(), dynamics.as_ref());
                let measured = node_probe_error(&material, kind, grid, &mut kept).and_then(|nodes_pct| {
                    let probe = ProbeFigures { nodes_pct, ..surface };
                    model_points(object, &material, kind, grid, opts.timing_s, refs, (alpha(kind)?, probe))
                });
                match measured {
                    Ok(mut pts) => points.append(&mut pts),
                    // A direct solve past the factor bound (none at the default resolutions since
                    // the nested dissection; in minimum degree the shear and hex lattices' static
                    // Newton at 32^3 was): the point is left out, and the chart says so.
                    Err(e) if over_factor_bound(&e) => {
                        notes.push(format!("object {object}: {} at {n}^3 is left out: {e:#}", kind.chart_name()));
                    }
                    Err(e) => return Err(e),
                }
            }
        }
        if opts.resolutions.contains(&32) {
            let g = Grid::new(32)?;
            let fine: Vec<Vec<[f64; 3]>> = FemModel::new(g, &material)
                .solve_cases(&cases(&g, object.name()))?
                .into_iter()
                .map(|s| s.displacements)
                .collect();
            let (avg, max) = errors(&sampled(&g, &fine), &reference);
            notes.push(format!(
                "object {object}: the 32^3 FEM differs from the {REFERENCE_N}^3 reference by {avg:.4} % (avg) and {max:.4} % (max) of h: the reference's own error is of that order or below"
            ));
        }
    }
    mark_pareto(&mut points);
    Ok((points, notes))
}
