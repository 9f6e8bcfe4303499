//! `bench`'s resolution sweep: the viewer's 1 ms tick with the probe pressed, for every model x
//! resolution x integrator, each integrator at the fewest substeps that keep it stable and inside
//! the dynamic budget ([`crate::sim::fewest_substeps`]), and which of them the automatic choice
//! takes; the largest resolution each model runs at 1 kHz; and the GPU's figures where an
//! adapter computes ([`super::gpu`]).
//!
//! The scene is the viewer's ([`super::pressed`]): object A held by its bottom face, the
//! lattice's shipped tissue carried to the grid, damping ratio 0.2, and the 15 mm probe pressed
//! 4 mm into the top face with the material's surface compliance.

use std::collections::BTreeMap;

use crate::gpu::Compute;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::sim::TICK_S;
use crate::sim::material_surface::MaterialSurface;
use crate::sim::{DEFAULT_DYNAMIC_BUDGET, Integrator, Model};
use crate::study::bench::pressed::{scene, time_tick};

/// The resolutions swept, nodes per edge.
pub const SWEEP_NODES: [usize; 5] = [8, 12, 16, 24, 32];
/// The integrators swept (the full-tangent implicit step, a factorisation per step, is left out).
pub const SWEEP_INTEGRATORS: [Integrator; 3] = [Integrator::Symplectic, Integrator::Prefactored, Integrator::Newmark];

/// One model x resolution x integrator.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SweepTick {
    /// `hex`, ..., `fem-corotational`.
    pub model: Model,
    /// Nodes per edge.
    pub nodes: usize,
    /// The integrator (`any` in JSON where the row holds for every one).
    #[serde(serialize_with = "any_integrator")]
    pub integrator: Option<Integrator>,
    /// `cpu`, `cpu-f32` or `gpu`.
    pub compute: Compute,
    /// Substeps of the 1 ms tick that keep it stable and inside the budget (`None`: none up to
    /// [`crate::sim::MAX_AUTO_SUBSTEPS`] does).
    pub substeps: Option<usize>,
    /// Whether the automatic choice takes this integrator and step.
    pub automatic: bool,
    /// Wall time of one 1 ms tick, s (`None` where not run; `note` says why).
    pub tick_s: Option<f64>,
    /// Why there is no time, if there is none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// The implicit rows of the lattices and the corotational FEM: their Newton corrections and
    /// conjugate-gradient iterations over the whole run (press, hold and timed ticks;
    /// [`crate::mechanics::newton_krylov`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub newton_solves: Option<crate::mechanics::newton_krylov::NewtonSolves>,
    /// `cpu-f32` rows: how far the `f32` force moves the answer
    /// ([`super::gpu::cpu_f32_drift`]: the largest node distance after 20 ticks under a
    /// pull, over the largest displacement in `f64`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub f32_drift: Option<f64>,
}

/// The sweep's results.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Sweep {
    /// Every model x resolution x integrator (and the GPU's symplectic step where it runs).
    pub ticks: Vec<SweepTick>,
    /// The largest resolution swept at which each model's automatic choice on the CPU ticks in
    /// under 1 ms (runs at 1 kHz), by model (`None`: not even 8^3).
    pub largest_1khz_nodes: BTreeMap<String, Option<usize>>,
    /// The same for the force in `f32` ([`Compute::CpuF32`]: symplectic Euler at its fewest
    /// substeps inside the dynamic budget), by model (`None`: not even 8^3, or no `f32` step).
    pub largest_1khz_nodes_cpu_f32: BTreeMap<String, Option<usize>>,
    /// The GPU's step alone and its 1 ms tick at scale against the CPU's
    /// ([`super::gpu`]).
    #[serde(flatten)]
    pub gpu: super::gpu::GpuBench,
}

/// Every integrator of `model` on `grid` for `compute`, into `ticks`.
pub fn sweep_model(
    model: Model,
    nodes: usize,
    surface: &MaterialSurface,
    compute: Compute,
    ticks: &mut Vec<SweepTick>,
) -> anyhow::Result<()> {
    let grid = Grid::new(nodes)?;
    let tissue = model.build_on(grid, &Material::object_a(), None, crate::response::damping::DEFAULT_DAMPING_RATIO)?;
    let mut sim = scene(compute.place(tissue)?, surface);
    let (limit, damping) = (sim.limit(), sim.tissue.damping());
    let auto = crate::sim::choose_step(None, TICK_S, limit, damping, DEFAULT_DYNAMIC_BUDGET).ok();
    let integrators: &[Integrator] =
        if compute == Compute::Cpu { &SWEEP_INTEGRATORS } else { &[Integrator::Symplectic] };
    let f32_drift = if compute == Compute::CpuF32 { Some(super::gpu::cpu_f32_drift(model, grid)?) } else { None };
    for &integrator in integrators {
        let substeps = crate::sim::fewest_substeps(integrator, TICK_S, limit, damping, DEFAULT_DYNAMIC_BUDGET);
        let automatic = compute == Compute::Cpu
            && auto.as_ref().is_some_and(|(i, h, _)| {
                *i == integrator && substeps.is_some_and(|k| (TICK_S / k as f64 - h).abs() < 1e-15)
            });
        let (tick_s, note, newton_solves) = match substeps {
            None => (
                None,
                Some(format!(
                    "no substep count up to {} is stable and inside the budget",
                    crate::sim::MAX_AUTO_SUBSTEPS
                )),
                None,
            ),
            Some(k) => match time_tick(&mut sim, integrator, k) {
                Ok(t) => (Some(t), None, sim.tissue.newton_solves()),
                Err(e) => (None, Some(e), sim.tissue.newton_solves()),
            },
        };
        ticks.push(SweepTick {
            model,
            nodes,
            integrator: Some(integrator),
            compute,
            substeps,
            automatic,
            tick_s,
            note,
            newton_solves,
            f32_drift,
        });
    }
    Ok(())
}

/// Runs the sweep (minutes: the 32^3 factorisations and corotational steps dominate).
pub fn run() -> anyhow::Result<Sweep> {
    let mut report = crate::sim::material_surface::stderr_report();
    let surface =
        MaterialSurface::load_or_compute(&Material::object_a(), crate::io::cache_dir().as_deref(), &mut |e| {
            report.event(e)
        })?;
    let gpu = crate::gpu::ComputeDevice::open();
    let started = std::time::Instant::now();
    let mut ticks = Vec::new();
    for model in Model::ALL {
        for nodes in SWEEP_NODES {
            let on_gpu = model != Model::Fem(crate::mechanics::fem::dynamics::Formulation::Corotational);
            let f32_force = on_gpu;
            for compute in [Compute::Cpu, Compute::CpuF32, Compute::Gpu] {
                if (compute == Compute::Gpu && !(gpu.is_ok() && on_gpu)) || (compute == Compute::CpuF32 && !f32_force) {
                    continue;
                }
                crate::io::progress(&format!(
                    "bench: {} at {nodes}^3 on the {} ({:.0} s)",
                    model.name(),
                    compute.name(),
                    started.elapsed().as_secs_f64()
                ));
                if let Err(e) = sweep_model(model, nodes, &surface, compute, &mut ticks) {
                    // A model that cannot be built here (its damping's fundamental too large
                    // to factorise): said in each of its rows.
                    ticks.push(SweepTick {
                        model,
                        nodes,
                        integrator: None,
                        compute,
                        substeps: None,
                        automatic: false,
                        tick_s: None,
                        note: Some(format!("{e:#}")),
                        newton_solves: None,
                        f32_drift: None,
                    });
                }
            }
        }
    }
    let largest = |counted: &dyn Fn(&SweepTick) -> bool| -> BTreeMap<String, Option<usize>> {
        Model::ALL
            .iter()
            .map(|model| {
                let fast = ticks
                    .iter()
                    .filter(|t| t.model == *model && counted(t) && t.tick_s.is_some_and(|s| s < TICK_S))
                    .map(|t| t.nodes)
                    .max();
                (model.name(), fast)
            })
            .collect()
    };
    let largest_1khz_nodes = largest(&|t| t.automatic);
    let largest_1khz_nodes_cpu_f32 = largest(&|t| t.compute == Compute::CpuF32);
    let gpu = match &gpu {
        Ok(g) => super::gpu::measure(g, &surface)?,
        Err(e) => super::gpu::unavailable(e),
    };
    Ok(Sweep { ticks, largest_1khz_nodes, largest_1khz_nodes_cpu_f32, gpu })
}

impl Sweep {
    /// A human-readable table.
    pub fn to_text(&self) -> String {
        let mut s = String::from("viewer 1 ms tick with the probe pressed (A, bottom clamp, surface compliance)\n");
        for t in &self.ticks {
            let time = t
                .tick_s
                .map_or_else(|| format!("- ({})", t.note.as_deref().unwrap_or("")), |v| format!("{:10.1} us", v * 1e6));
            let k = t.substeps.map_or("-".into(), |k| k.to_string());
            let auto = if t.automatic { " [automatic]" } else { "" };
            let cg = t.newton_solves.map_or(String::new(), |w| {
                format!(
                    " (Newton's CG: {:.2} a step, at most {}, {} unconverged)",
                    w.iterations as f64 / w.steps.max(1) as f64,
                    w.most,
                    w.unconverged
                )
            });
            s += &format!(
                "  {:<17} {:>2}^3 {:<12} {} x{k:<3} {time}{auto}{cg}{drift}\n",
                t.model,
                t.nodes,
                t.integrator.map_or("any", Integrator::name),
                t.compute.name(),
                drift = t.f32_drift.map_or(String::new(), |d| format!(" (f32 drift after 20 ticks {d:.1e})"))
            );
        }
        s += "largest resolution at 1 kHz (automatic choice, CPU; cpu-f32: -, none or no f32 step):\n";
        for (m, n) in &self.largest_1khz_nodes {
            let f32 = self.largest_1khz_nodes_cpu_f32.get(m).copied().flatten();
            let f32 = f32.map_or("-".into(), |n| format!("{n}^3"));
            s += &format!("  {m:<17} {} (cpu-f32: {f32})\n", n.map_or("below 8^3".into(), |n| format!("{n}^3")));
        }
        s + &self.gpu.to_text()
    }
}

/// An integrator's name, or `any` for a row that holds for every one.
fn any_integrator<S: serde::Serializer>(i: &Option<Integrator>, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(i.map_or("any", Integrator::name))
}
