//! `tissue-sim bench`: timings of the physics core, median of repeated batches, one thread.
//!
//! [`pressed`]: the viewer's scene with the probe pressed; [`sweep`]: every model x resolution x
//! integrator; [`gpu`]: the GPU's figures.

pub mod gpu;
pub mod moving;
pub mod pressed;
pub mod sweep;

use crate::study::timing::{time_fallible, time_per_call};
use std::collections::BTreeMap;

use crate::mechanics::cases::{Bc, LoadCase, benchmark_cases};
use crate::mechanics::fem::FemModel;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::msm::statics::{self, NewtonOptions};
use crate::mechanics::msm::{Dynamics, MsmModel, MsmParams};

/// Benchmark results, seconds.
#[derive(Debug, Clone, serde::Serialize)]
pub struct BenchReport {
    /// One symplectic Euler step of the axis-spring MSM (paper's model), keyed by nodes per axis.
    pub msm_explicit_step_s: BTreeMap<usize, f64>,
    /// One symplectic Euler step of the shear-spring MSM, keyed by nodes per axis.
    pub msm_shear_explicit_step_s: BTreeMap<usize, f64>,
    /// One linearised implicit Euler step (assembly + factorisation + solve), keyed by nodes per axis.
    pub msm_implicit_step_s: BTreeMap<usize, f64>,
    /// One prefactored implicit Euler step (force pass, one solve with the rest tangent factorised
    /// once, and Newton's check of the step's equation), paper's model, keyed by nodes per axis.
    pub msm_prefactored_step_s: BTreeMap<usize, f64>,
    /// The same for the hex-element lattice (object A's shipped tissue).
    pub msm_hex_prefactored_step_s: BTreeMap<usize, f64>,
    /// FEM: assembly, one factorisation per fixed face, 9 solves (object A, 8^3).
    pub fem_static_9_cases_s: f64,
    /// Static MSM equilibrium of the 9 clamped cases, paper's model (closed form).
    pub msm_static_9_cases_s: f64,
    /// The same 9 cases through the general Newton solver (the check of the fast path).
    pub msm_static_9_cases_newton_s: f64,
    /// Newton on the 9 cases of the shear-spring model.
    pub msm_shear_static_9_cases_newton_s: f64,
    /// The linear FEM's elastic force `K u`, keyed by nodes per axis: by the stencil on one
    /// thread and by the element loop (before), seconds.
    pub fem_linear_force_s: BTreeMap<usize, (f64, f64)>,
    /// On one thread and on the physics pool (every core, [`crate::mechanics::parallel`]), keyed
    /// `linear-force/N` (the stencil's `K u`, interleaved), `linear-force-components/N` (the same
    /// on the component-wise state the running FEM steps) and `corotational-step/N` (one symplectic step of
    /// the corotational FEM), seconds; and `corotational-step-converged-rotations/N`: one step
    /// with 20 rotation iterations every step (before) and with the default's, until the update
    /// is below its tolerance (now), one thread.
    pub fem_parallel_s: BTreeMap<String, (f64, f64)>,
    /// One 1 ms physics tick of the viewer's scene (face z = 0 clamped, object A, 8^3) with the
    /// probe pressed 4 mm into the top face, keyed by `model/integrator/dt`: the viewer keeps up
    /// with 1 kHz real time when this is below 1 ms.
    pub viewer_tick_with_probe_s: BTreeMap<String, f64>,
    /// One 1 ms tick of the viewer's scene with the probe moving on the material's surface,
    /// moved at every step as the viewer's glide moves it ([`moving`]), keyed
    /// `model/nodes/motion` (`pressing`: in to 4 mm and out along `sin^2`, 0.4 s a cycle;
    /// `sliding`: 4 mm deep at 40 mm/s): the viewer keeps 1 kHz while the probe moves where
    /// this is below 1 ms.
    pub moving_probe_tick_s: BTreeMap<String, f64>,
    /// Every model x resolution x integrator ([`crate::study::bench::sweep`]).
    pub resolution_sweep: sweep::Sweep,
}

/// How the benchmarked probe touches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ProbeRun {
    /// Held still, the model's node contact.
    NodesStill,
    /// Held still, the material's surface compliance.
    SurfaceStill,
    /// Sliding along x at 40 mm/s (moved once per 1 ms tick), the surface compliance.
    SurfaceSliding,
}

/// One 1 ms tick of `model` in the viewer's scene with the probe pressed 4 mm into the top face
/// (after 0.2 s of settling), stepping `integrator` at `dt`, on the physics pool as the viewer's
/// loop runs.
fn probe_tick(
    model: crate::sim::Model,
    integrator: crate::sim::Integrator,
    dt: f64,
    run: ProbeRun,
) -> anyhow::Result<f64> {
    crate::mechanics::parallel::on_pool(|| probe_tick_here(model, integrator, dt, run))
}

fn probe_tick_here(
    model: crate::sim::Model,
    integrator: crate::sim::Integrator,
    dt: f64,
    run: ProbeRun,
) -> anyhow::Result<f64> {
    use crate::sim::{Simulation, Tool};
    let material = Material::object_a();
    let grid = Grid::paper();
    let tissue = model.build(&material, None, crate::response::damping::DEFAULT_DAMPING_RATIO)?;
    let mut sim = Simulation::with_tissue(tissue, integrator, dt, Some(&LoadCase::bottom_clamp(&grid, "A")));
    if run != ProbeRun::NodesStill {
        let mut report = crate::sim::material_surface::stderr_report();
        let c = crate::sim::material_surface::MaterialSurface::load_or_compute(
            &material,
            crate::io::cache_dir().as_deref(),
            &mut |e| report.event(e),
        )?;
        let zeta = sim.tissue.damping().ratio();
        sim.set_surface_probe(Some(crate::sim::material_surface::SurfaceProbe::on(&c, grid, zeta)));
    }
    let r = crate::validate::touch::PROBE_RADIUS_M;
    let z = crate::mechanics::grid::CUBE_SIDE_M + r - 0.004;
    sim.tool = Tool::Probe { centre: [0.03, 0.05, z], radius: r };
    let steps = (1e-3 / dt).round().max(1.0) as usize;
    let mut failed = None;
    for _ in 0..(0.2 / dt) as usize {
        if let Err(e) = sim.step() {
            failed = Some(e.message);
        }
    }
    let mut x = 0.03;
    let t = time_per_call(1.0, || {
        if run == ProbeRun::SurfaceSliding {
            x = if x > 0.07 { 0.03 } else { x + 4e-5 };
            sim.tool = Tool::Probe { centre: [x, 0.05, z], radius: r };
        }
        for _ in 0..steps {
            if let Err(e) = sim.step() {
                failed = Some(e.message.clone());
            }
        }
    });
    match failed {
        Some(m) => anyhow::bail!("{} with {} at dt = {dt}: {m}", model.name(), integrator.name()),
        None => Ok(t),
    }
}

fn paper_params() -> MsmParams {
    MsmParams::axis(968.2, 1010.0, 1137.7, 0.5)
}

fn shear_params() -> MsmParams {
    MsmParams { c12: Some(300.0), c13: Some(300.0), c23: Some(300.0), ..paper_params() }
}

fn explicit_step(n: usize, params: MsmParams) -> anyhow::Result<f64> {
    let grid = Grid::new(n)?;
    let model = MsmModel::new(grid, params, crate::mechanics::material::TISSUE_DENSITY)?;
    let mut dynamics = Dynamics::new(&model);
    dynamics.apply_case(&LoadCase::clamped(&grid, "A", 1, 1.0));
    // Far below the stability limit at every resolution benchmarked.
    let dt = 1e-7;
    Ok(time_per_call(0.5, || dynamics.step_symplectic(&model, dt)))
}

fn implicit_step(n: usize, params: MsmParams, prefactored: bool) -> anyhow::Result<f64> {
    let grid = Grid::new(n)?;
    let model = MsmModel::new(grid, params, crate::mechanics::material::TISSUE_DENSITY)?;
    let mut dynamics = Dynamics::new(&model);
    dynamics.apply_case(&LoadCase::clamped(&grid, "A", 1, 1.0));
    let step =
        |d: &mut Dynamics| if prefactored { d.step_prefactored(&model, 1e-3) } else { d.step_implicit(&model, 1e-3) };
    step(&mut dynamics)?;
    Ok(time_fallible(0.5, || step(&mut dynamics))?)
}

/// The linear FEM's `K u` by the stencil and by the element loop, at 8^3, 16^3 and 32^3.
fn fem_linear_force(material: &Material) -> anyhow::Result<BTreeMap<usize, (f64, f64)>> {
    let mut out = BTreeMap::new();
    for n in [8, 16, 32] {
        let fem = FemModel::new(Grid::new(n)?, material);
        let u: Vec<f64> = (0..3 * fem.grid.num_nodes()).map(|d| ((d * 7919) % 101) as f64 * 1e-6).collect();
        let mut ku = vec![0.0; u.len()];
        let stencil = time_per_call(0.3, || fem.stencil().apply_on(std::hint::black_box(&u), &mut ku, false));
        let elements = time_per_call(0.3, || fem.apply_by_elements(std::hint::black_box(&u), &mut ku));
        out.insert(n, (stencil, elements));
    }
    Ok(out)
}

/// The stencil's `K u` and the corotational FEM's step on one thread and on the physics pool.
fn fem_parallel(material: &Material) -> anyhow::Result<BTreeMap<String, (f64, f64)>> {
    use crate::mechanics::fem::dynamics::{FemDynamics, Formulation, ROTATION_ITERATIONS, ROTATION_TOLERANCE};
    let mut out = BTreeMap::new();
    for n in [8, 16, 32] {
        let fem = FemModel::new(Grid::new(n)?, material);
        let u: Vec<f64> = (0..3 * fem.grid.num_nodes()).map(|d| ((d * 7919) % 101) as f64 * 1e-6).collect();
        let mut ku = vec![0.0; u.len()];
        let one = time_per_call(0.3, || fem.stencil().apply_on(std::hint::black_box(&u), &mut ku, false));
        let all = time_per_call(0.3, || fem.stencil().apply_on(std::hint::black_box(&u), &mut ku, true));
        out.insert(format!("linear-force/{n}"), (one, all));
        // The same product on the running FEM's component-wise state (four x-inside nodes at a
        // time with AVX2).
        let nn = fem.grid.num_nodes();
        let split: [Vec<f64>; 3] = std::array::from_fn(|c| (0..nn).map(|p| u[3 * p + c]).collect());
        let mut out_c: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; nn]);
        let stencil = fem.stencil();
        let one = time_per_call(0.3, || stencil.apply_components_on(std::hint::black_box(&split), &mut out_c, false));
        let all = time_per_call(0.3, || stencil.apply_components_on(std::hint::black_box(&split), &mut out_c, true));
        out.insert(format!("linear-force-components/{n}"), (one, all));
        let mut d = FemDynamics::new(fem, material.density, Formulation::Corotational, 0.0);
        for (x, du) in d.x.iter_mut().zip(&u) {
            *x += du;
        }
        // A drifting state, so that the rotations change every step as they do in use.
        let mut time = |parallel: bool, iterations: usize, tolerance: f64| {
            (d.parallel, d.rotation_iterations, d.rotation_tolerance) = (parallel, iterations, tolerance);
            let mut k = 0usize;
            time_per_call(0.3, || {
                k += 1;
                let phase = (k % 200) as f64 / 200.0;
                for (i, x) in d.x.iter_mut().enumerate() {
                    *x += 1e-7 * (phase * std::f64::consts::TAU + i as f64).sin();
                }
                d.step_symplectic(1e-9);
            })
        };
        // 20 iterations every step, against the default's until the update is below its tolerance.
        let converged = time(false, 20, 0.0);
        let (one, all) =
            (time(false, ROTATION_ITERATIONS, ROTATION_TOLERANCE), time(true, ROTATION_ITERATIONS, ROTATION_TOLERANCE));
        out.insert(format!("corotational-step/{n}"), (one, all));
        out.insert(format!("corotational-step-converged-rotations/{n}"), (converged, one));
    }
    Ok(out)
}

/// The viewer's 1 ms tick with the probe pressed, keyed by `model/integrator/dt[/contact]`.
fn viewer_ticks() -> anyhow::Result<BTreeMap<String, f64>> {
    let mut viewer_tick_with_probe_s = BTreeMap::new();
    use crate::mechanics::fem::dynamics::Formulation;
    use crate::sim::{Integrator, Model};
    let default = Model::Lattice(crate::sim::shipped::DEFAULT_TOPOLOGY);
    // The viewer's default with the material's surface compliance, the probe still and
    // sliding (the automatic choice's 4 substeps of a 1 ms tick).
    for (run, name) in [(ProbeRun::SurfaceStill, "surface"), (ProbeRun::SurfaceSliding, "surface-sliding")] {
        let key = format!("{}/symplectic/0.00025/{name}", default.name());
        viewer_tick_with_probe_s.insert(key, probe_tick(default, Integrator::Symplectic, 2.5e-4, run)?);
    }
    for (model, integrator, dt) in [
        (Model::Lattice(crate::sim::shipped::DEFAULT_TOPOLOGY), Integrator::Symplectic, 1e-4),
        (Model::Fem(Formulation::Corotational), Integrator::Symplectic, 1e-4),
        // The viewer's automatic choice for the FEM's 1 ms request (the dynamic budget).
        (Model::Fem(Formulation::Corotational), Integrator::Symplectic, 2.5e-4),
        (Model::Fem(Formulation::Linear), Integrator::Symplectic, 2.5e-4),
        (Model::Fem(Formulation::Corotational), Integrator::Prefactored, 1e-3),
        (Model::Fem(Formulation::Linear), Integrator::Prefactored, 1e-3),
        // One Newmark (trapezoidal) solve per tick: inside the dynamic budget.
        (Model::Fem(Formulation::Corotational), Integrator::Newmark, 1e-3),
        (Model::Fem(Formulation::Linear), Integrator::Newmark, 1e-3),
        (Model::Lattice(crate::sim::shipped::DEFAULT_TOPOLOGY), Integrator::Newmark, 1e-3),
    ] {
        let key = format!("{}/{}/{dt}", model.name(), integrator.name());
        viewer_tick_with_probe_s.insert(key, probe_tick(model, integrator, dt, ProbeRun::NodesStill)?);
    }
    Ok(viewer_tick_with_probe_s)
}

/// Runs every benchmark (minutes in a release build; the resolution sweep takes most).
pub fn run() -> anyhow::Result<BenchReport> {
    let mut msm_explicit_step_s = BTreeMap::new();
    let mut msm_shear_explicit_step_s = BTreeMap::new();
    for n in [8, 16, 32] {
        msm_explicit_step_s.insert(n, explicit_step(n, paper_params())?);
        msm_shear_explicit_step_s.insert(n, explicit_step(n, shear_params())?);
    }
    let mut msm_implicit_step_s = BTreeMap::new();
    for n in [8, 16] {
        msm_implicit_step_s.insert(n, implicit_step(n, paper_params(), false)?);
    }
    let hex = crate::sim::shipped::tissue_params(&Material::object_a(), crate::mechanics::msm::Topology::Hex)?;
    let mut msm_prefactored_step_s = BTreeMap::new();
    let mut msm_hex_prefactored_step_s = BTreeMap::new();
    for n in [8, 16, 32] {
        msm_prefactored_step_s.insert(n, implicit_step(n, paper_params(), true)?);
    }
    for n in [8, 16] {
        msm_hex_prefactored_step_s.insert(n, implicit_step(n, hex, true)?);
    }
    let material = Material::object_a();
    let fem_linear_force_s = fem_linear_force(&material)?;
    let fem_parallel_s = fem_parallel(&material)?;
    let grid = Grid::paper();
    let cases = benchmark_cases(&grid, "A", Bc::Clamped);
    let mut err = None;
    let fem_static_9_cases_s = time_per_call(1.0, || {
        if let Err(e) = FemModel::new(grid, &material).solve_cases(&cases) {
            err = Some(e);
        }
    });
    if let Some(e) = err {
        return Err(e.into());
    }
    let model = MsmModel::new(grid, paper_params(), material.density)?;
    let msm_static_9_cases_s = time_per_call(0.5, || {
        for c in &cases {
            std::hint::black_box(statics::equilibrium(&model, c).ok());
        }
    });
    let newton = |model: &MsmModel| {
        time_per_call(1.0, || {
            for c in &cases {
                std::hint::black_box(statics::solve_newton(model, c, NewtonOptions::default()).ok());
            }
        })
    };
    let msm_static_9_cases_newton_s = newton(&model);
    let shear = MsmModel::new(grid, shear_params(), material.density)?;
    let msm_shear_static_9_cases_newton_s = newton(&shear);
    let viewer_tick_with_probe_s = viewer_ticks()?;
    let moving_probe_tick_s = moving::run()?;
    let resolution_sweep = sweep::run()?;
    Ok(BenchReport {
        resolution_sweep,
        fem_linear_force_s,
        fem_parallel_s,
        viewer_tick_with_probe_s,
        moving_probe_tick_s,
        msm_explicit_step_s,
        msm_shear_explicit_step_s,
        msm_implicit_step_s,
        msm_prefactored_step_s,
        msm_hex_prefactored_step_s,
        fem_static_9_cases_s,
        msm_static_9_cases_s,
        msm_static_9_cases_newton_s,
        msm_shear_static_9_cases_newton_s,
    })
}

impl BenchReport {
    /// A human-readable summary.
    pub fn to_text(&self) -> String {
        let mut s = String::from("tissue-sim bench (one thread, median of batches)\n");
        let us = |t: f64| format!("{:10.2} us", t * 1e6);
        for (name, map) in [
            ("MSM explicit step, axis springs", &self.msm_explicit_step_s),
            ("MSM explicit step, shear springs", &self.msm_shear_explicit_step_s),
            ("MSM implicit step, axis springs", &self.msm_implicit_step_s),
            ("MSM prefactored implicit step, axis", &self.msm_prefactored_step_s),
            ("MSM prefactored implicit step, hex", &self.msm_hex_prefactored_step_s),
        ] {
            for (n, t) in map {
                s += &format!("{name:<40} n={n:>3}: {}\n", us(*t));
            }
        }
        for (n, (stencil, elements)) in &self.fem_linear_force_s {
            s += &format!(
                "{:<40} n={n:>3}: {} (element loop {}, {:.2}x)\n",
                "FEM linear force K u, stencil",
                us(*stencil),
                us(*elements).trim(),
                elements / stencil
            );
        }
        for (key, (a, b)) in &self.fem_parallel_s {
            let (first, second) =
                if key.contains("converged") { ("converged", "incremental") } else { ("one thread", "all cores") };
            s += &format!(
                "{:<40}: {} {first}, {} {second} ({:.2}x)\n",
                format!("FEM {key}"),
                us(*a),
                us(*b).trim(),
                a / b
            );
        }
        s += &format!("{:<46}: {}\n", "FEM static, 9 clamped cases (A, 8^3)", us(self.fem_static_9_cases_s));
        s += &format!("{:<46}: {}\n", "MSM static, 9 cases, closed form", us(self.msm_static_9_cases_s));
        s += &format!("{:<46}: {}\n", "MSM static, 9 cases, Newton (axis)", us(self.msm_static_9_cases_newton_s));
        s +=
            &format!("{:<46}: {}\n", "MSM static, 9 cases, Newton (shear)", us(self.msm_shear_static_9_cases_newton_s));
        for (key, t) in &self.viewer_tick_with_probe_s {
            s += &format!(
                "{:<46}: {} ({:.0} ticks/s possible)\n",
                format!("viewer 1 ms tick + probe, {key}"),
                us(*t),
                1.0 / t
            );
        }
        s += &moving::to_text(&self.moving_probe_tick_s);
        s += &self.resolution_sweep.to_text();
        s
    }
}
