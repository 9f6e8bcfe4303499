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

use crate::bench::{time_fallible, time_per_call};
use crate::cases::{CaseSolution, LoadCase};
use crate::fem::FemModel;
use crate::fem::clamped::ClampedSolver;
use crate::fem::dynamics::{FemDynamics, Formulation};
use crate::grid::{CUBE_SIDE_M, Grid};
use crate::material::Material;
use crate::msm::{Dynamics, MsmModel, MsmParams, Topology, statics};
use crate::tissue::tissue_params;

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
    /// On the Pareto front of (step time, average error) for its object.
    pub pareto: bool,
}

impl ChartPoint {
    /// Wall time to advance `1 / rate_hz` of simulated time: one implicit step, or as many
    /// explicit steps as `0.9 dt_max` needs.
    pub fn tick_s(&self, rate_hz: f64) -> f64 {
        let tick = 1.0 / rate_hz;
        if self.dt_max_s.is_finite() {
            (tick / (0.9 * self.dt_max_s)).ceil().max(1.0) * self.step_s
        } else {
            self.step_s
        }
    }

    /// Explicit substeps per tick at `rate_hz` (1 for implicit).
    pub fn substeps(&self, rate_hz: f64) -> f64 {
        if self.dt_max_s.is_finite() { (1.0 / rate_hz / (0.9 * self.dt_max_s)).ceil().max(1.0) } else { 1.0 }
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

impl PointBase<'_> {
    fn point(&self, integrator: ChartIntegrator, step_s: f64, dt_max_s: f64, memory_bytes: usize) -> ChartPoint {
        ChartPoint {
            object: self.object.into(),
            model: self.model,
            n: self.n,
            integrator,
            step_s,
            dt_max_s,
            static_s: self.static_s,
            memory_bytes,
            avg_err_pct: self.avg,
            max_err_pct: self.max,
            force_err_pct: self.force,
            pareto: false,
        }
    }
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
    (reference, touch): (&[Vec<[f64; 3]>], Option<&crate::touch::Reference>),
) -> anyhow::Result<Vec<ChartPoint>> {
    let params = msm_params_at(material, topology, &grid)?;
    let model = MsmModel::new(grid, params, material.density)?;
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
    let dt_max = damped_explicit_limit(omega, params.d / model.node_mass);
    let mut dynamics = Dynamics::new(&model);
    dynamics.apply_case(&cs[0]);
    let explicit = time_per_call(opts.timing_s, || dynamics.step_symplectic(&model, 0.5 * dt_max));
    let base = msm_memory(&model);
    let mut out = vec![];
    if topology == Topology::Axis || grid.n() <= MAX_COUPLED_IMPLICIT_N {
        let mut dynamics = Dynamics::new(&model);
        dynamics.apply_case(&cs[0]);
        dynamics.step_prefactored(&model, 1e-3)?;
        let implicit = time_fallible(opts.timing_s, || dynamics.step_prefactored(&model, 1e-3))?;
        out.push((ChartIntegrator::Implicit, implicit, f64::INFINITY, base + dynamics.prefactored_memory_bytes()));
    }
    let force = match touch {
        Some(reference) => {
            100.0
                * crate::touch::score::evaluate(reference, material, &crate::touch::ModelUnderTest::Lattice(params))?
                    .worst_force_error
        }
        None => f64::NAN,
    };
    let shared = PointBase { object, model: ModelKind::Msm(topology), n: grid.n(), static_s, avg, max, force };
    let mut points = vec![shared.point(ChartIntegrator::Explicit, explicit, dt_max, base)];
    points.extend(out.into_iter().map(|(i, t, dt, m)| shared.point(i, t, dt, m)));
    Ok(points)
}

fn fem_points(
    object: &str,
    material: &Material,
    formulation: Formulation,
    grid: Grid,
    opts: &ChartOptions,
    (reference, touch): (&[Vec<[f64; 3]>], Option<&crate::touch::Reference>),
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
    let mut points = vec![shared.point(ChartIntegrator::Explicit, explicit, dt_max, without)];
    points.extend(implicit.map(|(t, m)| shared.point(ChartIntegrator::Implicit, t, f64::INFINITY, m)));
    Ok(points)
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

/// Marks the Pareto front of (step time, average error) per object.
pub fn mark_pareto(points: &mut [ChartPoint]) {
    let snapshot = points.to_vec();
    for p in points.iter_mut() {
        p.pareto = !snapshot.iter().any(|q| {
            q.object == p.object
                && q.step_s <= p.step_s
                && q.avg_err_pct <= p.avg_err_pct
                && (q.step_s < p.step_s || q.avg_err_pct < p.avg_err_pct)
        });
    }
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
        // Same damping as the default tissue, as a mass-proportional rate.
        let alpha = crate::tissue::fem_damping_rate(&material)?;
        for &n in &opts.resolutions {
            let grid = Grid::new(n)?;
            let touch = if n == Grid::paper().n() {
                progress(&format!("object {object}: touch benchmark FEM at {n}^3"));
                Some(crate::touch::Reference::new(&material, grid)?)
            } else {
                None
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
                let mut pts = match kind {
                    ModelKind::Msm(t) => msm_points(object, &material, t, grid, opts, (&reference, touch.as_ref()))?,
                    ModelKind::Fem(f) => {
                        fem_points(object, &material, f, grid, opts, (&reference, touch.as_ref()), alpha)?
                    }
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
