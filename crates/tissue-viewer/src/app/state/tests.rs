//! Tests of the parent module.

use super::*;
use crate::app::physics::{PhysicsThread, Published};
use crate::sim::shipped::tissue_params;

fn wait_until(physics: &PhysicsThread, mut ok: impl FnMut(&Published) -> bool) -> Published {
    let mut p = Published::default();
    for _ in 0..3000 {
        physics.latest(&mut p);
        if ok(&p) {
            return p;
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    p
}

fn started() -> (ViewerState, PhysicsThread) {
    let (state, first) = ViewerState::new(|| {}).expect("state");
    let physics = PhysicsThread::spawn(first, false).expect("physics");
    (state, physics)
}

#[test]
fn applying_a_calibration_changes_topology_and_keeps_the_integrator_guard() {
    let (mut state, physics) = started();
    let mut send = |c| physics.send(c).expect("physics runs");
    assert_eq!(state.shown.topology(), crate::sim::shipped::DEFAULT_TOPOLOGY);
    // A result of another lattice (the paper's axis springs), applied as the panel would.
    let axis = tissue_params(&state.shown.material, Topology::Axis).expect("shipped");
    state.shown.result = Some(axis);
    let before = state.shown.params;
    state.handle(Request::ApplyCalibration, &mut send);
    assert_eq!(state.shown.topology(), Topology::Axis, "the topology follows the parameters");
    // What ran before is kept to show what changed; an edit afterwards forgets it.
    let applied = state.shown.applied.clone().expect("the Apply is remembered");
    assert_eq!((applied.from, applied.to), (before, state.shown.params));
    let p = wait_until(&physics, |p| p.params == Some(axis));
    assert_eq!(p.params.map(|p| p.topology()), Some(Topology::Axis), "the running model agrees");
    // The automatic choice follows the new model's limit.
    let auto = crate::sim::choose_integrator(None, state.shown.dt, p.limit).expect("auto never refuses");
    assert_eq!(p.integrator.map(|(i, _)| i), Some(auto));
    // Symplectic Euler asked for far above its limit: the policy on the physics side refuses.
    let limit = p.limit.tissue;
    assert!(limit > 0.0 && limit.is_finite());
    state.handle(Request::SetIntegrator(Some(Integrator::Symplectic), 3.0 * limit), &mut send);
    // It switches to the automatic choice: symplectic substeps, cheaper than one prefactored step.
    let p = wait_until(&physics, |p| p.note.as_deref().is_some_and(|n| n.contains("stability limit")));
    assert!(p.note.as_deref().is_some_and(|n| n.contains("automatic choice")), "{:?}", p.note);
    assert!(p.integrator.is_some_and(|(i, dt)| i == Integrator::Symplectic && dt <= 0.9 * limit), "{:?}", p.integrator);
    // Well below: accepted.
    state.handle(Request::SetIntegrator(Some(Integrator::Symplectic), 0.3 * limit), &mut send);
    let p = wait_until(&physics, |p| p.integrator.is_some_and(|(_, dt)| dt == 0.3 * limit));
    assert_eq!(p.integrator.map(|(i, _)| i), Some(Integrator::Symplectic));
}

#[test]
fn another_resolution_runs_the_model_on_that_grid() {
    let (mut state, physics) = started();
    let mut send = |c| physics.send(c).expect("physics runs");
    let at8 = state.shown.params;
    state.handle(Request::SetResolution(12), &mut send);
    assert_eq!(state.grid().n(), 12);
    let p = wait_until(&physics, |p| p.positions.len() == 12 * 12 * 12);
    assert_eq!(p.positions.len(), 1728, "the physics thread runs the 12^3 model");
    // The shipped hex tissue carried over by its stiffness scale: softer springs on a finer grid.
    assert!(state.shown.params.k1 < at8.k1, "{:?} vs {at8:?}", state.shown.params);
    state.handle(Request::SetResolution(1), &mut send);
    assert_eq!(state.grid().n(), 12, "an impossible grid is refused");
}

#[test]
fn the_gpu_steps_the_model_when_asked() {
    if crate::gpu::ComputeDevice::open().is_err() && std::env::var_os("CI").is_none() {
        return; // CI has software Vulkan
    }
    let (mut state, physics) = started();
    let mut send = |c| physics.send(c).expect("physics runs");
    state.settings.compute = crate::gpu::Compute::Gpu;
    state.handle(Request::SetCompute, &mut send);
    let p = wait_until(&physics, |p| p.note.as_deref().is_some_and(|n| n.contains("GPU")));
    assert!(p.note.as_deref().is_some_and(|n| n.contains("on the GPU")), "{:?}", p.note);
    let t0 = p.time_s;
    let p = wait_until(&physics, |p| p.time_s > t0 + 0.01);
    assert!(p.time_s > t0 + 0.01 && p.message.is_none(), "{:?}", p.message);
}

#[test]
fn object_b_ties_are_imposed_and_a_second_calibration_is_refused() {
    let (mut state, physics) = started();
    let mut send = |c| physics.send(c).expect("physics runs");
    state.settings.object = crate::app::settings::Source::Object(crate::mechanics::object::Object::B);
    state.handle(Request::LoadObject, &mut send);
    assert_eq!(state.shown.material.name, "B");
    let mut edited = state.shown.params;
    edited.k3 = 2.0 * edited.k2;
    state.handle(Request::EditParams(edited), &mut send);
    assert_eq!(state.shown.params.k3, state.shown.params.k2, "k3 = k2 for a transversely isotropic object");
    state.settings.calib_generations = 1000;
    state.handle(Request::StartCalibration, &mut send);
    assert!(state.shown.calibrating);
    state.handle(Request::StartCalibration, &mut send);
    assert!(state.shown.note.as_deref().is_some_and(|n| n.contains("already running")), "{:?}", state.shown.note);
    state.handle(Request::CancelCalibration, &mut send);
    for _ in 0..5000 {
        state.poll(&mut send);
        if !state.shown.calibrating {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    assert!(!state.shown.calibrating, "cancelled within a generation");
}

#[test]
fn the_probe_gets_the_materials_surface_compliance_in_the_background() {
    let (mut state, physics) = started();
    let mut send = |c| physics.send(c).expect("physics runs");
    // Loaded from the cache folder, or computed there (about a minute) the first time; waited
    // for up to 10 minutes on a loaded machine.
    let mut p = Published::default();
    for _ in 0..6000 {
        state.poll(&mut send);
        physics.latest(&mut p);
        if p.surface_probe {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    assert!(p.surface_probe, "{:?}", state.shown.contact_status);
    assert!(state.shown.contact_status.is_none());
    // Pressed 4 mm into the middle of the top face at once: the cube's slow modes cannot follow
    // at first (a stiffer push), then it settles to the material's static force, about 9.7 N (A).
    let press = crate::app::recording::Press {
        at: [0.05, 0.05, 0.1],
        direction: Some([0.0, 0.0, -1.0]),
        radius: 0.015,
        depth: 0.004,
    };
    state.handle(Request::Press(press), &mut send);
    let first = wait_until(&physics, |p| p.tool_force[2] > 5.0);
    let p = wait_until(&physics, |p| (9.0..10.5).contains(&p.tool_force[2]));
    assert!((9.0..10.5).contains(&p.tool_force[2]), "{:?} (first {:?})", p.tool_force, first.tool_force);
}

#[test]
fn the_fem_runs_in_place_of_the_lattice_and_back() {
    let (mut state, physics) = started();
    let mut send = |c| physics.send(c).expect("physics runs");
    state.handle(Request::SelectFem(crate::mechanics::fem::dynamics::Formulation::Corotational), &mut send);
    assert_eq!(state.shown.model().name(), "fem-corotational");
    let before = wait_until(&physics, |p| p.params.is_some()).revision;
    let p = wait_until(&physics, |p| p.params.is_none() && p.revision > before);
    assert!(p.params.is_none(), "the FEM has no spring parameters");
    state.handle(Request::SelectTopology(Topology::Hex), &mut send);
    let p = wait_until(&physics, |p| p.params.is_some());
    assert_eq!(p.params.map(|p| p.topology()), Some(Topology::Hex));
}

/// A material loaded from a file is recorded by the file's absolute path, and the script reads
/// it back from anywhere; the paper's objects by name.
#[test]
fn a_recording_names_the_object_or_the_material_file() {
    let (mut state, physics) = started();
    let rec = || crate::app::recording::Recording {
        actions: vec![crate::study::script::Action::Wait { duration_s: 0.01, record: false }],
        force_path: Vec::new(),
        integrator: Integrator::Symplectic,
        dt: 1e-4,
        damping_ratio: Some(0.2),
        contact: crate::sim::press::Contact::Nodes,
        note: None,
    };
    let a = state.recording_script(rec()).expect("object A is recorded");
    assert_eq!((a.object, &a.material), (Some(crate::mechanics::object::Object::A), &None));
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/examples/my_tissue.toml");
    state.settings.object = crate::app::settings::Source::File;
    state.settings.material_path = file.display().to_string();
    state.handle(Request::SelectFem(crate::mechanics::fem::dynamics::Formulation::Linear), &mut |_| {});
    state.handle(Request::LoadObject, &mut |c| {
        let _ = physics.send(c);
    });
    let script = state.recording_script(rec()).expect("the file's material is recorded");
    assert!(script.object.is_none() && script.material.as_deref().is_some_and(std::path::Path::is_absolute));
    let back: crate::study::script::Script =
        serde_json::from_str(&serde_json::to_string(&script).expect("JSON")).expect("reads back");
    let out = crate::study::script::run_from(&back, std::path::Path::new("/")).expect("replays from anywhere");
    assert_eq!(out.object, "my_tissue");
}

#[test]
fn the_force_depth_plot_is_the_physics_readings_from_the_first_contact() {
    let (mut state, _physics) = started();
    let press = crate::sim::press::Press::normal([0.05, 0.05, 0.1], 0.015);
    let reading = |depth_m: f64, force_n: f64| crate::sim::press::ProbeReading {
        force: [0.0, 0.0, force_n],
        force_n,
        depth_m,
        contact: crate::sim::press::Contact::Surface,
        time_s: 0.0,
    };
    state.handle(Request::ProbeStarted, &mut |_| {});
    // The first reading a frame sees may be past the touch: the plot starts at the touch.
    state.observe_probe(Some((press.depth(7e-4), reading(7e-4, 0.8))));
    state.observe_probe(Some((press.depth(2e-3), reading(2e-3, 3.1))));
    // The same depth again (a held press settling): the sample is replaced, not added.
    state.observe_probe(Some((press.depth(2e-3), reading(2e-3, 3.2))));
    assert_eq!(state.shown.force_depth, vec![[0.0, 0.0], [0.7, 0.8], [2.0, 3.2]]);
    let (kept, r) = state.shown.last_reading.expect("the reading a comparison compares");
    assert_eq!((kept.depth, r.force_n), (2e-3, 3.2));
    // Let go: the last pressed reading stays.
    state.observe_probe(None);
    assert_eq!(state.shown.last_reading.map(|(_, r)| r.force_n), Some(3.2));
}
