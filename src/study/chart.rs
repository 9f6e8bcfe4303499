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
//!   step), one thread; the explicit critical step `2 / omega_max` (power iteration); time of the
//!   static answer of one case; bytes held by the state, the model and any factor.
//! * Models: the mass-spring lattices (the paper's axis springs, shear, hex) with the shipped
//!   calibrated 8^3 parameters carried to other resolutions by their stiffness scale (`k ~ E L^2 /
//!   (n^2 h)` per chain for axis and shear, `k ~ E h` per element for hex; damping with the node
//!   mass), and the linear and corotational FEM.

use std::time::Instant;

use crate::study::bench::{time_fallible, time_per_call};
use crate::mechanics::cases::{CaseSolution, LoadCase};
use crate::mechanics::fem::FemModel;
use crate::mechanics::fem::clamped::ClampedSolver;
use crate::mechanics::fem::dynamics::{FemDynamics, Formulation};
use crate::mechanics::grid::{CUBE_SIDE_M, Grid};
use crate::mechanics::material::Material;
use crate::mechanics::msm::{Dynamics, MsmModel, MsmParams, Topology, statics};
use crate::sim::shipped::tissue_params;

/// Nodes per axis of the reference FEM.
pub const REFERENCE_N: usize = 40;
/// Power iterations for the chart's `omega_max` (the stability study uses more): the Rayleigh
/// quotient approaches it from below, within a few percent here.
const CHART_POWER_ITERATIONS: usize = 300;
/// Largest resolution at which the implicit step of a coupled model (shear or hex lattice, FEM)
/// is measured: its sparse factor grows like `n^6` (several GB and minutes at 32^3 on this
/// 2-core machine). The axis lattice's rest tangent splits into chains and is measured at any size.
pub const MAX_COUPLED_IMPLICIT_N: usize = 24;
/// The length errors are expressed in (the paper's 8^3 spacing), metres.
pub const ERROR_UNIT_M: f64 = CUBE_SIDE_M / 7.0;

/// A model of the tissue; in files, its [`ModelKind::name`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelKind {
    /// Mass-spring lattice of a topology.
    Msm(Topology),
    /// Finite elements.
    Fem(Formulation),
}

impl ModelKind {
    /// All models, cheapest first.
    pub const ALL: [ModelKind; 5] = [
        ModelKind::Msm(Topology::Axis),
        ModelKind::Msm(Topology::Shear),
        ModelKind::Msm(Topology::Hex),
        ModelKind::Fem(Formulation::Linear),
        ModelKind::Fem(Formulation::Corotational),
    ];

    /// The models charted: every one but the paper's axis lattice, whose only calibration is on
    /// the paper's cases (the chart's static cases) and which the touch benchmark cannot score
    /// (no shear stiffness at rest), so no held-out figure exists for it.
    pub const CHARTED: [ModelKind; 4] = [
        ModelKind::Msm(Topology::Shear),
        ModelKind::Msm(Topology::Hex),
        ModelKind::Fem(Formulation::Linear),
        ModelKind::Fem(Formulation::Corotational),
    ];

    /// Name in the chart and the CSV, e.g. `msm-hex`.
    pub fn name(self) -> String {
        match self {
            ModelKind::Msm(t) => format!("msm-{}", t.name()),
            ModelKind::Fem(f) => format!("fem-{}", f.name()),
        }
    }

    /// The model of a [`ModelKind::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

impl std::fmt::Display for ModelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(&self.name())
    }
}

/// Compares with a [`ModelKind::name`].
impl serde::Serialize for ModelKind {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(&self.name())
    }
}

impl<'de> serde::Deserialize<'de> for ModelKind {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let name = <String as serde::Deserialize>::deserialize(deserializer)?;
        Self::from_name(&name).ok_or_else(|| {
            let known: Vec<String> = Self::ALL.iter().map(|k| k.name()).collect();
            serde::de::Error::custom(format!("unknown model {name:?} (expected one of {})", known.join(", ")))
        })
    }
}

/// How a chart point steps in time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ChartIntegrator {
    /// Symplectic Euler.
    Explicit,
    /// Prefactored backward Euler.
    Implicit,
}

impl ChartIntegrator {
    /// The lower-case name used in the chart and the CSV.
    pub fn name(self) -> &'static str {
        match self {
            ChartIntegrator::Explicit => "explicit",
            ChartIntegrator::Implicit => "implicit",
        }
    }
}

impl std::fmt::Display for ChartIntegrator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.name())
    }
}

/// Compares with a [`ChartIntegrator::name`].
/// One point of the chart.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChartPoint {
    /// Object label.
    pub object: String,
    /// The model (`msm-axis`, ..., `fem-corotational` in files).
    pub model: ModelKind,
    /// Nodes per axis.
    pub n: usize,
    /// `explicit` (symplectic Euler) or `implicit` (prefactored backward Euler).
    pub integrator: ChartIntegrator,
    /// Wall time of one step, s.
    pub step_s: f64,
    /// Largest stable explicit step ([`damped_explicit_limit`] of `omega_max` and the damping rate), s;
    /// infinite for implicit.
    pub dt_max_s: f64,
    /// The time step of the point, s: 0.9 of `dt_max_s` (explicit), or one of
    /// [`IMPLICIT_STEPS_S`] (implicit).
    pub dt_s: f64,
    /// Wall time per simulated second, `step_s / dt_s`, s.
    pub cost_per_sim_s: f64,
    /// Wall time of the static answer of one case, s.
    pub static_s: f64,
    /// Bytes held by state, model and factor.
    pub memory_bytes: usize,
    /// Average nodal error, % of the paper's h.
    pub avg_err_pct: f64,
    /// Maximum nodal error, % of the paper's h.
    pub max_err_pct: f64,
    /// Worst touch force error on the touch benchmark's validation set, percent, against the
    /// FEM on the same mesh (0 for the FEM itself). Scored at the viewer's resolution (the
    /// paper's 8^3 grid, the scene a user touches) only; NaN at other resolutions, where a point
    /// load's answer depends on the mesh and no common touch reference exists.
    pub force_err_pct: f64,
    /// Dynamic error: the worst trajectory error against the FEM's converged transients (the
    /// viewer scene's top-face step load and its release, first 0.2 s), percent; model and
    /// integrator together. At the viewer's 8^3 only (NaN elsewhere), as the touch scores.
    pub dyn_err_pct: f64,
    /// The probe tap's force error (run in the viewer's simulation, its contact and readout)
    /// against the FEM's converged tap, percent (8^3 only).
    pub tap_err_pct: f64,
    /// The integrator's period error on the model's own fundamental, measured by time stepping,
    /// percent (8^3 only).
    pub period_err_pct: f64,
    /// The integrator's damping ratio error on the model's own fundamental, percent of critical
    /// (8^3 only).
    pub damping_err_pct: f64,
    /// On the Pareto front of (cost per simulated second, average static error) for its object.
    pub pareto: bool,
    /// On the Pareto front of (cost per simulated second, dynamic error) for its object.
    pub pareto_dynamic: bool,
}

/// The steps of the implicit points, s: from 0.1 ms to one frame at 60 Hz.
pub const IMPLICIT_STEPS_S: [f64; 6] = [1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 1.0 / 60.0];
/// The damping ratio of every chart point (mass-proportional at each model's fundamental).
pub const CHART_DAMPING_RATIO: f64 = crate::response::damping::DEFAULT_DAMPING_RATIO;

impl ChartPoint {
    /// Wall time to advance `1 / rate_hz` of simulated time: as many steps of `dt_s` as the
    /// tick needs (at least one).
    pub fn tick_s(&self, rate_hz: f64) -> f64 {
        self.substeps(rate_hz) * self.step_s
    }

    /// Steps of `dt_s` per tick at `rate_hz`.
    pub fn substeps(&self, rate_hz: f64) -> f64 {
        (1.0 / rate_hz / self.dt_s * (1.0 - 1e-9)).ceil().max(1.0)
    }

    /// Whether its step fits in a tick at `rate_hz` (an implicit step longer than the tick
    /// cannot run at that rate).
    pub fn fits_rate(&self, rate_hz: f64) -> bool {
        self.dt_s <= 1.0 / rate_hz * (1.0 + 1e-9)
    }
}

/// What to compute.
#[derive(Debug, Clone)]
pub struct ChartOptions {
    /// Objects (`A`, `B`).
    pub objects: Vec<String>,
    /// Resolutions, nodes per axis.
    pub resolutions: Vec<usize>,
    /// Timing budget per measured step, s.
    pub timing_s: f64,
    /// Set (by another thread) to stop between points with an error.
    pub cancel: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
}

impl Default for ChartOptions {
    fn default() -> Self {
        Self { objects: vec!["A".into(), "B".into()], resolutions: vec![4, 8, 16, 32], timing_s: 0.15, cancel: None }
    }
}

impl ChartOptions {
    /// The default options for `objects` (trimmed, upper case; the presets A and B) at
    /// `resolutions` (at least one, each in 2..=32 nodes per axis).
    pub fn new(objects: Vec<String>, resolutions: Vec<usize>) -> anyhow::Result<Self> {
        let objects: Vec<String> = objects.iter().map(|o| o.trim().to_ascii_uppercase()).collect();
        for o in &objects {
            if Material::preset(o).is_none() {
                anyhow::bail!("unknown object {o:?}: the chart covers the presets A and B");
            }
        }
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

/// What the points of one model and resolution share.
struct PointBase<'a> {
    object: &'a str,
    model: ModelKind,
    n: usize,
    static_s: f64,
    avg: f64,
    max: f64,
    force: f64,
}

/// How one point steps: its integrator, wall time per step, explicit limit, step and memory.
struct Stepping {
    integrator: ChartIntegrator,
    step_s: f64,
    dt_max_s: f64,
    dt_s: f64,
    memory_bytes: usize,
}

impl PointBase<'_> {
    fn point(&self, st: &Stepping, dynamic: Option<&crate::validate::dynamic_measure::DynamicReport>) -> ChartPoint {
        let pct = |f: fn(&crate::validate::dynamic_measure::DynamicReport) -> f64| dynamic.map_or(f64::NAN, |d| 100.0 * f(d));
        ChartPoint {
            object: self.object.into(),
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
            dyn_err_pct: pct(|d| d.trajectory_error),
            tap_err_pct: pct(|d| d.probe_tap_error),
            period_err_pct: pct(|d| d.period_error),
            damping_err_pct: pct(|d| d.damping_error),
            pareto: false,
            pareto_dynamic: false,
        }
    }
}

/// The chart's points of one model and resolution: an explicit point at 0.9 of `dt_max` and an
/// implicit point at each of [`IMPLICIT_STEPS_S`] (when the implicit step was timed), each with
/// its dynamic measurement where `dynamics` is given (the viewer's 8^3 scene).
fn points_of(
    shared: &PointBase<'_>,
    explicit: (f64, f64, usize),
    implicit: Option<(f64, usize)>,
    dynamics: Option<(&crate::validate::dynamic_measure::References, crate::sim::ModelChoice, Option<MsmParams>)>,
) -> anyhow::Result<Vec<ChartPoint>> {
    use crate::validate::dynamic_measure::{Configuration, measure};
    use crate::sim::Integrator;
    let (step_s, dt_max_s, memory_bytes) = explicit;
    let mut steppings =
        vec![Stepping { integrator: ChartIntegrator::Explicit, step_s, dt_max_s, dt_s: 0.9 * dt_max_s, memory_bytes }];
    if let Some((step_s, memory_bytes)) = implicit {
        steppings.extend(IMPLICIT_STEPS_S.iter().map(|&dt_s| Stepping {
            integrator: ChartIntegrator::Implicit,
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
                    let integrator = match st.integrator {
                        ChartIntegrator::Explicit => Integrator::Symplectic,
                        ChartIntegrator::Implicit => Integrator::Prefactored,
                    };
                    Some(measure(refs, Configuration { model, params, integrator, dt: st.dt_s })?)
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
    let n = grid.n();
    let h = grid.h();
    let mut cell = [0usize; 3];
    let mut t = [0.0; 3];
    for a in 0..3 {
        let s = (p[a] / h).clamp(0.0, (n - 1) as f64);
        cell[a] = (s.floor() as usize).min(n - 2);
        t[a] = s - cell[a] as f64;
    }
    let mut out = [0.0; 3];
    for corner in 0..8 {
        let o = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
        let w: f64 = (0..3).map(|a| if o[a] == 1 { t[a] } else { 1.0 - t[a] }).product();
        if w != 0.0 {
            let q = grid.node(cell[0] + o[0], cell[1] + o[1], cell[2] + o[2]);
            for c in 0..3 {
                out[c] += w * u[q][c];
            }
        }
    }
    out
}

/// The three 10 N clamped cases on `grid`.
fn cases(grid: &Grid, object: &str) -> Vec<LoadCase> {
    (1..=3).map(|a| LoadCase::clamped(grid, object, a, 10.0)).collect()
}

/// Sampled displacements of each case.
fn sampled(grid: &Grid, answers: &[Vec<[f64; 3]>]) -> Vec<Vec<[f64; 3]>> {
    let pts = sample_points();
    answers.iter().map(|u| pts.iter().map(|&p| sample(grid, u, p)).collect()).collect()
}

/// Average and maximum distance between sampled fields, % of [`ERROR_UNIT_M`].
fn errors(model: &[Vec<[f64; 3]>], reference: &[Vec<[f64; 3]>]) -> (f64, f64) {
    let d: Vec<f64> = model
        .iter()
        .zip(reference)
        .flat_map(|(m, r)| {
            m.iter().zip(r).map(|(a, b)| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt())
        })
        .collect();
    let avg = d.iter().sum::<f64>() / d.len() as f64;
    let max = d.iter().copied().fold(0.0, f64::max);
    (100.0 * avg / ERROR_UNIT_M, 100.0 * max / ERROR_UNIT_M)
}

/// The shipped 8^3 parameters carried to `grid` (see the module docs).
pub fn msm_params_at(material: &Material, topology: Topology, grid: &Grid) -> anyhow::Result<MsmParams> {
    let p = tissue_params(material, topology)?;
    let paper = Grid::paper();
    let chain = |g: &Grid| CUBE_SIDE_M * CUBE_SIDE_M / ((g.n() * g.n()) as f64 * g.h());
    let s = if topology == Topology::Hex { grid.h() / paper.h() } else { chain(grid) / chain(&paper) };
    let mass = (paper.num_nodes() as f64) / grid.num_nodes() as f64;
    let sc = |v: Option<f64>| v.map(|v| v * s);
    Ok(MsmParams {
        k1: p.k1 * s,
        k2: p.k2 * s,
        k3: p.k3 * s,
        d: p.d * mass,
        c12: sc(p.c12),
        c13: sc(p.c13),
        c23: sc(p.c23),
        b: sc(p.b),
    })
}

/// Bytes of a mass-spring state and model: positions, velocities, forces (4 x 3 arrays), the
/// fixed mask, and per spring slot its stiffness, validity and pair force.
fn msm_memory(model: &MsmModel) -> usize {
    let nn = model.grid.num_nodes();
    let slots: usize = model.families.iter().map(|f| f.stiffness.len()).sum();
    nn * (12 + 1) * 8 + slots * (8 + 1 + 24)
}

fn msm_points(
    object: &str,
    material: &Material,
    topology: Topology,
    grid: Grid,
    opts: &ChartOptions,
    (reference, touch, dynamics): (
        &[Vec<[f64; 3]>],
        Option<&crate::validate::touch_score::Reference>,
        Option<&crate::validate::dynamic_measure::References>,
    ),
    alpha: f64,
) -> anyhow::Result<Vec<ChartPoint>> {
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
    let (avg, max) = errors(&sampled(&grid, &answers), reference);
    let fixed = cs[0].fixed_nodes();
    let omega = crate::study::stability::msm_omega_max(&model, &fixed, CHART_POWER_ITERATIONS);
    let dt_max = damped_explicit_limit(omega, alpha);
    let mut stepper = Dynamics::new(&model);
    stepper.apply_case(&cs[0]);
    let explicit = time_per_call(opts.timing_s, || stepper.step_symplectic(&model, 0.5 * dt_max));
    let base = msm_memory(&model);
    let mut implicit = None;
    if topology == Topology::Axis || grid.n() <= MAX_COUPLED_IMPLICIT_N {
        let mut stepper = Dynamics::new(&model);
        stepper.apply_case(&cs[0]);
        stepper.step_prefactored(&model, 1e-3)?;
        let t = time_fallible(opts.timing_s, || stepper.step_prefactored(&model, 1e-3))?;
        implicit = Some((t, base + stepper.prefactored_memory_bytes()));
    }
    let force = match touch {
        Some(reference) => {
            100.0
                * crate::validate::touch_score::evaluate(reference, material, &crate::validate::touch_score::ModelUnderTest::Lattice(params))?
                    .worst_force_error
        }
        None => f64::NAN,
    };
    let shared = PointBase { object, model: ModelKind::Msm(topology), n: grid.n(), static_s, avg, max, force };
    let dynamics = dynamics.map(|r| (r, crate::sim::ModelChoice::Lattice(topology), Some(params)));
    points_of(&shared, (explicit, dt_max, base), implicit, dynamics)
}

fn fem_points(
    object: &str,
    material: &Material,
    formulation: Formulation,
    grid: Grid,
    opts: &ChartOptions,
    (reference, touch, dynamics): (
        &[Vec<[f64; 3]>],
        Option<&crate::validate::touch_score::Reference>,
        Option<&crate::validate::dynamic_measure::References>,
    ),
    alpha: f64,
) -> anyhow::Result<Vec<ChartPoint>> {
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
    let (avg, max) = errors(&sampled(&grid, &answers), reference);
    fem.apply_case(&cs[0]);
    let omega = crate::study::stability::fem_omega_max(&fem, CHART_POWER_ITERATIONS);
    let dt_max = damped_explicit_limit(omega, alpha);
    let explicit = time_per_call(opts.timing_s, || fem.step_symplectic(0.5 * dt_max));
    let without = fem.memory_bytes() - fem.factor_memory_bytes();
    let mut implicit = None;
    if grid.n() <= MAX_COUPLED_IMPLICIT_N {
        fem.step_prefactored(1e-3)?;
        let t = time_fallible(opts.timing_s, || fem.step_prefactored(1e-3))?;
        implicit = Some((t, fem.memory_bytes()));
    }
    // The touch reference is this FEM on this mesh: it scores itself exactly.
    let force = if touch.is_some() { 0.0 } else { f64::NAN };
    let shared = PointBase { object, model: ModelKind::Fem(formulation), n: grid.n(), static_s, avg, max, force };
    let dynamics = dynamics.map(|r| (r, crate::sim::ModelChoice::Fem(formulation), None));
    points_of(&shared, (explicit, dt_max, without), implicit, dynamics)
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

/// The stability limit of symplectic Euler on a mode `omega` with damping rate `gamma` (1/s)
/// treated explicitly: the one-step matrix has determinant `1 - h gamma` and trace
/// `2 - h gamma - h^2 omega^2`, stable while `h^2 omega^2 + 2 h gamma < 4`, i.e.
/// `h < 4 / (gamma + sqrt(gamma^2 + 4 omega^2))` (`2 / omega` undamped).
pub fn damped_explicit_limit(omega: f64, gamma: f64) -> f64 {
    4.0 / (gamma + (gamma * gamma + 4.0 * omega * omega).sqrt())
}

/// Marks the Pareto fronts of (cost per simulated second, average static error) and (cost per
/// simulated second, dynamic error) per object; a point without a dynamic score is on no
/// dynamic front.
pub fn mark_pareto(points: &mut [ChartPoint]) {
    let snapshot = points.to_vec();
    let dominated = |p: &ChartPoint, err: fn(&ChartPoint) -> f64| {
        snapshot.iter().any(|q| {
            q.object == p.object
                && err(q).is_finite()
                && q.cost_per_sim_s <= p.cost_per_sim_s
                && err(q) <= err(p)
                && (q.cost_per_sim_s < p.cost_per_sim_s || err(q) < err(p))
        })
    };
    for p in points.iter_mut() {
        p.pareto = !dominated(p, |q| q.avg_err_pct);
        p.pareto_dynamic = p.dyn_err_pct.is_finite() && !dominated(p, |q| q.dyn_err_pct);
    }
}

/// Where a series of points (ascending steps) crosses `threshold` percent of `err`: the step by
/// log-log interpolation between the last step below and the first above, or why not.
pub fn crossing(points: &[&ChartPoint], err: fn(&ChartPoint) -> f64, threshold: f64) -> String {
    let mut sorted: Vec<&&ChartPoint> = points.iter().filter(|p| err(p).is_finite()).collect();
    sorted.sort_by(|a, b| a.dt_s.total_cmp(&b.dt_s));
    let Some(first) = sorted.first() else { return "not measured".into() };
    if err(first) > threshold {
        return format!("above {threshold} % already at {} ms ({:.2} %)", fmt_ms(first.dt_s), err(first));
    }
    for w in sorted.windows(2) {
        let (a, b) = (w[0], w[1]);
        if err(a) <= threshold && err(b) > threshold {
            let t = (threshold.ln() - err(a).max(1e-12).ln()) / (err(b).ln() - err(a).max(1e-12).ln());
            let dt = (a.dt_s.ln() + t * (b.dt_s.ln() - a.dt_s.ln())).exp();
            return format!(
                "crosses {threshold} % at about {} ms (between {} ms: {:.2} % and {} ms: {:.2} %)",
                fmt_ms(dt),
                fmt_ms(a.dt_s),
                err(a),
                fmt_ms(b.dt_s),
                err(b)
            );
        }
    }
    let last = sorted.last().map_or(first, |l| l);
    format!("below {threshold} % up to {} ms ({:.2} %)", fmt_ms(last.dt_s), err(last))
}

fn fmt_ms(s: f64) -> String {
    format!("{:.3}", s * 1e3)
}

/// The mass-proportional rate of `kind` for `material`: the chart's damping ratio at the
/// model's own 8^3 fundamental.
fn damping_rate(material: &Material, kind: ModelKind) -> anyhow::Result<f64> {
    let choice = match kind {
        ModelKind::Msm(t) => crate::sim::ModelChoice::Lattice(t),
        ModelKind::Fem(f) => crate::sim::ModelChoice::Fem(f),
    };
    // The running tissue's own rate (its one home: `Tissue::set_damping_ratio`).
    Ok(choice.build(material, None, CHART_DAMPING_RATIO)?.damping().rate())
}

/// The FEM's dynamic reference of `material` at the chart's damping ratio, with a note on how
/// each transient converged.
fn dynamic_references(
    material: &Material,
    notes: &mut Vec<String>,
) -> anyhow::Result<crate::validate::dynamic_measure::References> {
    let refs = crate::validate::dynamic_measure::References::new(material, CHART_DAMPING_RATIO)?;
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

/// Computes every point: for each object, model, resolution and integrator.
pub fn compute(opts: &ChartOptions, progress: &mut dyn FnMut(&str)) -> anyhow::Result<(Vec<ChartPoint>, Vec<String>)> {
    let mut points = Vec::new();
    let mut notes = Vec::new();
    let start = Instant::now();
    if opts.resolutions.iter().any(|&n| n > MAX_COUPLED_IMPLICIT_N) {
        notes.push(format!(
            "implicit steps of the shear and hex lattices and of the FEM are measured up to {MAX_COUPLED_IMPLICIT_N}^3 only: \
             their sparse factor grows like n^6 (several GB and minutes at 32^3 on this machine)"
        ));
    }
    for object in &opts.objects {
        let material =
            Material::preset(object).ok_or_else(|| anyhow::anyhow!("unknown object {object:?}: use A or B"))?;
        progress(&format!("object {object}: reference FEM {REFERENCE_N}^3"));
        let ref_grid = Grid::new(REFERENCE_N)?;
        let reference: Vec<Vec<[f64; 3]>> = FemModel::new(ref_grid, &material)
            .solve_cases(&cases(&ref_grid, object))?
            .into_iter()
            .map(|s| s.displacements)
            .collect();
        let reference = sampled(&ref_grid, &reference);
        let alpha = |kind: ModelKind| damping_rate(&material, kind);
        for &n in &opts.resolutions {
            let grid = Grid::new(n)?;
            let (touch, dynamics) = if n == Grid::paper().n() {
                progress(&format!("object {object}: touch benchmark and dynamic reference FEM at {n}^3"));
                let refs = dynamic_references(&material, &mut notes)?;
                (Some(crate::validate::touch_score::Reference::new(&material, grid)?), Some(refs))
            } else {
                (None, None)
            };
            for kind in ModelKind::CHARTED {
                if opts.cancel.as_ref().is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed)) {
                    anyhow::bail!("the chart was cancelled");
                }
                progress(&format!(
                    "object {object}: {} at {n}^3 ({:.1} s)",
                    kind.name(),
                    start.elapsed().as_secs_f64()
                ));
                let refs = (&reference[..], touch.as_ref(), dynamics.as_ref());
                let mut pts = match kind {
                    ModelKind::Msm(t) => msm_points(object, &material, t, grid, opts, refs, alpha(kind)?)?,
                    ModelKind::Fem(f) => fem_points(object, &material, f, grid, opts, refs, alpha(kind)?)?,
                };
                points.append(&mut pts);
            }
        }
        if opts.resolutions.contains(&32) {
            let g = Grid::new(32)?;
            let fine: Vec<Vec<[f64; 3]>> = FemModel::new(g, &material)
                .solve_cases(&cases(&g, object))?
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Symplectic Euler with explicit damping on one mode, `n` steps of `h` from `x = 1`.
    fn grows(omega: f64, gamma: f64, h: f64) -> bool {
        let (mut x, mut v) = (1.0f64, 0.0f64);
        for _ in 0..20_000 {
            v += h * (-omega * omega * x - gamma * v);
            x += h * v;
        }
        x.is_nan() || x.abs() > 1e3 // NaN after an overflow counts as growth
    }

    #[test]
    fn sample_points_are_the_4_cubed_nodes() {
        assert_eq!(sample_points(), Grid::new(4).unwrap().positions());
    }

    #[test]
    fn model_and_integrator_names_round_trip() {
        for kind in ModelKind::ALL {
            assert_eq!(ModelKind::from_name(&kind.name()), Some(kind));
            assert_eq!(format!("{kind}"), kind.name());
        }
        assert_eq!(ModelKind::from_name("msm-other"), None);
        assert_eq!(format!("{:<9}|", ChartIntegrator::Explicit), "explicit |");
    }

    #[test]
    fn damped_limit_separates_stable_from_unstable_steps() {
        for (omega, gamma) in [(1000.0, 0.0), (990.0, 425.0), (300.0, 2000.0)] {
            let h = damped_explicit_limit(omega, gamma);
            assert!(!grows(omega, gamma, 0.99 * h), "omega {omega} gamma {gamma}: 0.99 h grows");
            assert!(grows(omega, gamma, 1.01 * h), "omega {omega} gamma {gamma}: 1.01 h is stable");
        }
        assert!((damped_explicit_limit(1000.0, 0.0) - 2e-3).abs() < 1e-15);
    }
}
