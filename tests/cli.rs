//! Command-line round trips and bad-input handling of the `tissue-sim` binary.

use std::path::Path;
use std::process::{Command, Output};

use tissue_sim::io::DisplacementFile;

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tissue-sim")).args(args).output().expect("binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn read(path: &Path) -> DisplacementFile {
    serde_json::from_str(&std::fs::read_to_string(path).expect("file written")).expect("valid JSON")
}

#[test]
fn fem_writes_the_spec_format_and_reads_back() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("fem_A.json");
    let o = run(&["fem", "--object", "A", "--bc", "clamped", "--out", out.to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let file = read(&out);
    assert_eq!((file.object.as_str(), file.bc.as_str(), file.model.as_str()), ("A", "clamped", "fem"));
    assert_eq!(file.nodes_per_axis, 8);
    assert_eq!(file.cases.len(), 9);
    assert_eq!(file.cases[0].case_id, "A_clamped_ax1_F1");
    assert_eq!(file.cases[8].case_id, "A_clamped_ax3_F10");
    for c in &file.cases {
        assert_eq!(c.displacements.len(), 512);
    }
    // The raw JSON keys of the spec.
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).expect("read")).expect("json");
    assert!(v["cases"][0]["force_N"].is_number());
    assert!(v["cases"][0]["displacements"][511][0].is_number());
    // Same numbers as the library computes.
    let grid = tissue_sim::grid::Grid::paper();
    let cases = tissue_sim::cases::benchmark_cases(&grid, "A", tissue_sim::cases::Bc::Clamped);
    let sols = tissue_sim::fem::FemModel::new(grid, &tissue_sim::material::Material::object_a())
        .solve_cases(&cases)
        .expect("solve");
    assert!(file.cases[4].displacements == sols[4].displacements, "JSON does not round-trip exactly");
}

#[test]
fn patch_and_msm_commands() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("patch.json");
    let o = run(&["fem", "--object", "b", "--bc", "patch", "--out", out.to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(read(&out).cases[3].case_id, "B_patch_ax2_F1");
    let out = dir.path().join("msm.json");
    let o = run(&["msm", "--object", "B", "--k1", "735.5", "--k2", "679.9", "--out", out.to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let file = read(&out);
    assert_eq!(file.model, "msm");
    let tip = file.cases[8].displacements[511][2];
    assert!((tip - 7.0 * 10.0 / 64.0 / 679.9).abs() < 1e-15, "{tip}");
}

#[test]
fn errors_prints_table_and_json() {
    let o = run(&["errors", "--object", "A", "--k1", "968.2", "--k2", "1010", "--k3", "1137.7"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("Axis 3") && text.contains("10 N"), "{text}");
    let o = run(&["errors", "--object", "A", "--k1", "968.2", "--k2", "1010", "--k3", "1137.7", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(v["cases"].as_array().map(Vec::len), Some(9));
    assert!(v["cost"].as_f64().is_some_and(|c| c > 0.0));
    // The same parameters from a calibration-style file.
    let dir = tempfile::tempdir().expect("tempdir");
    let p = dir.path().join("cal.json");
    std::fs::write(&p, r#"{"object":"A","params":{"k1":968.2,"k2":1010.0,"k3":1137.7,"d":795.3}}"#).expect("write");
    let o2 = run(&["errors", "--params", p.to_str().expect("utf8"), "--json"]);
    assert!(o2.status.success(), "{}", stderr(&o2));
    let v2: serde_json::Value = serde_json::from_slice(&o2.stdout).expect("json");
    assert_eq!(v["cost"], v2["cost"]);
}

#[test]
fn material_file_gives_the_same_answer_as_the_preset() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mat = dir.path().join("a.toml");
    std::fs::write(
        &mat,
        "name = \"A\"\nsymmetry = \"orthotropic\"\nunits = \"kPa\"\nE1 = 179.0\nE2 = 188.0\nE3 = 228.0\n\
         nu12 = 0.26\nnu13 = 0.30\nnu23 = 0.31\nG12 = 57.1\nG13 = 65.8\nG23 = 71.1\n",
    )
    .expect("write");
    let (o1, o2) = (dir.path().join("1.json"), dir.path().join("2.json"));
    let a = run(&["fem", "--material", mat.to_str().expect("utf8"), "--out", o1.to_str().expect("utf8")]);
    let b = run(&["fem", "--object", "A", "--out", o2.to_str().expect("utf8")]);
    assert!(a.status.success() && b.status.success(), "{}", stderr(&a));
    assert_eq!(read(&o1), read(&o2));
}

#[test]
fn bad_input_fails_cleanly_without_output() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("never.json");
    let o = out.to_str().expect("utf8");
    let bad_mat = dir.path().join("bad.toml");
    std::fs::write(
        &bad_mat,
        "symmetry = \"orthotropic\"\nE1 = 1.0\nE2 = 1.0\nE3 = 1.0\nnu12 = 0.9\nnu13 = 0.9\nnu23 = 0.9\n\
         G12 = 1.0\nG13 = 1.0\nG23 = 1.0\n",
    )
    .expect("write");
    let missing = dir.path().join("missing.toml");
    let nan_mat = dir.path().join("nan.json");
    std::fs::write(
        &nan_mat,
        r#"{"symmetry":"transversely_isotropic","E1":1e5,"E2":-2e5,"nu12":0.3,"nu23":0.3,"G12":3e4}"#,
    )
    .expect("write");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["fem", "--object", "C", "--out", o], "possible values"),
        (vec!["fem", "--object", "A", "--nodes", "1", "--out", o], "at least 2"),
        (vec!["msm", "--object", "A", "--k1", "-5", "--k2", "1", "--k3", "1", "--out", o], "k1"),
        (vec!["msm", "--object", "A", "--k1", "NaN", "--k2", "1", "--k3", "1", "--out", o], "k1"),
        (vec!["msm", "--object", "A", "--k1", "1", "--k2", "1", "--out", o], "--k3"),
        (vec!["msm", "--object", "B", "--k1", "1", "--k2", "1", "--k3", "2", "--out", o], "transversely isotropic"),
        (vec!["fem", "--material", bad_mat.to_str().expect("utf8"), "--out", o], "positive definite"),
        (vec!["fem", "--material", missing.to_str().expect("utf8"), "--out", o], "cannot read"),
        (vec!["fem", "--material", nan_mat.to_str().expect("utf8"), "--out", o], "E2"),
        (vec!["fem", "--object", "A", "--out", "/nonexistent-dir/x.json"], "cannot"),
    ];
    for (args, needle) in cases {
        let r = run(&args);
        assert!(!r.status.success(), "{args:?} should fail");
        let msg = stderr(&r);
        assert!(msg.contains(needle), "{args:?}: {msg}");
        assert!(!msg.contains("panicked"), "{args:?}: {msg}");
        assert!(!out.exists(), "{args:?} left a file");
    }
}

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
fn chart_then_choose_round_trip_and_bad_budgets() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("chart");
    let out_s = out.to_str().expect("utf8");
    let o = run(&["chart", "--out", out_s, "--objects", "A", "--resolutions", "4,6", "--no-stability"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(out.join("chart.csv")).expect("chart.csv");
    // 5 models x 2 resolutions x 2 integrators, plus the header.
    assert_eq!(csv.lines().count(), 21, "{csv}");
    assert!(csv.lines().next().expect("header").contains("avg_err_pct"));
    assert!(csv.contains(",true"), "a Pareto front is marked");
    assert!(std::fs::read_to_string(out.join("chart.svg")).expect("svg").contains("<svg"));
    let chart = out.join("chart.csv");
    let chart_s = chart.to_str().expect("utf8");
    let o = run(&["choose", "--chart", chart_s, "--max-error", "5", "--rate", "1000"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("Chosen:"), "{text}");
    // An impossible budget: a clear message and a non-zero exit.
    let o = run(&["choose", "--chart", chart_s, "--max-error", "0.00001"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("No model meets"));
    for bad in [
        vec!["choose", "--chart", chart_s, "--max-error", "-1"],
        vec!["choose", "--chart", chart_s, "--max-error", "1", "--rate", "0"],
        vec!["choose", "--chart", "/nonexistent/chart.csv", "--max-error", "1"],
        vec!["chart", "--out", out_s, "--resolutions", "50"],
        vec!["chart", "--out", out_s, "--objects", "C"],
    ] {
        let o = run(&bad);
        assert!(!o.status.success(), "{bad:?} must fail");
        assert!(stderr(&o).contains("error:"), "{bad:?}: {}", stderr(&o));
    }
}
