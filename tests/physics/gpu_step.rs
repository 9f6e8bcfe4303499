//! The GPU's explicit step (wgpu compute, f32) against the CPU's (f64) on whatever adapter exists
//! (software Vulkan, Mesa lavapipe, in CI): the same script gives the same trajectory. Likewise
//! the CPU's step with its force in f32 (`"compute": "cpu-f32"`).

use tissue_studies::study::script::{Outcome, Script, run};

/// Relative tolerance on positions: the largest distance between the two runs' nodes over the
/// largest displacement. f32 carries about 6e-8 of a spring's length; over 1,000 steps the runs
/// part by 1e-5 of the displacement (measured: 7.5e-6 on the hex lattice, 4.8e-6 on the FEM).
const TOLERANCE: f64 = 1e-4;

fn script(model: &str, nodes: usize, compute: &str) -> Script {
    serde_json::from_value(serde_json::json!({
        "object": "A", "model": model, "dt": 1e-4, "compute": compute, "contact": "nodes", "nodes": nodes,
        "actions": [
            { "drag": { "node": nodes * nodes * nodes - 1, "to": [0.11, 0.1, 0.12], "duration_s": 0.03 } },
            { "release": {} },
            { "probe": { "at": [0.05, 0.05, 0.1], "direction": [0, 0, -1], "radius": 0.015, "depth": 0.004,
                         "duration_s": 0.02, "samples": 4 } },
            { "wait": { "duration_s": 0.02 } }
        ]
    }))
    .expect("a valid script")
}

fn final_positions(o: &Outcome) -> &[[f64; 3]] {
    o.events.last().and_then(|e| e.positions.as_deref()).expect("the last event has positions")
}

/// The largest distance between the two runs' final node positions, and the CPU run's largest
/// displacement (the scale it is compared with), m.
fn apart(cpu: &Outcome, gpu: &Outcome) -> (f64, f64) {
    let scale = cpu.events.iter().map(|e| e.max_displacement_m).fold(0.0, f64::max);
    let apart = final_positions(cpu)
        .iter()
        .zip(final_positions(gpu))
        .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    (apart, scale)
}

/// The script of `model` on `nodes`^3 run on the CPU in f64 and with `compute`: the same steps,
/// and the final positions within [`TOLERANCE`] of the f64 run's largest displacement.
fn follows(model: &str, nodes: usize, compute: &str) -> (Outcome, Outcome) {
    let cpu = run(&script(model, nodes, "cpu")).expect("the f64 CPU run");
    let other = run(&script(model, nodes, compute)).expect("the other run");
    assert_eq!(other.steps, cpu.steps);
    let (apart, scale) = apart(&cpu, &other);
    assert!(scale > 1e-4, "{model} {nodes}^3 moved only {scale} m");
    assert!(apart <= TOLERANCE * scale, "{model} {nodes}^3 {compute}: the runs part by {apart} m of {scale} m");
    (cpu, other)
}

/// Whether a test that needs an adapter skips: none here and not in CI (which requires one).
fn skipped() -> bool {
    let none = tissue_gpu::ComputeDevice::open().is_err() && std::env::var_os("CI").is_none();
    if none {
        eprintln!("skipped: no wgpu adapter (install mesa-vulkan-drivers for software Vulkan); CI requires one");
    }
    none
}

#[test]
fn the_cpu_f32_force_follows_the_f64_step() {
    for (model, nodes) in
        [("fem-linear", 8), ("fem-linear", 11), ("fem-linear", 16), ("hex", 8), ("shear", 11), ("axis", 8)]
    {
        let (cpu, single) = follows(model, nodes, "cpu-f32");
        assert!(apart(&cpu, &single).0 > 0.0, "{model} {nodes}^3: the f32 run is the f64 one");
    }
    let refused = run(&script("fem-corotational", 8, "cpu-f32")).expect_err("the corotational FEM has no f32 force");
    assert!(format!("{refused:#}").contains("no f32 step"), "{refused:#}");
}

#[test]
fn the_gpu_step_follows_the_cpu_step() {
    if skipped() {
        return;
    }
    for (model, nodes) in [("hex", 8), ("shear", 8), ("axis", 8), ("fem-linear", 8), ("hex", 11), ("fem-linear", 11)] {
        let (cpu, gpu) = follows(model, nodes, "gpu");
        let (f_cpu, f_gpu) = (cpu.force_depth.last().expect("samples"), gpu.force_depth.last().expect("samples"));
        assert!(
            (f_cpu.force_n - f_gpu.force_n).abs() <= 1e-3 * f_cpu.force_n.abs().max(0.01),
            "{model} {nodes}^3: probe force {} N on the CPU, {} N on the GPU",
            f_cpu.force_n,
            f_gpu.force_n
        );
    }
}

#[test]
fn the_gpu_refuses_what_it_has_no_step_for() {
    if tissue_gpu::ComputeDevice::open().is_err() {
        return; // the missing adapter's own error is the CLI test's
    }
    let err = run(&script("fem-corotational", 8, "gpu")).expect_err("no GPU step").to_string();
    assert!(err.contains("corotational") && !err.contains('\n'), "{err}");
    let mut prefactored = script("hex", 8, "gpu");
    prefactored.integrator = Some(tissue_core::sim::Integrator::Prefactored);
    let err = run(&prefactored).expect_err("symplectic only").to_string();
    assert!(err.contains("symplectic") && !err.contains('\n'), "{err}");
}

/// The probe on the material's surface compliance (the viewer's contact): the tools change only
/// the load, so the GPU's state stays there between the script's actions, the guard reading the
/// kernel's figures once a tick. The same trajectory and force as the CPU's.
#[test]
fn the_state_stays_on_the_gpu_under_the_surface_probe() {
    if skipped() {
        return;
    }
    let pressed = |model: &str, nodes: usize, compute: &str| -> Script {
        serde_json::from_value(serde_json::json!({
            "object": "A", "model": model, "compute": compute, "nodes": nodes,
            "actions": [
                { "probe": { "at": [0.03, 0.05, 0.1], "direction": [0, 0, -1], "radius": 0.015, "depth": 0.004,
                             "duration_s": 0.05, "samples": 4 } },
                { "wait": { "duration_s": 0.05 } }
            ]
        }))
        .expect("a valid script")
    };
    for (model, nodes) in [("hex", 8), ("fem-linear", 11)] {
        let cpu = run(&pressed(model, nodes, "cpu")).expect("the CPU run");
        let gpu = run(&pressed(model, nodes, "gpu")).expect("the GPU run");
        assert_eq!(gpu.steps, cpu.steps);
        assert!(gpu.blow_ups.is_empty() && cpu.blow_ups.is_empty(), "{:?} {:?}", gpu.blow_ups, cpu.blow_ups);
        let (apart, scale) = apart(&cpu, &gpu);
        assert!(scale > 1e-3, "{model} {nodes}^3 moved only {scale} m");
        assert!(apart <= TOLERANCE * scale, "{model} {nodes}^3: the runs part by {apart} m of {scale} m");
        let (f_cpu, f_gpu) = (cpu.force_depth.last().expect("samples"), gpu.force_depth.last().expect("samples"));
        assert!((f_cpu.force_n - f_gpu.force_n).abs() <= 1e-6 * f_cpu.force_n.abs(), "{f_cpu:?} {f_gpu:?}");
    }
}

/// A blow-up on the GPU, its state never brought back by a tool, is caught by the kernel's figures
/// of the step: a 1e9 N pull stops the run as on the CPU.
#[test]
fn the_guard_catches_a_blow_up_on_the_gpu() {
    if tissue_gpu::ComputeDevice::open().is_err() {
        return; // the missing adapter's own error is the CLI test's
    }
    let script: Script = serde_json::from_value(serde_json::json!({
        "object": "A", "model": "hex", "compute": "gpu", "clamp": "A_clamped_ax3_F1000000000",
        "actions": [ { "wait": { "duration_s": 0.5 } } ]
    }))
    .expect("a valid script");
    let err = run(&script).expect_err("a persistent blow-up").to_string();
    assert!(err.contains("blow-ups in a row"), "{err}");
}

/// The kernel's guard figures of a step (summed over workgroups in f32) are the state's: its
/// kinetic energy and largest displacement component, as the CPU computes them once the state
/// is brought back.
#[test]
fn the_gpu_guard_figures_are_the_states() {
    use tissue_core::mechanics::{cases::LoadCase, grid::Grid, material::Material};
    use tissue_core::sim::{Integrator, Model, Tissue};
    let Ok(gpu) = tissue_gpu::ComputeDevice::open() else {
        return; // the missing adapter's own error is the CLI test's
    };
    for model in ["hex", "fem-linear"] {
        let model = Model::ALL.into_iter().find(|m| m.name() == model).expect("a model");
        let grid = Grid::new(9).expect("grid");
        let mut inner = model.build_undamped_on(grid, &Material::object_a(), None).expect("built");
        inner.apply_case(&LoadCase::clamped(&grid, "A", 3, 1.0));
        let mut tissue = tissue_gpu::GpuTissue::new(&gpu, inner).expect("on the GPU");
        let dt = 0.5 * tissue.explicit_dt_limit();
        for _ in 0..200 {
            tissue.step(Integrator::Symplectic, dt).expect("a step");
        }
        let health = tissue.step_health().expect("on the GPU").expect("read");
        tissue.sync().expect("brought back");
        let largest = (0..grid.num_nodes())
            .flat_map(|p| (0..3).map(move |c| (p, c)))
            .map(|(p, c)| (tissue.x()[c][p] - grid.position(p)[c]).abs())
            .fold(0.0, f64::max);
        let energy = tissue.kinetic_energy();
        assert!(energy > 0.0 && largest > 0.0, "{model:?}: {energy} J, {largest} m");
        assert!((health.kinetic_energy_j - energy).abs() <= 1e-5 * energy, "{model:?}: {health:?} vs {energy} J");
        assert!(
            (health.largest_displacement_m - largest).abs() <= 1e-6 * largest,
            "{model:?}: {health:?} vs {largest} m"
        );
        assert!(tissue.step_health().is_none(), "the state is here after a sync");
    }
}

/// The drag's split step on the GPU (the state stays there): a top corner dragged and held moves
/// the cube as on the CPU, and the hand feels the same force.
#[test]
fn the_gpu_steps_the_drag() {
    if skipped() {
        return;
    }
    let dragged = |model: &str, nodes: usize, compute: &str| -> Script {
        serde_json::from_value(serde_json::json!({
            "object": "A", "model": model, "compute": compute, "nodes": nodes,
            "actions": [
                { "drag": { "node": nodes * nodes * nodes - 1, "to": [0.11, 0.1, 0.11], "duration_s": 0.03 } },
                { "wait": { "duration_s": 0.03 } }
            ]
        }))
        .expect("a valid script")
    };
    for (model, nodes) in [("hex", 8), ("fem-linear", 11)] {
        let cpu = run(&dragged(model, nodes, "cpu")).expect("the CPU run");
        let gpu = run(&dragged(model, nodes, "gpu")).expect("the GPU run");
        assert!(gpu.blow_ups.is_empty() && cpu.blow_ups.is_empty(), "{:?} {:?}", gpu.blow_ups, cpu.blow_ups);
        let (apart, scale) = apart(&cpu, &gpu);
        assert!(scale > 5e-3, "{model} {nodes}^3 moved only {scale} m");
        assert!(apart <= TOLERANCE * scale, "{model} {nodes}^3: the runs part by {apart} m of {scale} m");
        for (a, b) in cpu.events.iter().zip(&gpu.events) {
            let size = a.tool_force_n.iter().map(|f| f * f).sum::<f64>().sqrt();
            let gap = (0..3).map(|c| (a.tool_force_n[c] - b.tool_force_n[c]).powi(2)).sum::<f64>().sqrt();
            assert!(
                size > 0.1 && gap <= 1e-3 * size,
                "{model} {nodes}^3: {:?} vs {:?}",
                a.tool_force_n,
                b.tool_force_n
            );
        }
    }
}

/// A cube held nowhere on the GPU (its guard reads the state brought back once a tick, since its
/// motion as a whole shows only there): dragged by a corner it moves as on the CPU.
#[test]
fn a_cube_held_nowhere_runs_on_the_gpu_as_on_the_cpu() {
    if skipped() {
        return;
    }
    let free = |compute: &str| -> Script {
        serde_json::from_value(serde_json::json!({
            "object": "A", "model": "hex", "compute": compute, "clamp": "none",
            "actions": [
                { "drag": { "node": 511, "to": [0.12, 0.1, 0.1], "duration_s": 0.03 } },
                { "release": {} },
                { "wait": { "duration_s": 0.03 } }
            ]
        }))
        .expect("a valid script")
    };
    let (cpu, gpu) = (run(&free("cpu")).expect("the CPU run"), run(&free("gpu")).expect("the GPU run"));
    assert!(gpu.blow_ups.is_empty() && cpu.blow_ups.is_empty(), "{:?} {:?}", gpu.blow_ups, cpu.blow_ups);
    let (apart, scale) = apart(&cpu, &gpu);
    assert!(scale > 5e-3, "moved only {scale} m");
    assert!(apart <= TOLERANCE * scale, "the runs part by {apart} m of {scale} m");
}
