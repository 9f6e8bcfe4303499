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
        assert!(o.stderr.is_empty(), "quiet when not on a terminal: {}", stderr(&o));
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
