//! `simulate`: compact bounded output, the blow-up guard, presses and probe paths on the material.

use crate::*;

#[test]
fn simulate_writes_compact_bounded_output_and_stops_on_a_persistent_blow_up() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out.json");
    let o = run(&["simulate", "--script", "assets/examples/interaction.json", "--out", out.to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&out).expect("written");
    assert_eq!(text.trim_end().lines().count(), 1, "compact JSON");
    let v: serde_json::Value = serde_json::from_str(&text).expect("json");
    let events = v["events"].as_array().expect("events");
    let with: Vec<bool> = events.iter().map(|e| e.get("positions").is_some()).collect();
    assert!(with[0] && *with.last().expect("last") && with.iter().filter(|w| **w).count() == 2, "{with:?}");
    for key in ["object", "model", "integrator", "dt", "nodes_per_axis", "steps", "force_depth", "blow_ups"] {
        assert!(v.get(key).is_some(), "key {key}");
    }
    // A blow-up that persists: a 1e9 N load. One message, exit 1, no output.
    let script = dir.path().join("blow.json");
    std::fs::write(
        &script,
        r#"{"object":"A","clamp":"A_clamped_ax3_F1000000000","integrator":"prefactored","actions":[{"wait":{"duration_s":1.0}}]}"#,
    )
    .expect("write");
    let never = dir.path().join("never.json");
    let o = run(&["simulate", "--script", script.to_str().expect("utf8"), "--out", never.to_str().expect("utf8")]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(stderr(&o).trim_end().lines().count(), 1, "{}", stderr(&o));
    assert!(stderr(&o).contains("blow-ups in a row"), "{}", stderr(&o));
    assert!(!never.exists());
}

/// The paper's axis lattice under the viewer's probe: it cannot carry the surface compliance's
/// contact forces (nothing resists a layer's slide; before, its columns folded over and a node
/// left the cube 0.66 s into a held 4 mm press), so it shows the press by its own node contact
/// while the hand feels the material: the force under the hex lattice within 0.1 % (the axis
/// lattice has no ratio damping, so its force is the static one).
#[test]
fn the_axis_lattice_holds_a_press_on_the_materials_surface() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out.json");
    let mut felt = Vec::new();
    for model in ["axis", "hex"] {
        let script = dir.path().join(format!("{model}.json"));
        std::fs::write(
            &script,
            format!(
                r#"{{"object":"A","model":"{model}","dt":1e-3,"actions":[
                {{"probe":{{"at":[0.03,0.05,0.1],"direction":[0,0,-1],"radius":0.015,"depth":0.004,
                  "duration_s":0.1,"samples":2}}}},{{"wait":{{"duration_s":2.0}}}}]}}"#
            ),
        )
        .expect("write");
        let o = run(&["simulate", "--script", script.to_str().expect("utf8"), "--out", out.to_str().expect("utf8")]);
        assert!(o.status.success(), "{model}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).expect("read")).expect("json");
        assert_eq!(v["contact"], "surface");
        assert_eq!(v["blow_ups"].as_array().map(Vec::len), Some(0), "{model}: {}", v["blow_ups"]);
        let last = &v["events"][1];
        let shown = last["max_displacement_m"].as_f64().expect("displacement");
        assert!(shown > 0.002 && shown < 0.006, "{model}: largest displacement {shown} m under a 4 mm press");
        felt.push(last["tool_force_n"][2].as_f64().expect("force"));
    }
    assert!(felt[0] > 5.0 && (felt[0] - felt[1]).abs() < 1e-3 * felt[1], "{felt:?}");
}

#[test]
fn a_probe_path_presses_and_slides_with_the_materials_force_on_any_grid() {
    let dir = tempfile::tempdir().expect("tempdir");
    let script = dir.path().join("path.json");
    let out = dir.path().join("out.json");
    // On a 12^3 grid (node 1727 is its far top corner), the viewer's surface contact.
    std::fs::write(
        &script,
        r#"{"object":"A","dt":1e-3,"nodes":12,"actions":[
            {"probe_path":{"radius":0.015,"direction":[0,0,-1],"sample_hz":20,"keys":[
                {"t":0.0,"at":[0.03,0.05,0.1],"depth":0.0},
                {"t":0.2,"at":[0.03,0.05,0.1],"depth":0.004},
                {"t":0.6,"at":[0.07,0.05,0.1],"depth":0.004}]}},
            {"release":{}},
            {"drag":{"node":1727,"to":[0.1,0.1,0.105],"duration_s":0.05}}]}"#,
    )
    .expect("write");
    let o = run(&["simulate", "--script", script.to_str().expect("utf8"), "--out", out.to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).expect("read")).expect("json");
    assert_eq!(v["nodes_per_axis"], 12);
    assert_eq!(v["contact"], "surface");
    let samples = v["force_path"].as_array().expect("force_path");
    // 20 Hz over 0.6 s: t = 0, 0.05, ..., 0.6.
    assert_eq!(samples.len(), 13, "{samples:?}");
    let mut last_t = -1.0;
    for s in samples {
        for key in ["action", "t", "at", "depth_m", "force_n", "force"] {
            assert!(s.get(key).is_some(), "sample without {key}: {s}");
        }
        let t = s["t"].as_f64().expect("t");
        assert!(t > last_t);
        last_t = t;
        let at: Vec<f64> = s["at"].as_array().expect("at").iter().map(|x| x.as_f64().expect("x")).collect();
        let expected_x = if t <= 0.2 { 0.03 } else { 0.03 + 0.04 * (t - 0.2) / 0.4 };
        assert!((at[0] - expected_x).abs() < 1e-9 && at[2] == 0.1, "{t}: {at:?}");
        let force = s["force"].as_array().expect("force");
        assert!((force[2].as_f64().expect("fz") - s["force_n"].as_f64().expect("fn")).abs() < 1e-12);
    }
    // Held 4 mm deep while sliding across the middle: the material's 9 to 10 N, smooth.
    let held: Vec<f64> =
        samples.iter().filter(|s| s["t"].as_f64() >= Some(0.2)).map(|s| s["force_n"].as_f64().expect("f")).collect();
    let (lo, hi) = held.iter().fold((f64::INFINITY, 0.0f64), |(l, h), &f| (l.min(f), h.max(f)));
    assert!(lo > 8.5 && hi < 10.5 && (hi - lo) / hi < 0.07, "{held:?}");
    // The bounds: keys that do not increase, a grid out of range, a node off the script's grid.
    for (bad, why) in [
        (
            r#""nodes":12,"actions":[{"probe_path":{"radius":0.01,"direction":[0,0,-1],"sample_hz":10,"keys":[{"t":0.1,"at":[0.05,0.05,0.1],"depth":0.001},{"t":0.1,"at":[0.05,0.05,0.1],"depth":0.002}]}}]"#,
            "does not increase",
        ),
        (
            r#""nodes":12,"actions":[{"probe_path":{"radius":0.01,"direction":[0,0,-1],"sample_hz":0,"keys":[{"t":0.1,"at":[0.05,0.05,0.1],"depth":0.001}]}}]"#,
            "sample_hz",
        ),
        (
            r#""nodes":12,"actions":[{"probe_path":{"radius":0.01,"direction":[0,0,-1],"sample_hz":10,"keys":[]}}]"#,
            "keys",
        ),
        (r#""nodes":3,"actions":[]"#, "nodes = 3"),
        (r#""nodes":8,"actions":[{"drag":{"node":1727,"to":[0.1,0.1,0.1],"duration_s":0.1}}]"#, "8^3 grid"),
    ] {
        std::fs::write(&script, format!(r#"{{"object":"A",{bad}}}"#)).expect("write");
        let o = run(&["simulate", "--script", script.to_str().expect("utf8"), "--out", out.to_str().expect("utf8")]);
        assert_eq!(o.status.code(), Some(1), "{bad}");
        assert!(stderr(&o).contains(why), "{bad}: {}", stderr(&o));
    }
}
