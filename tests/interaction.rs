//! Scripted interaction (the `simulate` command's engine): deterministic and physically sane.

use tissue_sim::script::{Action, Script, run};
use tissue_sim::sim::Integrator;

fn script(actions: Vec<Action>) -> Script {
    Script {
        object: "A".into(),
        model: tissue_sim::msm::Topology::Shear,
        dt: 1e-4,
        integrator: None,
        clamp: "bottom".into(),
        actions,
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
        },
        Action::Wait { duration_s: 0.1 },
        Action::Release {},
        Action::Wait { duration_s: 1.0 },
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
    for x in &pushed.positions {
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
        Action::Drag { node: 511, to: [0.12, 0.1, 0.1], duration_s: 0.2 },
        Action::Wait { duration_s: 0.3 },
        Action::Release {},
        Action::Wait { duration_s: 1.0 },
    ]))
    .expect("script runs");
    let held = &out.events[1];
    let x = held.positions[511][0];
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
fn explicit_blow_up_is_caught_and_nothing_nan_is_reported() {
    let mut s = script(vec![
        Action::Drag { node: 511, to: [0.12, 0.1, 0.1], duration_s: 0.05 },
        Action::Wait { duration_s: 0.05 },
    ]);
    s.dt = 2e-3; // several times the explicit limit (about 0.5 ms)
    s.integrator = Some(Integrator::Symplectic);
    let out = run(&s).expect("script runs");
    assert!(!out.blow_ups.is_empty(), "the guard must report the divergence");
    assert!(out.blow_ups[0].contains("stability limit"), "{}", out.blow_ups[0]);
    for e in &out.events {
        assert!(e.positions.iter().flatten().all(|v| v.is_finite()));
    }
    // The implicit integrator at the same dt stays bounded.
    s.integrator = Some(Integrator::Implicit);
    let out = run(&s).expect("script runs");
    assert!(out.blow_ups.is_empty(), "{:?}", out.blow_ups);
}

#[test]
fn bad_scripts_are_refused_with_a_reason() {
    let mut s = script(vec![Action::Wait { duration_s: 0.01 }]);
    s.clamp = "A_patch_ax1_F10".into();
    let e = run(&s).expect_err("patch supports are not modelled").to_string();
    assert!(e.contains("patch"), "{e}");
    let mut s = script(vec![Action::Wait { duration_s: 100.0 }]);
    s.dt = 1e-7;
    assert!(run(&s).expect_err("dt too small").to_string().contains("dt"));
    let s = script(vec![Action::Drag { node: 9999, to: [0.0; 3], duration_s: 0.1 }]);
    assert!(run(&s).expect_err("no such node").to_string().contains("node 9999"));
}
