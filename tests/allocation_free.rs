//! The physics steps allocate nothing once built (a counting global allocator checks it).

#[path = "support/test_cache.rs"]
mod test_cache;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use tissue_core::mechanics::cases::LoadCase;
use tissue_core::mechanics::grid::Grid;
use tissue_core::mechanics::msm::{Dynamics, MsmModel, MsmParams};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// This thread's allocations (a `const` cell: reading it allocates nothing).
    static OWN: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// Allocations made by the calling thread so far.
fn own_allocations() -> usize {
    OWN.with(std::cell::Cell::get)
}

// SAFETY: forwards to the system allocator, only counting calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        OWN.with(|n| n.set(n.get() + 1));
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        OWN.with(|n| n.set(n.get() + 1));
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The allocations in 100 symplectic steps with the springs' force in `f32` (`cpu-f32`).
fn single_precision_steps(model: &MsmModel, dynamics: &mut Dynamics) -> usize {
    dynamics.set_single_precision(model, true);
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for _ in 0..100 {
        dynamics.step_symplectic(model, 1e-5);
    }
    ALLOCATIONS.load(Ordering::Relaxed) - before
}

#[test]
fn explicit_and_implicit_steps_do_not_allocate() {
    let grid = Grid::paper();
    let params = MsmParams {
        c12: Some(200.0),
        c13: Some(200.0),
        c23: Some(200.0),
        ..MsmParams::axis(900.0, 1000.0, 1100.0, 0.5)
    };
    let model = MsmModel::new(grid, params, 1040.0).expect("model");
    let mut dynamics = Dynamics::new(&model);
    dynamics.apply_case(&LoadCase::clamped(&grid, "A", 1, 5.0));
    dynamics.step_symplectic(&model, 1e-5);
    dynamics.step_implicit(&model, 1e-3).expect("first implicit step builds the pattern");
    dynamics.step_prefactored(&model, 1e-3).expect("first prefactored step builds the factor");
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for _ in 0..100 {
        dynamics.step_symplectic(&model, 1e-5);
    }
    let explicit = ALLOCATIONS.load(Ordering::Relaxed) - before;
    for _ in 0..10 {
        dynamics.step_implicit(&model, 1e-3).expect("implicit step");
    }
    let implicit = ALLOCATIONS.load(Ordering::Relaxed) - before - explicit;
    for _ in 0..10 {
        dynamics.step_prefactored(&model, 1e-3).expect("prefactored step");
    }
    let prefactored = ALLOCATIONS.load(Ordering::Relaxed) - before - explicit - implicit;
    assert_eq!(
        (explicit, implicit, prefactored),
        (0, 0, 0),
        "allocations in 100 explicit / 10 implicit / 10 prefactored steps"
    );
    assert_eq!(single_precision_steps(&model, &mut dynamics), 0, "allocations in 100 f32 symplectic steps");
    // The interactive simulation over the Tissue trait, with each tool and the guard's good-state
    // copies: allocation-free too. (In the same test: the counter is global to the binary.)
    use tissue_core::sim::{Integrator, Simulation, Tool};
    let mut sim = Simulation::new(model, Integrator::Symplectic, 1e-5, Some(&LoadCase::clamped(&grid, "A", 3, 0.0)));
    let tools = [
        Tool::Drag { node: 511, target: [0.11, 0.1, 0.105] },
        Tool::Probe { centre: [0.05, 0.05, 0.1 + 0.015 - 0.002], radius: 0.015 },
        Tool::None,
    ];
    for t in tools {
        sim.tool = t;
        sim.step().expect("warm-up step");
    }
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for t in tools {
        sim.tool = t;
        for _ in 0..200 {
            sim.step().expect("step");
        }
    }
    let simulated = ALLOCATIONS.load(Ordering::Relaxed) - before;
    assert_eq!(simulated, 0, "allocations in 600 simulation steps with drag, probe and no tool");
    // The probe on the material's surface compliance (a coarse one here: 10 divisions) with the
    // material's slow modes, the sphere moving every step: a few contact solves each step (the
    // lag's fixed point) and the modes advanced, in preallocated memory.
    let material = tissue_core::mechanics::material::Material::object_a();
    let compliance =
        tissue_core::sim::material_surface::compliance::SurfaceCompliance::compute(&material, 10, &mut |_| true)
            .expect("c");
    let surface = tissue_core::sim::material_surface::MaterialSurface {
        compliance: std::sync::Arc::new(compliance),
        modes: std::sync::Arc::new(
            tissue_core::sim::material_surface::modal_lag::ModalBasis::of_material(&material).expect("modes"),
        ),
    };
    let probe = tissue_core::sim::material_surface::SurfaceProbe::on(&surface, grid, Some(0.2));
    assert!(probe.is_dynamic());
    sim.set_surface_probe(Some(probe));
    let at = |i: usize| Tool::Probe { centre: [0.03 + 2e-4 * i as f64, 0.05, 0.1 + 0.015 - 0.004], radius: 0.015 };
    for i in 0..5 {
        sim.tool = at(i);
        sim.step().expect("warm-up step");
    }
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for i in 5..205 {
        sim.tool = at(i);
        sim.step().expect("step");
    }
    assert!(sim.tool_force[2] > 1.0, "the surface compliance pushes back: {:?}", sim.tool_force);
    let surface = ALLOCATIONS.load(Ordering::Relaxed) - before;
    assert_eq!(surface, 0, "allocations in 200 steps with the probe sliding on the surface compliance");
    drag_inside_newmarks_solve(&mut sim);
    fem_steps_on_the_physics_pool();
}

/// The drag inside Newmark's solve: the anchor's correction prepared in preallocated memory
/// when a drag starts on a node, Newton's corrections by conjugate gradients on the factor.
fn drag_inside_newmarks_solve(sim: &mut tissue_core::sim::Simulation) {
    use tissue_core::sim::{Integrator, Tool};
    sim.try_set_integrator(Some(Integrator::Newmark), 1e-3).expect("Newmark at 1 ms");
    sim.tool = Tool::None;
    sim.step().expect("the first Newmark step builds the factor");
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for node in [511, 510] {
        sim.tool = Tool::Drag { node, target: [0.11, 0.1, 0.11] };
        for _ in 0..100 {
            sim.step().expect("step");
        }
    }
    let anchored = ALLOCATIONS.load(Ordering::Relaxed) - before;
    let solves = sim.tissue.newton_solves().expect("the lattice's Newton solves");
    assert!(solves.iterations > 0 && solves.newton > 0, "no conjugate-gradient or Newton iteration ran: {solves:?}");
    assert_eq!(anchored, 0, "allocations in 200 Newmark steps with the drag inside the solve");
}

/// The FEM's steps on the physics pool (the corotational element loop at 12^3, the linear
/// stencil's slabs at 16^3), run from a thread of the pool as the viewer's physics loop runs
/// (`parallel::on_pool`): the stepping thread allocates nothing while the work is split over the
/// cores. (From outside the pool each split queues a job in rayon's shared injector, which
/// allocates a block every 63 calls: 300 corotational symplectic steps at 12^3 allocated 4
/// times.) Counted on the stepping thread: the pool's other worker, stealing the splits, once
/// allocated 3 times in its own bookkeeping (in 1 of 6 runs, at one step of 200).
fn fem_steps_on_the_physics_pool() {
    use tissue_core::mechanics::fem::FemModel;
    use tissue_core::mechanics::fem::dynamics::{FemDynamics, Formulation};
    use tissue_core::mechanics::parallel::on_pool;
    // With a lump in it: its elements' changes applied in the steps too.
    let mut material = tissue_core::mechanics::material::Material::object_a();
    let stiffness = material.stiffness * 5.0;
    material.inclusions.push(tissue_core::mechanics::inclusion::Inclusion {
        centre: [0.05, 0.05, 0.08],
        radius: 0.008,
        stiffness,
    });
    for (n, formulation) in [(12, Formulation::Corotational), (16, Formulation::Linear)] {
        let grid = Grid::new(n).expect("grid");
        let mut fem = FemDynamics::new(FemModel::new(grid, &material), material.density, formulation, 10.0);
        fem.apply_case(&LoadCase::clamped(&grid, "A", 1, 5.0));
        let allocated = on_pool(|| {
            for _ in 0..5 {
                fem.step_symplectic(1e-6);
            }
            let before = own_allocations();
            for _ in 0..200 {
                fem.step_symplectic(1e-6);
            }
            own_allocations() - before
        });
        assert_eq!(allocated, 0, "allocations in 200 {formulation:?} FEM steps at {n}^3 on the physics pool");
    }
    // The corotational FEM's implicit steps: Newton on the warped stiffness, each solve by
    // conjugate gradients on the rest factor, each product split over the pool.
    let grid = Grid::new(12).expect("grid");
    let mut fem = FemDynamics::new(FemModel::new(grid, &material), material.density, Formulation::Corotational, 10.0);
    fem.apply_case(&LoadCase::clamped(&grid, "A", 1, 5.0));
    let warped = on_pool(|| {
        for _ in 0..3 {
            fem.step_newmark(1e-3).expect("the first step builds the factor");
        }
        let before = own_allocations();
        for _ in 0..10 {
            fem.step_newmark(1e-3).expect("Newmark step");
        }
        own_allocations() - before
    });
    let solves = fem.newton_solves().expect("the corotational FEM's warped solves");
    assert!(solves.iterations > 0 && solves.newton > 0, "no conjugate-gradient or Newton iteration ran: {solves:?}");
    assert_eq!(warped, 0, "allocations in 10 warped Newmark steps of the corotational FEM at 12^3 on the pool");
}
