//! What the chart measures of one model at one resolution: its static answers at common sample
//! points against the fine FEM, its explicit limit, the wall time of its explicit and implicit
//! steps, its touch score and its dynamic errors (the chart's module docs say how).

use crate::mechanics::object::Object;
use glam::DVec3;
use std::time::Instant;

use super::point::{ChartPoint, IMPLICIT_STEPS_S, NEWMARK_STEPS_S};
use crate::mechanics::cases::{CaseSolution, LoadCase};
use crate::mechanics::fem::FemModel;
use crate::mechanics::fem::clamped::ClampedSolver;
use crate::mechanics::fem::dynamics::{FemDynamics, Formulation};
use crate::mechanics::grid::{CUBE_SIDE_M, Grid};
use crate::mechanics::material::Material;
use crate::mechanics::msm::{Dynamics, MsmModel, MsmParams, Topology, statics};
use crate::response::single_mode::damped_explicit_limit;
use crate::sim::shipped::msm_params_at;
use crate::sim::{Integrator, Model};
use crate::study::timing::{time_fallible, time_per_call};

/// Lanczos steps for the chart's `omega_max`, at most (the stability study allows more).
const CHART_LANCZOS_ITERATIONS: usize = 300;
/// Largest resolution at which the implicit step of a coupled model (shear or hex lattice, FEM)
/// is measured: its sparse factorisation's work grows like `n^6` (about 1.2 GB and tens of seconds
/// a factor at 32^3 in the grid's nested dissection, on this 2-core machine; the lattices'
/// linearised backward Euler factorises every step). The axis lattice's rest tangent splits into
/// chains and is measured at any size.
pub const MAX_COUPLED_IMPLICIT_N: usize = 24;
/// The length errors are expressed in (the paper's 8^3 spacing), metres.
pub const ERROR_UNIT_M: f64 = CUBE_SIDE_M / 7.0;

/// What the points of one model and resolution share.
struct PointBase {
    object: Object,
    model: Model,
    n: usize,
    static_s: f64,
    avg: f64,
    max: f64,
    force: f64,
    probe: ProbeFigures,
}

/// The probe force errors against the material of one model at one resolution, percent, and
/// what the surface compliance costs per tick, s.
#[derive(Debug, Clone, Copy)]
pub(super) struct ProbeFigures {
    /// With the model's surface-node contact.
    pub nodes_pct: f64,
    /// With the material's surface compliance.
    pub surface_pct: f64,
    /// The surface compliance's time per 1 ms tick, sliding.
    pub surface_tick_s: f64,
}

/// How one point steps: its integrator, wall time per step, explicit limit, step and memory.
struct Stepping {
    integrator: Integrator,
    step_s: f64,
    dt_max_s: f64,
    dt_s: f64,
    memory_bytes: usize,
}

impl PointBase {
    fn point(&self, st: &Stepping, dynamic: Option<&crate::validate::dynamic::measure::DynamicReport>) -> ChartPoint {
        let pct = |f: fn(&crate::validate::dynamic::measure::DynamicReport) -> f64| {
            dynamic.map_or(f64::NAN, |d| 100.0 * f(d))
        };
        ChartPoint {
            object: self.object,
            model: self.model,
            n: self.n,
            integrator: st.integrator,
            step_s: st.step_s,
            dt_max_s: st.dt_max_s,
            dt_s: st.dt_s,
            cost_per_sim_s: st.step_s / st.dt_s,
            static_s: self.static_s,
            memory_bytes: st.memory_bytes,
            avg_err_pct: self.avg,
            max_err_pct: self.max,
            force_err_pct: self.force,
            probe_err_pct: self.probe.nodes_pct,
            surface_probe_err_pct: self.probe.surface_pct,
            surface_probe_tick_s: self.probe.surface_tick_s,
            dyn_err_pct: pct(|d| d.trajectory_error),
            tap_err_pct: pct(|d| d.probe_tap_error),
            period_err_pct: pct(|d| d.period_error),
            damping_err_pct: pct(|d| d.damping_error),
            pareto: false,
            pareto_dynamic: false,
        }
    }
}

/// The chart's points of one model and resolution: an explicit point at 0.9 of `dt_max`, an
/// implicit point at each of [`IMPLICIT_STEPS_S`] and a Newmark point at each of
/// [`NEWMARK_STEPS_S`] (when the implicit step was timed: the same factor and solve), each with
/// its dynamic measurement where `dynamics` is given (the viewer's 8^3 scene).
fn points_of(
    shared: &PointBase,
    explicit: (f64, f64, usize),
    implicit: Option<(f64, usize)>,
    dynamics: Option<(&crate::validate::dynamic::measure::References, crate::sim::Model, Option<MsmParams>)>,
) -> anyhow::Result<Vec<ChartPoint>> {
    use crate::validate::dynamic::measure::{Configuration, measure};
    let (step_s, dt_max_s, memory_bytes) = explicit;
    let mut steppings =
        vec![Stepping { integrator: Integrator::Symplectic, step_s, dt_max_s, dt_s: 0.9 * dt_max_s, memory_bytes }];
    if let Some((step_s, memory_bytes)) = implicit {
        steppings.extend(IMPLICIT_STEPS_S.iter().map(|&dt_s| Stepping {
            integrator: Integrator::Prefactored,
            step_s,
            dt_max_s: f64::INFINITY,
            dt_s,
            memory_bytes,
        }));
        // Newmark's trapezoidal rule, prefactored like it: one solve per step, no numerical damping.
        steppings.extend(NEWMARK_STEPS_S.iter().map(|&dt_s| Stepping {
            integrator: Integrator::Newmark,
            step_s,
            dt_max_s: f64::INFINITY,
            dt_s,
            memory_bytes,
        }));
    }
    steppings
        .iter()
        .map(|st| {
            let report = match dynamics {
                Some((refs, model, params)) => {
                    Some(measure(refs, Configuration { model, params, integrator: st.integrator, dt: st.dt_s })?)
                }
                None => None,
            };
            Ok(shared.point(st, report.as_ref()))
        })
        .collect()
}

/// The 64 common sample points: the nodes of the 4^3 lattice (as [`Grid::positions`] of a 4^3 grid).
fn sample_points() -> Vec<[f64; 3]> {
    let h = CUBE_SIDE_M / 3.0;
    (0..64).map(|p| [p % 4, (p / 4) % 4, p / 16].map(|c| c as f64 * h)).collect()
}

/// Trilinear interpolation of nodal displacements `u` on `grid` at point `p`.
pub fn sample(grid: &Grid, u: &[[f64; 3]], p: [f64; 3]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (q, w) in grid.corners(p) {
        for c in 0..3 {
            out[c] += w * u[q][c];
        }
    }
    out
}

/// The three 10 N clamped cases on `grid`.
pub(super) fn cases(grid: &Grid, object: &str) -> Vec<LoadCase> {
    (1..=3).map(|a| LoadCase::clamped(grid, object, a, 10.0)).collect()
}

/// Sampled displacements of each case.
pub(super) fn sampled(grid: &Grid, answers: &[Vec<[f64; 3]>]) -> Vec<Vec<[f64; 3]>> {
    let pts = sample_points();
    answers.iter().map(|u| pts.iter().map(|&p| sample(grid, u, p)).collect()).collect()
}

/// Average and maximum distance between sampled fields, % of [`ERROR_UNIT_M`].
pub(super) fn errors(model: &[Vec<[f64; 3]>], reference: &[Vec<[f64; 3]>]) -> (f64, f64) {
    let d: Vec<f64> = model
        .iter()
        .zip(reference)
        .flat_map(|(m, r)| m.iter().zip(r).map(|(a, b)| DVec3::from(*a).distance(DVec3::from(*b))))
        .collect();
    let avg = d.iter().sum::<f64>() / d.len() as f64;
    let max = d.iter().copied().fold(0.0, f64::max);
    (100.0 * avg / ERROR_UNIT_M, 100.0 * max / ERROR_UNIT_M)
}

/// Bytes of a mass-spring state and model: positions, velocities, forces (4 x 3 arrays), the
/// fixed mask, and per spring slot its stiffness, validity and pair force.
fn msm_memory(model: &MsmModel) -> usize {
    let nn = model.grid.num_nodes();
    let slots: usize = model.families.iter().map(|f| f.stiffness.len()).sum();
    nn * (12 + 1) * 8 + slots * (8 + 1 + 24)
}

/// The references a model is scored against: the fine FEM's sampled static answers, and at the
/// viewer's 8^3 the touch benchmark and the dynamic reference.
pub(super) type References<'a> = (
    &'a [Vec<[f64; 3]>],
    Option<&'a crate::validate::touch::score::Reference>,
    Option<&'a crate::validate::dynamic::measure::References>,
);

/// What one model measured at one resolution, before it becomes chart points.
struct Measured {
    /// A lattice's parameters (the dynamic measurement runs them).
    params: Option<MsmParams>,
    /// Static answers of the chart's cases.
    answers: Vec<Vec<[f64; 3]>>,
    /// Wall time of one static answer, s.
    static_s: f64,
    /// The explicit limit, s.
    dt_max: f64,
    /// Explicit step: wall time, s, and memory, bytes.
    explicit: (f64, usize),
    /// Prefactored step, where timed: wall time, s, and memory, bytes.
    implicit: Option<(f64, usize)>,
    /// Touch force error, percent (NaN off the viewer's resolution).
    force: f64,
}

/// The chart's points of `model` of `material` at `grid`, damped at the rate `alpha`, with its probe
/// force errors against the material `probe`.
pub(super) fn model_points(
    object: Object,
    material: &Material,
    model: Model,
    grid: Grid,
    timing_s: f64,
    (reference, touch, dynamics): References<'_>,
    (alpha, probe): (f64, ProbeFigures),
) -> anyhow::Result<Vec<ChartPoint>> {
    let m = match model {
        Model::Lattice(t) => measure_msm(object.name(), material, t, grid, timing_s, touch, alpha)?,
        Model::Fem(f) => measure_fem(object.name(), material, f, grid, timing_s, touch.is_some(), alpha)?,
    };
    let (avg, max) = errors(&sampled(&grid, &m.answers), reference);
    let shared = PointBase { object, model, n: grid.n(), static_s: m.static_s, avg, max, force: m.force, probe };
    let dynamics = dynamics.map(|r| (r, model, m.params));
    points_of(&shared, (m.explicit.0, m.dt_max, m.explicit.1), m.implicit, dynamics)
}

fn measure_msm(
    object: &str,
    material: &Material,
    topology: Topology,
    grid: Grid,
    timing_s: f64,
    touch: Option<&crate::validate::touch::score::Reference>,
    alpha: f64,
) -> anyhow::Result<Measured> {
    let params = msm_params_at(material, topology, &grid)?;
    let mut model = MsmModel::new(grid, params, material.density)?;
    model.set_mass_damping(alpha);
    let cs = cases(&grid, object);
    let t = Instant::now();
    let chord = statics::NewtonOptions { chord: true, ..Default::default() };
    let answers = cs
        .iter()
        .map(|c| match statics::closed_form_axis(&model, c) {
            Some(u) => Ok(u),
            None => statics::solve_newton(&model, c, chord).map(|r| r.0),
        })
        .collect::<Result<Vec<_>, _>>()?;
    let static_s = t.elapsed().as_secs_f64() / cs.len() as f64;
    let fixed = cs[0].fixed_nodes();
    let omega = crate::study::stability::msm_omega_max(&model, &fixed, CHART_LANCZOS_ITERATIONS);
    let dt_max = damped_explicit_limit(omega, alpha);
    let mut stepper = Dynamics::new(&model);
    stepper.apply_case(&cs[0]);
    let explicit = time_per_call(timing_s, || stepper.step_symplectic(&model, 0.5 * dt_max));
    let base = msm_memory(&model);
    let mut implicit = None;
    if topology == Topology::Axis || grid.n() <= MAX_COUPLED_IMPLICIT_N {
        let mut stepper = Dynamics::new(&model);
        stepper.apply_case(&cs[0]);
        stepper.step_prefactored(&model, 1e-3)?;
        let t = time_fallible(timing_s, || stepper.step_prefactored(&model, 1e-3))?;
        implicit = Some((t, base + stepper.prefactored_memory_bytes()));
    }
    let force = match touch {
        Some(reference) => {
            100.0
                * crate::validate::touch::score::evaluate(reference, material, Model::Lattice(topology), Some(params))?
                    .worst_force_error
        }
        None => f64::NAN,
    };
    Ok(Measured { params: Some(params), answers, static_s, dt_max, explicit: (explicit, base), implicit, force })
}

fn measure_fem(
    object: &str,
    material: &Material,
    formulation: Formulation,
    grid: Grid,
    timing_s: f64,
    touch: bool,
    alpha: f64,
) -> anyhow::Result<Measured> {
    let model = FemModel::new(grid, material);
    let cs = cases(&grid, object);
    let mut fem = FemDynamics::new(model.clone(), material.density, formulation, alpha);
    fem.apply_case(&cs[0]);
    let t = Instant::now();
    let answers: Vec<Vec<[f64; 3]>> = match formulation {
        Formulation::Linear => model.solve_cases(&cs)?.into_iter().map(|s: CaseSolution| s.displacements).collect(),
        Formulation::Corotational => {
            let mut solver = ClampedSolver::new(grid, &material.stiffness)?;
            cs.iter().map(|c| corotational_static(&mut fem, &mut solver, c)).collect::<Result<_, _>>()?
        }
    };
    let static_s = t.elapsed().as_secs_f64() / cs.len() as f64;
    fem.apply_case(&cs[0]);
    let omega = crate::study::stability::fem_omega_max(&fem, CHART_LANCZOS_ITERATIONS);
    let dt_max = damped_explicit_limit(omega, alpha);
    let explicit = time_per_call(timing_s, || fem.step_symplectic(0.5 * dt_max));
    let without = fem.memory_bytes() - fem.factor_memory_bytes();
    let mut implicit = None;
    if grid.n() <= MAX_COUPLED_IMPLICIT_N {
        fem.step_prefactored(1e-3)?;
        let t = time_fallible(timing_s, || fem.step_prefactored(1e-3))?;
        implicit = Some((t, fem.memory_bytes()));
    }
    // The touch reference is this FEM on this mesh: it scores itself exactly.
    let force = if touch { 0.0 } else { f64::NAN };
    Ok(Measured { params: None, answers, static_s, dt_max, explicit: (explicit, without), implicit, force })
}

/// Static answer of the corotational FEM of a clamped case: quasi-Newton with the linear
/// stiffness (the mirror-symmetric clamped solver), `u += K^-1 (f_ext + f_int(u))`, to `1e-10`
/// relative. Leaves `fem` at rest.
fn corotational_static(
    fem: &mut FemDynamics,
    solver: &mut ClampedSolver,
    case: &LoadCase,
) -> anyhow::Result<Vec<[f64; 3]>> {
    fem.apply_case(case);
    let rest = fem.rest().to_vec();
    fem.x.copy_from_slice(&rest);
    let mut residual = case.clone();
    let mut u = vec![0.0; rest.len()];
    for _ in 0..100 {
        let f = fem.forces();
        for (d, r) in residual.load.iter_mut().enumerate() {
            *r = if case.fixed[d] { 0.0 } else { f[d] };
        }
        let du = solver.solve_case(&fem.model, &residual)?.displacements;
        let mut change = 0.0f64;
        for (p, d) in du.iter().enumerate() {
            for c in 0..3 {
                fem.x[3 * p + c] += d[c];
                change = change.max(d[c].abs());
            }
        }
        fem.displacement(&mut u);
        let scale = u.iter().map(|v| v.abs()).fold(0.0, f64::max);
        if change <= 1e-10 * scale {
            fem.x.copy_from_slice(&rest);
            return Ok(u.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect());
        }
    }
    anyhow::bail!("corotational static solve of {} did not converge", case.id)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sample_points_are_the_4_cubed_nodes() {
        assert_eq!(sample_points(), Grid::new(4).unwrap().positions());
    }
}
