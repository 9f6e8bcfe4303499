//! `calibrate`: the spec's result, deterministic; the touch cases, the polish, the stiffness fit.

use crate::*;

#[test]
fn calibrate_writes_the_spec_result_deterministically() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (a, b) = (dir.path().join("a.json"), dir.path().join("b.json"));
    for out in [&a, &b] {
        let o = run(&[
            "calibrate",
            "--object",
            "B",
            "--method",
            "hybrid",
            "--seed",
            "5",
            "--out",
            out.to_str().expect("utf8"),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        // No progress bar when not on a terminal: the summary line only.
        let err = stderr(&o);
        assert!(err.starts_with("calibrate: the axis lattice of material B") && err.lines().count() == 1, "{err}");
    }
    let strip = |p: &Path| {
        let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(p).expect("read")).expect("json");
        v["wall_s"] = serde_json::Value::Null;
        v
    };
    let v = strip(&a);
    assert_eq!(v, strip(&b), "same seed, same result (wall time aside)");
    for key in
        ["object", "method", "seed", "population", "generations", "model", "params", "cost", "evaluations", "history"]
    {
        assert!(!v[key].is_null(), "missing key {key}");
    }
    assert_eq!(
        (v["object"].as_str(), v["method"].as_str(), v["model"].as_str()),
        (Some("B"), Some("hybrid"), Some("axis"))
    );
    assert_eq!(v["params"]["k3"], v["params"]["k2"]);
    assert_eq!(v["history"][100]["generation"].as_u64(), Some(100));
    for key in ["best_cost", "mean_fitness", "std_fitness"] {
        assert!(v["history"][0][key].is_number(), "history key {key}");
    }
    // errors --params reads it back.
    let o = run(&["errors", "--params", a.to_str().expect("utf8"), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    let rel = (e["cost"].as_f64().expect("cost") / v["cost"].as_f64().expect("cost") - 1.0).abs();
    assert!(rel < 1e-9, "errors recomputes the calibrated cost ({rel:e})");
    // Bad settings are refused.
    let o = run(&["calibrate", "--object", "A", "--mutation", "1.5", "--out", a.to_str().expect("utf8")]);
    assert!(!o.status.success() && stderr(&o).contains("mutation"));
    let o = run(&["calibrate", "--object", "A", "--bound", "k9=1:2", "--out", a.to_str().expect("utf8")]);
    assert!(!o.status.success() && stderr(&o).contains("no gene"));
}

#[test]
fn calibrate_on_touch_cases_polishes_and_the_stiffness_fit_runs() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("touch.json");
    let args = ["calibrate", "--object", "B", "--model", "hex", "--cases", "touch", "--nodes", "5"];
    let o =
        run(&[&args[..], &["--population", "8", "--generations", "4", "--out", out.to_str().expect("utf8")]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).expect("read")).expect("json");
    assert_eq!(v["cases"], "touch");
    let polish = &v["polish"];
    assert!(polish["cost"].as_f64().expect("cost") <= polish["start_cost"].as_f64().expect("start"));
    assert_eq!(v["cost"], polish["cost"]);
    let out = dir.path().join("fit.json");
    let o = run(&[
        "calibrate",
        "--object",
        "A",
        "--model",
        "shear",
        "--method",
        "stiffness-fit",
        "--out",
        out.to_str().expect("utf8"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).expect("read")).expect("json");
    assert_eq!(v["method"], "stiffness-fit");
    assert!(v["params"]["c12"].as_f64().is_some());
    let o = run(&[
        "calibrate",
        "--object",
        "A",
        "--model",
        "axis",
        "--cases",
        "touch",
        "--out",
        out.to_str().expect("utf8"),
    ]);
    assert!(!o.status.success() && stderr(&o).contains("no shear stiffness"), "{}", stderr(&o));
}

#[test]
fn calibrate_refuses_presses_that_touch_no_node_at_once() {
    // On a 2^3 or 3^3 grid every training sphere passes between the top nodes: no press has a
    // contact, every force is zero whatever the stiffness, and the cost is 1. Refused before any
    // reference is computed, naming the grid and one that works.
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("presses.json");
    for nodes in ["2", "3"] {
        let started = std::time::Instant::now();
        let o = run(&[
            "calibrate",
            "--object",
            "A",
            "--model",
            "hex",
            "--cases",
            "presses",
            "--nodes",
            nodes,
            "--population",
            "2",
            "--generations",
            "1",
            "--out",
            out.to_str().expect("utf8"),
        ]);
        let took = started.elapsed().as_secs_f64();
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        let e = stderr(&o);
        assert!(e.contains(&format!("no training press touches a node of the {nodes}^3 grid")), "{e}");
        assert!(e.contains("--nodes 4") && e.lines().count() == 1, "{e}");
        assert!(took < 2.0, "refused after {took} s");
        assert!(!out.exists(), "nothing written");
    }
}

#[test]
fn calibrate_refuses_a_cost_mode_its_cases_or_method_cannot_use() {
    // The transient cost integrates only the paper's nine face loads: with other cases it would
    // train on those and name the others. The load-free stiffness fit identifies no damping.
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("transient.json");
    for cases in ["presses", "touch", "both"] {
        let started = std::time::Instant::now();
        let o = run(&[
            "calibrate",
            "--object",
            "A",
            "--model",
            "hex",
            "--cost",
            "transient",
            "--cases",
            cases,
            "--population",
            "2",
            "--generations",
            "1",
            "--out",
            out.to_str().expect("utf8"),
        ]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains(&format!("--cost transient cannot use --cases {cases}")), "{}", stderr(&o));
        assert!(started.elapsed().as_secs_f64() < 2.0, "refused after {:?}", started.elapsed());
        assert!(!out.exists(), "nothing written");
    }
    let o = run(&[
        "calibrate",
        "--object",
        "A",
        "--method",
        "stiffness-fit",
        "--cost",
        "transient",
        "--out",
        out.to_str().expect("utf8"),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--method stiffness-fit cannot use --cost transient"), "{}", stderr(&o));
    // The paper's cases still train the transient cost.
    let o = run(&[
        "calibrate",
        "--object",
        "B",
        "--cost",
        "transient",
        "--population",
        "4",
        "--generations",
        "2",
        "--out",
        out.to_str().expect("utf8"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).expect("read")).expect("json");
    assert_eq!((v["cases"].as_str(), v["d_identified"].as_bool()), (Some("paper"), Some(true)));
}

#[test]
fn calibrate_polish_stays_inside_the_box_it_reports() {
    // At 4^3 few training presses touch a node, so the press cost leaves several genes free: the
    // polish used to leave the box by up to 10^5. It ends inside, and names the bounds it is on.
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("presses4.json");
    let o = run(&[
        "calibrate",
        "--object",
        "A",
        "--model",
        "hex",
        "--cases",
        "presses",
        "--nodes",
        "4",
        "--population",
        "2",
        "--generations",
        "1",
        "--out",
        out.to_str().expect("utf8"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).expect("read")).expect("json");
    let names = v["bounds"]["names"].as_array().expect("names");
    let bound = |key: &str, i: usize| v["bounds"][key][i].as_f64().expect("bound");
    for (i, name) in names.iter().enumerate().filter(|(_, n)| n.as_str() != Some("d")) {
        let name = name.as_str().expect("name");
        let x = v["params"][name].as_f64().expect("gene");
        assert!(bound("lo", i) <= x && x <= bound("hi", i), "{name} = {x} outside its box");
    }
    assert!(v["polish"].get("left_box").is_none());
    for entry in v["polish"]["at_bound"].as_array().expect("at_bound") {
        let (name, side) = entry.as_str().and_then(|e| e.split_once('=')).expect("NAME=lo|hi");
        let i = names.iter().position(|n| n.as_str() == Some(name)).expect("a gene");
        let x = v["params"][name].as_f64().expect("gene");
        assert!((x / bound(side, i) - 1.0).abs() < 1e-6, "{entry}: {x}");
    }
}
