//! `chart` and `choose`: round trips, bad budgets, checked files, interrupted runs.

use crate::*;

#[test]
#[ignore = "slow: in the slow group, cargo test --release -- --ignored"]
fn chart_then_choose_round_trip_and_bad_budgets() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("chart");
    let out_s = out.to_str().expect("utf8");
    let o = run(&["chart", "--out", out_s, "--objects", "A", "--resolutions", "4,8", "--no-stability"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(out.join("chart.csv")).expect("chart.csv");
    // 4 charted models (not the paper's axis lattice) x 2 resolutions x (1 explicit + 6 implicit
    // steps + 1 Newmark step), plus the header.
    assert_eq!(csv.lines().count(), 65, "{csv}");
    assert_eq!(csv.lines().filter(|l| l.contains(",newmark,")).count(), 8, "{csv}");
    assert!(!csv.contains("msm-axis"), "the axis lattice has no held-out score");
    let header = csv.lines().next().expect("header");
    assert!(header.contains("avg_err_pct") && header.contains("force_err_pct"), "{header}");
    // Touch force errors at the viewer's 8^3 scene only.
    let points = tissue_studies::study::read_chart_csv(&out).expect("reads back");
    assert!(points.iter().all(|p| (p.n == 8) != p.force_err_pct.is_nan()), "{csv}");
    // Dynamic errors too, and the cost per simulated second is the step's time over its step.
    assert!(points.iter().all(|p| (p.n == 8) != p.dyn_err_pct.is_nan() && (p.n == 8) != p.period_err_pct.is_nan()));
    assert!(points.iter().all(|p| (p.cost_per_sim_s / (p.step_s / p.dt_s) - 1.0).abs() < 1e-12));
    assert!(points.iter().any(|p| p.pareto_dynamic), "a dynamic Pareto front is marked");
    // The probe against the material at every resolution: the model's own node contact, and the
    // material's surface compliance (measured worst 2.7 %, A's held-out presses).
    assert!(header.contains("probe_err_pct") && header.contains("surface_probe_err_pct"), "{header}");
    assert!(points.iter().all(|p| p.probe_err_pct.is_finite() && p.surface_probe_err_pct < 7.0), "{csv}");
    assert!(std::fs::read_to_string(out.join("chart_dynamic.svg")).expect("svg").contains("<svg"));
    let md = std::fs::read_to_string(out.join("chart.md")).expect("md");
    assert!(md.contains("Where the dynamic error crosses 5 %"), "{md}");
    assert!(csv.contains(",true"), "a Pareto front is marked");
    assert!(std::fs::read_to_string(out.join("chart.svg")).expect("svg").contains("<svg"));
    let chart = out.join("chart.csv");
    let chart_s = chart.to_str().expect("utf8");
    // A rate every model meets on any machine: the round trip is tested here, not the speed (that
    // is `bench`'s; with other tests running beside it a 1 ms tick is not assured).
    let o = run(&["choose", "--chart", chart_s, "--max-error", "5", "--rate", "100"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("Chosen:") && text.contains("probe force error"), "{text}");
    // Dynamic budgets beside the static one.
    let o =
        run(&["choose", "--chart", chart_s, "--max-period-error", "2", "--max-damping-error", "1", "--rate", "100"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("period error <= 2 %") && text.contains("damping ratio error <= 1 % of critical"), "{text}");
    let o = run(&["choose", "--chart", chart_s, "--max-damping-error", "0"]);
    assert!(!o.status.success() && stderr(&o).contains("--max-damping-error"), "{}", stderr(&o));
    // An impossible budget: a clear message and a non-zero exit.
    let o = run(&["choose", "--chart", chart_s, "--max-error", "0.00001"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("No model meets"));
    for bad in [
        vec!["choose", "--chart", chart_s, "--max-error", "-1"],
        vec!["choose", "--chart", chart_s, "--max-probe-error", "-1"],
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

#[test]
fn chart_files_are_checked_and_an_interrupted_chart_leaves_no_directory() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bad = dir.path().join("bad.csv");
    std::fs::write(
        &bad,
        "object,model,n,integrator,step_s,dt_max_s,dt_s,cost_per_sim_s,static_s,memory_bytes,avg_err_pct,max_err_pct,\
         force_err_pct,dyn_err_pct,tap_err_pct,period_err_pct,damping_err_pct,pareto,pareto_dynamic\n\
         A,msm-hex,4,explicit,-7,1e-3,9e-4,1e-3,1e-3,100,0.5,1.0,NaN,NaN,NaN,NaN,NaN,true,false\n",
    )
    .expect("write");
    let o = run(&["choose", "--chart", bad.to_str().expect("utf8"), "--max-error", "5"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("step_s"), "{}", stderr(&o));
    // Interrupted while computing: nothing appears at --out.
    let out = dir.path().join("chart");
    let mut child = Command::new(env!("CARGO_BIN_EXE_tissue-sim"))
        .args(["chart", "--out", out.to_str().expect("utf8"), "--objects", "A", "--resolutions", "4"])
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("spawn");
    std::thread::sleep(std::time::Duration::from_millis(800));
    child.kill().expect("kill");
    let _ = child.wait();
    assert!(!out.exists(), "an interrupted chart left {}", out.display());
}
