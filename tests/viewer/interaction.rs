//! Scripted interaction (the `simulate` command's engine): deterministic and physically sane.

use tissue_core::sim::Integrator;
use tissue_studies::study::script::{Action, Script, run};

fn script(actions: Vec<Action>) -> Script {
    Script {
        object: Some(tissue_core::mechanics::object::Object::A),
        material: None,
        model: tissue_core::sim::Model::Lattice(tissue_core::mechanics::msm::Topology::Shear),
        dt: 1e-4,
        integrator: None,
        damping_ratio: None,
        clamp: "bottom".into(),
        nodes: 8,
        // The model's own node contact: these tests check that no node ends inside the sphere.
        contact: tissue_studies::study::script::Contact::Nodes,
        compute: tissue_gpu::Compute::Cpu,
        actions,
        recorded: None,
    }
}

/// A node of the top face, where the probe lands.
const TOP_NODE: [f64; 3] = [3.0 * 0.1 / 7.0, 3.0 * 0.1 / 7.0, 0.1];

fn probe_then_release() -> Vec<Action> {
    vec![
        Action::Probe {
            at: TOP_NODE,
            direction: [0.0, 0.0, -1.0],
            radius: 0.01,
            depth: 0.006,
            duration_s: 0.3,
            samples: 6,
            record: true,
        },
        Action::Wait { duration_s: 0.1, record: false },
        Action::Release { record: false },
        Action::Wait { duration_s: 1.0, record: false },
    ]
}

#[test]
fn probe_force_grows_with_depth_and_release_returns_to_rest() {
    let out = run(&script(probe_then_release())).expect("script runs");
    assert!(out.blow_ups.is_empty(), "{:?}", out.blow_ups);
    assert_eq!(out.force_depth.len(), 6);
    let f: Vec<f64> = out.force_depth.iter().map(|s| s.force_n).collect();
    assert!(f[0] > 0.0, "the probe must push back: {f:?}");
    for w in f.windows(2) {
        assert!(w[1] > w[0], "force must grow with depth: {f:?}");
    }
    // No node inside the probe at the end of the push.
    let pushed = &out.events[0];
    let centre = [TOP_NODE[0], TOP_NODE[1], TOP_NODE[2] + 0.01 - 0.006]; // touching at `at`, then pushed down
    for x in pushed.positions.as_ref().expect("recorded") {
        let d = ((x[0] - centre[0]).powi(2) + (x[1] - centre[1]).powi(2) + (x[2] - centre[2]).powi(2)).sqrt();
        assert!(d >= 0.01 - 1e-12, "node inside the probe: {d}");
    }
    assert!(pushed.max_displacement_m > 0.005);
    let end = out.events.last().expect("events");
    assert!(end.max_displacement_m < 1e-6, "not back at rest: {}", end.max_displacement_m);
}

#[test]
fn drag_pulls_the_node_and_the_tool_feels_the_tissue() {
    let out = run(&script(vec![
        Action::Drag { node: 511, to: [0.12, 0.1, 0.1], duration_s: 0.2, record: false },
        Action::Wait { duration_s: 0.3, record: true },
        Action::Release { record: false },
        Action::Wait { duration_s: 1.0, record: false },
    ]))
    .expect("script runs");
    let held = &out.events[1];
    let x = held.positions.as_ref().expect("recorded")[511][0];
    assert!(x > 0.103 && x < 0.12, "dragged node at x = {x}");
    // The tissue pulls the tool back towards -x.
    assert!(held.tool_force_n[0] < -1.0, "{:?}", held.tool_force_n);
    assert!(out.events[3].max_displacement_m < 1e-6);
}

#[test]
fn scripts_are_deterministic() {
    let a = serde_json::to_string(&run(&script(probe_then_release())).expect("run")).expect("json");
    let b = serde_json::to_string(&run(&script(probe_then_release())).expect("run")).expect("json");
    assert_eq!(a, b);
}

#[test]
fn explicit_above_its_limit_is_refused_up_front_and_implicit_stays_bounded() {
    let mut s = script(vec![
        Action::Drag { node: 511, to: [0.12, 0.1, 0.1], duration_s: 0.05, record: false },
        Action::Wait { duration_s: 0.05, record: false },
    ]);
    s.dt = 2e-3; // several times the explicit limit (about 0.5 ms)
    s.integrator = Some(Integrator::Symplectic);
    let e = run(&s).expect_err("a forced explicit step above its limit is refused").to_string();
    assert!(e.contains("stability limit"), "{e}");
    // The implicit integrator at the same dt stays bounded.
    s.integrator = Some(Integrator::Implicit);
    let out = run(&s).expect("script runs");
    assert!(out.blow_ups.is_empty(), "{:?}", out.blow_ups);
    for e in &out.events {
        assert!(e.positions.iter().flatten().flatten().all(|v| v.is_finite()));
    }
}

#[test]
fn a_persistent_blow_up_stops_the_run_with_one_message() {
    // A 1e9 N load case diverges on every step: the guard gives up after a few recoveries.
    let mut s = script(vec![Action::Wait { duration_s: 1.0, record: false }]);
    s.clamp = "A_clamped_ax3_F1000000000".into();
    s.integrator = Some(Integrator::Prefactored);
    let e = run(&s).expect_err("the guard stops the run").to_string();
    assert!(e.contains("blow-ups in a row"), "{e}");
    assert_eq!(e.matches("blow-up").count(), 1, "one message: {e}");
}

#[test]
fn positions_are_recorded_only_where_asked_and_for_the_last_action() {
    let out = run(&script(vec![
        Action::Wait { duration_s: 0.001, record: false },
        Action::Wait { duration_s: 0.001, record: true },
        Action::Wait { duration_s: 0.001, record: false },
        Action::Wait { duration_s: 0.001, record: false },
    ]))
    .expect("script runs");
    let recorded: Vec<bool> = out.events.iter().map(|e| e.positions.is_some()).collect();
    assert_eq!(recorded, [false, true, false, true]);
    let json = serde_json::to_value(&out).expect("json");
    assert!(json["events"][0].get("positions").is_none());
    assert_eq!(json["events"][3]["positions"].as_array().map(Vec::len), Some(512));
}

#[test]
fn script_bounds_are_named_before_any_work() {
    // Total steps: 200 actions of 100 s at 1e-4 s is 2e8 steps.
    let s = script((0..200).map(|_| Action::Wait { duration_s: 100.0, record: false }).collect());
    let e = run(&s).expect_err("too many steps").to_string();
    assert!(e.contains("steps in all") && e.contains("bound"), "{e}");
    let s =
        script((0..=tissue_studies::study::script::MAX_ACTIONS).map(|_| Action::Release { record: false }).collect());
    assert!(run(&s).expect_err("too many actions").to_string().contains("actions"));
    let s = script((0..300).map(|_| Action::Release { record: true }).collect());
    assert!(run(&s).expect_err("too many recorded").to_string().contains("record"));
    // A drag target typed in millimetres, and an absurd probe.
    let s = script(vec![Action::Drag { node: 511, to: [120.0, 100.0, 100.0], duration_s: 0.2, record: false }]);
    let e = run(&s).expect_err("millimetres").to_string();
    assert!(e.contains("metres"), "{e}");
    let s = script(vec![Action::Probe {
        at: TOP_NODE,
        direction: [0.0, 0.0, -1.0],
        radius: 1e300,
        depth: 1e300,
        duration_s: 0.1,
        samples: 2,
        record: false,
    }]);
    let e = run(&s).expect_err("absurd probe").to_string();
    assert!(e.contains("radius"), "{e}");
}

#[test]
fn soak_drags_probes_and_releases_stay_finite_and_return_to_rest() {
    // About 30 simulated seconds of interaction at the viewer's step: 300,000 steps.
    let mut actions = Vec::new();
    let top = |i: usize| [(i % 8) as f64 * 0.1 / 7.0, (i / 8 % 8) as f64 * 0.1 / 7.0, 0.1];
    for round in 0..10 {
        let node = 448 + (round * 13) % 64; // top-face nodes
        let r = tissue_core::mechanics::grid::Grid::paper().position(node);
        let to = [r[0] + 0.01 * (round % 3) as f64 - 0.01, r[1] + 0.005, r[2] + 0.01];
        actions.push(Action::Drag { node, to, duration_s: 0.3, record: false });
        actions.push(Action::Wait { duration_s: 0.5, record: false });
        actions.push(Action::Release { record: false });
        actions.push(Action::Wait { duration_s: 0.5, record: false });
        actions.push(Action::Probe {
            at: top((round * 7 + 9) % 64),
            direction: [0.0, 0.0, -1.0],
            radius: 0.015,
            depth: 0.002 + 0.0005 * (round % 5) as f64,
            duration_s: 0.4,
            samples: 4,
            record: false,
        });
        actions.push(Action::Wait { duration_s: 0.3, record: false });
        actions.push(Action::Release { record: false });
        actions.push(Action::Wait { duration_s: 0.5, record: false });
    }
    actions.push(Action::Wait { duration_s: 2.0, record: false });
    let out = run(&script(actions)).expect("soak runs");
    assert!(out.blow_ups.is_empty(), "{:?}", out.blow_ups);
    assert!(out.steps > 250_000, "{} steps", out.steps);
    out.check_finite().expect("finite");
    for e in &out.events {
        let f = e.tool_force_n.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(f < 100.0, "action {}: tool force {f} N", e.action);
        assert!(e.max_displacement_m < 0.05, "action {}: {} m", e.action, e.max_displacement_m);
    }
    for s in &out.force_depth {
        assert!(s.force_n.is_finite() && s.force_n >= 0.0 && s.force_n < 100.0, "{s:?}");
    }
    let end = out.events.last().expect("events");
    assert!(end.max_displacement_m < 1e-6, "not back at rest: {}", end.max_displacement_m);
}

#[test]
fn bad_scripts_are_refused_with_a_reason() {
    let mut s = script(vec![Action::Wait { duration_s: 0.01, record: false }]);
    s.clamp = "A_patch_ax1_F10".into();
    let e = run(&s).expect_err("patch supports are not modelled").to_string();
    assert!(e.contains("patch"), "{e}");
    let mut s = script(vec![Action::Wait { duration_s: 100.0, record: false }]);
    s.dt = 1e-7;
    assert!(run(&s).expect_err("dt too small").to_string().contains("dt"));
    let s = script(vec![Action::Drag { node: 9999, to: [0.0; 3], duration_s: 0.1, record: false }]);
    assert!(run(&s).expect_err("no such node").to_string().contains("node 9999"));
}

/// A script may name a material file in place of an object, from the script's folder; giving
/// both, or neither, is refused by name.
#[test]
fn a_script_takes_a_material_file_from_its_folder() {
    let script = |keys: serde_json::Value| -> Script {
        let mut s = serde_json::json!({
            "model": "fem-linear", "contact": "nodes",
            "actions": [{ "probe": { "at": [0.05, 0.05, 0.1], "direction": [0, 0, -1], "radius": 0.015,
                                     "depth": 0.004, "duration_s": 0.05, "samples": 2 } }]
        });
        s.as_object_mut().expect("an object").extend(keys.as_object().expect("keys").clone());
        serde_json::from_value(s).expect("a script")
    };
    let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/examples");
    let own =
        tissue_studies::study::script::run_from(&script(serde_json::json!({ "material": "my_tissue.toml" })), &folder)
            .expect("the material file's script runs");
    assert_eq!(own.object, "my_tissue");
    assert!(own.force_depth.last().is_some_and(|s| s.force_n > 0.0));
    let both = script(serde_json::json!({ "object": "A", "material": "my_tissue.toml" }));
    let e = tissue_studies::study::script::run_from(&both, &folder).expect_err("both refused");
    assert!(format!("{e:#}").contains("not both"), "{e:#}");
    let e = run(&script(serde_json::json!({}))).expect_err("neither refused");
    assert!(format!("{e:#}").contains("\"material\""), "{e:#}");
    let e = run(&script(serde_json::json!({ "material": "no/such/file.toml" }))).expect_err("a missing file refused");
    assert!(format!("{e:#}").contains("no/such/file.toml"), "{e:#}");
    // A material with a lump: the model takes it (the FEM's elements), so its own node contact
    // feels it, as the probe's surface contact does.
    let force = |s: &Script| {
        let out = tissue_studies::study::script::run_from(s, &folder).expect("the script runs");
        out.force_depth.last().expect("a sample").force_n
    };
    let on_nodes = force(&script(serde_json::json!({ "material": "lump_5x_r8.toml" })))
        / force(&script(serde_json::json!({ "object": "A" })));
    assert!((1.01..1.5).contains(&on_nodes), "the model's lump on its nodes {on_nodes}");
    let felt = |keys: serde_json::Value| {
        let mut s = script(keys);
        s.contact = tissue_core::sim::press::Contact::Surface;
        let out = tissue_studies::study::script::run_from(&s, &folder).expect("the script runs");
        out.force_depth.last().expect("a sample").force_n
    };
    let ratio = felt(serde_json::json!({ "material": "lump_5x_r8.toml" })) / felt(serde_json::json!({ "object": "A" }));
    assert!((1.03..1.13).contains(&ratio), "the lump's contrast {ratio}");
}
