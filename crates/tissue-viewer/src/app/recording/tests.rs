use super::*;
use crate::mechanics::cases::LoadCase;
use crate::mechanics::grid::Grid;
use crate::mechanics::object::Object;
use crate::sim::Model;
use crate::study::script::{Recorded, Script, run};

/// The default tissue of object A at 8^3, held at its bottom, as the viewer starts it.
fn viewer_sim() -> Simulation {
    let grid = Grid::paper();
    let material = Object::A.material();
    let model = Model::Lattice(crate::sim::shipped::DEFAULT_TOPOLOGY);
    let tissue = model.build_on(grid, &material, None, 0.2).expect("the default tissue");
    let case = LoadCase::bottom_clamp(&grid, "A");
    let mut sim = Simulation::with_tissue(tissue, Integrator::Prefactored, 1e-4, Some(&case));
    let _ = sim.set_integrator(None, 1e-4);
    sim
}

fn steps(t: &mut Timeline, sim: &mut Simulation, n: usize) {
    for _ in 0..n {
        t.before_step(sim);
        sim.step().expect("a healthy step");
        t.after_step(sim);
    }
}

/// A press slid and pushed in by mouse samples 16 ms apart (each glided to over the time since
/// the last), held, released, then a node dragged twice and let go, all recorded: the script
/// the recording makes, written as JSON and read back, replays the same forces.
#[test]
fn a_recorded_interaction_replays_to_the_same_forces() {
    let mut sim = viewer_sim();
    let mut t = Timeline::new(true);
    steps(&mut t, &mut sim, 300);
    let press = |k: f64| Press {
        at: [0.04 + 5e-4 * k, 0.05, 0.1],
        direction: Some([0.0, 0.0, -1.0]),
        radius: 0.015,
        depth: (2.5e-4 * k).min(0.004),
    };
    t.press(press(0.0), 1e-3, &mut sim);
    steps(&mut t, &mut sim, 37);
    for k in 1..=30 {
        // A sample that comes before the sphere reached the last one cuts its glide short.
        t.press(press(f64::from(k)), if k == 7 { 0.05 } else { 0.016 }, &mut sim);
        steps(&mut t, &mut sim, 160);
    }
    steps(&mut t, &mut sim, 2000);
    t.set_tool(Tool::None, &mut sim);
    steps(&mut t, &mut sim, 500);
    let drag = |to: [f64; 3]| Tool::Drag { node: 511, target: to };
    t.set_tool(drag([0.102, 0.1, 0.1]), &mut sim);
    steps(&mut t, &mut sim, 300);
    t.set_tool(drag([0.104, 0.101, 0.1]), &mut sim);
    steps(&mut t, &mut sim, 300);
    t.set_tool(Tool::None, &mut sim);
    steps(&mut t, &mut sim, 100);
    let rec = t.recording(&sim);
    assert!(rec.force_path.len() > 60, "{} samples", rec.force_path.len());
    let kinds: Vec<&str> = rec
        .actions
        .iter()
        .map(|a| match a {
            Action::Wait { .. } => "wait",
            Action::ProbePath { .. } => "probe_path",
            Action::Release { .. } => "release",
            Action::Drag { .. } => "drag",
            Action::Probe { .. } => "probe",
        })
        .collect();
    assert_eq!(kinds, ["wait", "probe_path", "release", "wait", "drag", "wait", "drag", "wait", "release", "wait"]);
    let script = Script {
        object: Some(Object::A),
        material: None,
        model: Model::Lattice(crate::sim::shipped::DEFAULT_TOPOLOGY),
        dt: rec.dt,
        integrator: Some(rec.integrator),
        damping_ratio: rec.damping_ratio,
        clamp: "bottom".into(),
        nodes: 8,
        contact: rec.contact,
        compute: crate::gpu::Compute::Cpu,
        actions: rec.actions,
        recorded: Some(Recorded { force_path: rec.force_path, note: None }),
    };
    let text = serde_json::to_string(&script).expect("JSON");
    let back: Script = serde_json::from_str(&text).expect("the script reads back");
    assert_eq!(back.actions, script.actions);
    let out = run(&back).expect("the replay runs");
    let replay = out.replay.expect("a replay comparison");
    assert_eq!(replay.matched, replay.recorded, "{replay:?}");
    assert!(replay.relative_l2 < 1e-9, "{replay:?}");
    let last = out.events.last().expect("events");
    let end = sim.tool_force;
    assert_eq!(last.tool_force_n, end);
}

/// A setting changed halfway (the material's contact arriving under a held press, say): the probe
/// stays held and read, nothing is recorded until the tissue rests with nothing held, and the
/// recording says from when it runs.
#[test]
fn after_a_setting_changes_the_recording_starts_again_at_rest() {
    let mut sim = viewer_sim();
    let mut t = Timeline::new(true);
    let p = Press { at: [0.05, 0.05, 0.1], direction: Some([0.0, 0.0, -1.0]), radius: 0.015, depth: 0.003 };
    t.press(p, 1e-3, &mut sim);
    steps(&mut t, &mut sim, 500);
    t.setting_changed(&sim);
    steps(&mut t, &mut sim, 100);
    // The probe held goes on being held where it was, and read.
    let (held, reading) = t.reading(&sim).expect("the probe is still read");
    assert_eq!((held.at, held.depth, reading.depth_m), (p.at, p.depth, p.depth));
    let waiting = t.recording(&sim);
    assert!(waiting.force_path.is_empty() && waiting.note.is_some());
    t.set_tool(Tool::None, &mut sim);
    for _ in 0..2000 {
        steps(&mut t, &mut sim, 10);
        t.tick(&sim);
    }
    let rec = t.recording(&sim);
    assert!(matches!(rec.actions[..], [Action::Wait { .. }]), "{:?}", rec.actions);
    assert!(rec.note.as_deref().is_some_and(|n| n.contains("at rest")), "{:?}", rec.note);
}
