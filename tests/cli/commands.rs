//! The static commands (`fem`, `msm`, `errors`) and their files.

use crate::*;

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
    let grid = tissue_core::mechanics::grid::Grid::paper();
    let cases = tissue_core::mechanics::cases::benchmark_cases(&grid, "A", tissue_core::mechanics::cases::Bc::Clamped);
    let sols =
        tissue_core::mechanics::fem::FemModel::new(grid, &tissue_core::mechanics::material::Material::object_a())
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

/// Every headless command ends with one summary line on standard error (what it wrote, the figure
/// that matters, a warning such as a gene on its bound), and `--quiet` leaves standard error
/// empty on success.
#[test]
fn the_commands_end_with_a_summary_and_quiet_says_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("fem.json");
    let out_s = out.to_str().expect("utf8");
    let o = run(&["fem", "--object", "A", "--out", out_s]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.starts_with("fem: 9 clamped cases of material A at 8^3 written to "), "{err}");
    assert!(err.contains("largest displacement ") && err.trim_end().lines().count() == 1, "{err}");
    let o = run(&["fem", "--object", "A", "--out", out_s, "--quiet"]);
    assert!(o.status.success() && stderr(&o).is_empty(), "{}", stderr(&o));
    let o = run(&["--quiet", "errors", "--object", "A", "--k1", "968.2", "--k2", "1010", "--k3", "1137.7"]);
    assert!(o.status.success() && stderr(&o).is_empty() && !o.stdout.is_empty(), "{}", stderr(&o));
    let o = run(&["errors", "--object", "A", "--k1", "968.2", "--k2", "1010", "--k3", "1137.7"]);
    assert!(
        stderr(&o).starts_with("errors: the axis lattice of material A at 8^3 on 9 clamped cases"),
        "{}",
        stderr(&o)
    );
    // The README's shear calibration of B: k2 ends on its lower bound, and the summary says so.
    let cal = dir.path().join("cal.json");
    let o = run(&["calibrate", "--object", "B", "--model", "shear", "--out", cal.to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.starts_with("calibrate: the shear lattice of material B written to "), "{err}");
    assert!(err.contains("k2 = ") && err.contains("cost "), "{err}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&cal).expect("read")).expect("json");
    let (k2, lo) = (v["params"]["k2"].as_f64().expect("k2"), v["bounds"]["lo"][1].as_f64().expect("lo"));
    if (k2 - lo).abs() <= 1e-3 * lo {
        assert!(err.contains("warning: k2 = ") && err.contains("is on its lower bound"), "{err}");
    }
}
