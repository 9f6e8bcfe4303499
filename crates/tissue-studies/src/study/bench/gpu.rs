//! `bench`'s GPU at scale: the GPU's symplectic step alone, and the 1 ms tick of the hex lattice
//! and the linear FEM at 16^3, 32^3 and 64^3 on the GPU against the CPU's in the same run, with
//! how far the GPU's f32 moves the answer from the CPU's f64; and the tick as the viewer and
//! `simulate` run it on the GPU, through the simulation with the probe pressed.
//!
//! The tissue is undamped (a damping ratio needs the fundamental, whose factor is too large at
//! 64^3), held by its bottom face and pulled by 10 N on its top face (load case `A`, axis 3), or
//! pressed by the probe on the material's surface compliance ([`super::pressed`]).

use std::collections::BTreeMap;

use crate::gpu::{ComputeDevice, GpuTissue};
use crate::mechanics::cases::LoadCase;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::sim::TICK_S;
use crate::sim::material_surface::MaterialSurface;
use crate::sim::{DEFAULT_DYNAMIC_BUDGET, Integrator, Model, Tissue};
use crate::study::timing::time_fallible;

/// The resolutions timed on the GPU, nodes per edge (up to the largest grid).
pub const GPU_NODES: [usize; 3] = [16, 32, crate::mechanics::grid::MAX_NODES_PER_AXIS];
/// How long the GPU is kept busy before its step and its tick are timed, s. After a few seconds
/// idle (a tissue being built on the CPU) an H200 stepped the hex lattice at 64^3 at 111 us a
/// step for its first 1,000 to 2,000 steps and at 25 us after; the same state stepped at once,
/// without the pause, took 25 us from the start (the GPU's clocks, not the state).
pub const WARM_UP_S: f64 = 0.5;
/// Ticks run on both before their states are compared.
const DRIFT_TICKS: usize = 20;
/// The pull on the top face, N.
const PULL_N: f64 = 10.0;

/// One model x resolution: a 1 ms tick on the GPU and on the CPU, measured in the same run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct GpuScale {
    /// `hex` or `fem-linear`.
    pub model: Model,
    /// Nodes per edge.
    pub nodes: usize,
    /// Symplectic substeps of the 1 ms tick (the automatic choice's for the undamped tissue).
    pub substeps: usize,
    /// One tick on the GPU under a held load (sent once, before): the substeps in one
    /// submission, waited for, no readback, after [`WARM_UP_S`] of ticks, s.
    pub gpu_tick_s: f64,
    /// The same and the whole state read back into the CPU's f64 model once (what drawing it
    /// costs, at most 60 times a second in the viewer), s.
    pub gpu_tick_readback_s: f64,
    /// The viewer's and `simulate`'s tick on the GPU: the simulation's 1 ms tick with the probe
    /// pressed 4 mm on the material's surface compliance, its loads sent every substep and the
    /// guard's figures read once a tick, the state kept on the GPU ([`super::pressed`]), s. The
    /// tissue is undamped (as above), so the held sphere's contact is not solved again: with a
    /// damping ratio the viewer also solves it once a tick, on the CPU, whichever computes the
    /// steps.
    pub sim_tick_s: f64,
    /// The same tick on the CPU, f64, on the physics pool (`cpu_threads` threads), s.
    pub cpu_tick_s: f64,
    /// The physics pool's threads.
    pub cpu_threads: usize,
    /// `cpu_tick_s / gpu_tick_s`.
    pub gpu_speedup: f64,
    /// After 20 ticks from rest under the pull: the largest distance between a node's position
    /// on the GPU (f32) and on the CPU (f64), over the largest displacement on the CPU.
    pub f32_drift: f64,
}

/// The GPU's figures.
#[derive(Debug, Clone, serde::Serialize)]
pub struct GpuBench {
    /// The GPU's adapter, or why there is none.
    pub gpu_adapter: String,
    /// One GPU step alone (100 steps in one submission, no readback, after [`WARM_UP_S`] of
    /// steps), by `model/nodes`, s.
    pub gpu_step_s: BTreeMap<String, f64>,
    /// The 1 ms tick at scale, GPU against CPU.
    pub gpu_scale: Vec<GpuScale>,
}

/// The models with a GPU step that are timed.
fn models() -> [Model; 2] {
    [
        Model::Lattice(crate::mechanics::msm::Topology::Hex),
        Model::Fem(crate::mechanics::fem::dynamics::Formulation::Linear),
    ]
}

/// `model` of object A on `grid`, undamped, under the pull.
fn tissue(model: Model, grid: Grid) -> anyhow::Result<Box<dyn Tissue>> {
    let mut tissue = model.build_undamped_on(grid, &Material::object_a(), None)?;
    tissue.apply_case(&LoadCase::clamped(&grid, "A", 3, PULL_N));
    Ok(tissue)
}

/// Where no adapter computes: only why not.
pub fn unavailable(why: &crate::gpu::GpuError) -> GpuBench {
    GpuBench { gpu_adapter: why.to_string(), gpu_step_s: BTreeMap::new(), gpu_scale: Vec::new() }
}

/// The GPU's figures on `gpu`, the probe pressed on object A's `surface` compliance.
pub fn measure(gpu: &ComputeDevice, surface: &MaterialSurface) -> anyhow::Result<GpuBench> {
    let mut gpu_step_s = BTreeMap::new();
    let mut gpu_scale = Vec::new();
    for model in models() {
        for nodes in GPU_NODES {
            crate::io::progress(&format!("bench: {} at {nodes}^3 on the GPU and the CPU", model.name()));
            let grid = Grid::new(nodes)?;
            let fail = |e: String| anyhow::anyhow!("GPU step of {} at {nodes}^3: {e}", model.name());
            let mut on_gpu = GpuTissue::new(gpu, tissue(model, grid)?)?;
            let dt = 0.5 * on_gpu.explicit_dt_limit();
            warm_up(&mut on_gpu, dt, 100).map_err(fail)?;
            let step = time_fallible(0.3, || on_gpu.run_unsynchronised(dt, 100)).map_err(fail)?;
            gpu_step_s.insert(format!("{}/{nodes}", model.name()), step / 100.0);
            gpu_scale.push(scale(gpu, model, grid, surface).map_err(fail)?);
        }
    }
    Ok(GpuBench { gpu_adapter: gpu.describe(), gpu_step_s, gpu_scale })
}

/// The GPU kept busy for [`WARM_UP_S`] (batches of `steps` steps of `dt`) before a timing.
fn warm_up(on_gpu: &mut GpuTissue, dt: f64, steps: usize) -> Result<(), String> {
    let start = std::time::Instant::now();
    while start.elapsed().as_secs_f64() < WARM_UP_S {
        on_gpu.run_unsynchronised(dt, steps)?;
    }
    Ok(())
}

/// The largest distance between a node's positions `a` and `b` on `grid`, over the largest
/// displacement from rest in `b` (the reference).
fn relative_gap(a: &[Vec<f64>; 3], b: &[Vec<f64>; 3], grid: Grid) -> f64 {
    let (mut gap, mut largest) = (0.0_f64, 0.0_f64);
    for p in 0..grid.num_nodes() {
        let x0 = grid.position(p);
        let d = (0..3).map(|c| (a[c][p] - b[c][p]).powi(2)).sum::<f64>().sqrt();
        let u = (0..3).map(|c| (b[c][p] - x0[c]).powi(2)).sum::<f64>().sqrt();
        gap = gap.max(d);
        largest = largest.max(u);
    }
    gap / largest
}

/// The CPU's `f32` force ([`crate::gpu::Compute::CpuF32`]) against its `f64` one: after 20
/// ticks from rest under the pull, the largest distance between a node's positions over the
/// largest displacement in `f64`.
pub fn cpu_f32_drift(model: Model, grid: Grid) -> anyhow::Result<f64> {
    let run = |single: bool| -> anyhow::Result<Box<dyn Tissue>> {
        let mut t = tissue(model, grid)?;
        t.set_single_precision(single).map_err(anyhow::Error::msg)?;
        let limit = t.step_limit();
        let substeps =
            crate::sim::fewest_substeps(Integrator::Symplectic, TICK_S, limit, t.damping(), DEFAULT_DYNAMIC_BUDGET)
                .ok_or_else(|| anyhow::anyhow!("no substep count is stable"))?;
        for _ in 0..DRIFT_TICKS * substeps {
            t.step(Integrator::Symplectic, TICK_S / substeps as f64).map_err(anyhow::Error::msg)?;
        }
        Ok(t)
    };
    let (single, double) = (run(true)?, run(false)?);
    Ok(relative_gap(single.x(), double.x(), grid))
}

/// One model x resolution's tick on both, and the drift between them.
fn scale(gpu: &ComputeDevice, model: Model, grid: Grid, surface: &MaterialSurface) -> Result<GpuScale, String> {
    let built = || tissue(model, grid).map_err(|e| format!("{e:#}"));
    let mut cpu = built()?;
    let mut on_gpu = GpuTissue::new(gpu, built()?).map_err(|e| e.to_string())?;
    let limit = cpu.step_limit();
    let substeps =
        crate::sim::fewest_substeps(Integrator::Symplectic, TICK_S, limit, cpu.damping(), DEFAULT_DYNAMIC_BUDGET)
            .ok_or_else(|| format!("no substep count up to {} is stable", crate::sim::MAX_AUTO_SUBSTEPS))?;
    let dt = TICK_S / substeps as f64;
    // The drift first, from rest.
    let cpu_tick = |cpu: &mut Box<dyn Tissue>| -> Result<(), String> {
        (0..substeps).try_for_each(|_| cpu.step(Integrator::Symplectic, dt))
    };
    crate::mechanics::parallel::on_pool(|| (0..DRIFT_TICKS).try_for_each(|_| cpu_tick(&mut cpu)))?;
    for _ in 0..DRIFT_TICKS {
        on_gpu.run_unsynchronised(dt, substeps)?;
    }
    on_gpu.read_back()?;
    let f32_drift = relative_gap(on_gpu.x(), cpu.x(), grid);
    warm_up(&mut on_gpu, dt, substeps)?;
    let gpu_tick_s = time_fallible(0.3, || on_gpu.run_unsynchronised(dt, substeps))?;
    let gpu_tick_readback_s = time_fallible(0.3, || {
        on_gpu.run_unsynchronised(dt, substeps)?;
        on_gpu.read_back()
    })?;
    let cpu_tick_s = crate::mechanics::parallel::on_pool(|| time_fallible(0.3, || cpu_tick(&mut cpu)))?;
    let undamped = model.build_undamped_on(grid, &Material::object_a(), None).map_err(|e| format!("{e:#}"))?;
    let mut sim = super::pressed::scene(Box::new(GpuTissue::new(gpu, undamped).map_err(|e| e.to_string())?), surface);
    let sim_tick_s = super::pressed::time_tick(&mut sim, Integrator::Symplectic, substeps)?;
    Ok(GpuScale {
        model,
        nodes: grid.n(),
        substeps,
        gpu_tick_s,
        gpu_tick_readback_s,
        sim_tick_s,
        cpu_tick_s,
        cpu_threads: crate::mechanics::parallel::pool().map_or(1, rayon::ThreadPool::current_num_threads),
        gpu_speedup: cpu_tick_s / gpu_tick_s,
        f32_drift,
    })
}

impl GpuBench {
    /// A human-readable table.
    pub fn to_text(&self) -> String {
        let mut s = format!("GPU: {}\n", self.gpu_adapter);
        for (k, t) in &self.gpu_step_s {
            s += &format!("  GPU step alone {k:<22} {:10.1} us\n", t * 1e6);
        }
        if !self.gpu_scale.is_empty() {
            s += "1 ms tick, undamped, pulled by 10 N (GPU f32 against CPU f64 in the same run), and the viewer's \
                  tick on the GPU with the probe pressed:\n";
        }
        for g in &self.gpu_scale {
            s += &format!(
                "  {:<11} {:>2}^3 x{:<3} GPU {:9.1} us ({:9.1} us with the state read back), CPU ({} threads) \
                 {:9.1} us: {:.1}x; f32 drift after 20 ticks {:.1e}; pressed {:9.1} us\n",
                g.model,
                g.nodes,
                g.substeps,
                g.gpu_tick_s * 1e6,
                g.gpu_tick_readback_s * 1e6,
                g.cpu_threads,
                g.cpu_tick_s * 1e6,
                g.gpu_speedup,
                g.f32_drift,
                g.sim_tick_s * 1e6
            );
        }
        s
    }
}
