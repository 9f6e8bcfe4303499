//! Bad input: one clear line and exit code 1, before any work; outputs that are never a hazard.

use crate::*;

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
    let lump = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/examples/lump_5x_r8.toml");
    let outside = dir.path().join("outside.toml");
    let background = std::fs::read_to_string(lump).expect("the shipped lump").replace("0.082]", "0.095]");
    std::fs::write(&outside, background).expect("write");
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
        // A lump is read and checked whole, then refused where it is not modelled yet.
        (vec!["errors", "--material", lump, "--k1", "1", "--k2", "1", "--k3", "1"], "does not model inclusions yet"),
        (vec!["validate", "--material", lump, "--nodes", "13"], "at most 12 nodes"),
        (vec!["view", "--material", missing.to_str().expect("utf8")], "cannot read"),
        (vec!["fem", "--material", outside.to_str().expect("utf8"), "--out", o], "inclusion 1: its sphere"),
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
fn outputs_never_replace_special_files_links_or_protected_files() {
    use std::os::unix::fs::PermissionsExt as _;
    let dir = tempfile::tempdir().expect("tempdir");
    // A link to /dev/null: written through, /dev/null stays a device and the link stays a link.
    let null = dir.path().join("null.json");
    std::os::unix::fs::symlink("/dev/null", &null).expect("symlink");
    let o = run(&["fem", "--object", "A", "--nodes", "3", "--out", null.to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::symlink_metadata(&null).expect("meta").file_type().is_symlink());
    assert!(!std::fs::metadata("/dev/null").expect("meta").is_file());
    // `-` is standard output.
    let o = run(&["fem", "--object", "A", "--nodes", "3", "--out", "-"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON on stdout");
    assert_eq!(v["nodes_per_axis"].as_u64(), Some(3));
    let o = run(&["fem", "--object", "A", "--nodes", "3", "--out", "/dev/stdout"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON through /dev/stdout");
    assert_eq!(v["nodes_per_axis"].as_u64(), Some(3));
    // A write-protected file is refused, even for root.
    let locked = dir.path().join("locked.json");
    std::fs::write(&locked, "keep").expect("write");
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o444)).expect("chmod");
    let o = run(&["fem", "--object", "A", "--nodes", "3", "--out", locked.to_str().expect("utf8")]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("write-protected"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&locked).expect("read"), "keep");
}

#[test]
fn bad_input_gets_one_clear_line_and_exit_code_1() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("never.json");
    let o = out.to_str().expect("utf8");
    let missing = dir.path().join("missing.toml");
    let lump = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/examples/lump_5x_r8.toml");
    let outside = dir.path().join("outside.toml");
    let background = std::fs::read_to_string(lump).expect("the shipped lump").replace("0.082]", "0.095]");
    std::fs::write(&outside, background).expect("write");
    let short = dir.path().join("short.toml");
    std::fs::write(&short, "symmetry = \"orthotropic\"\nE1 = 1.0\n").expect("write");
    let broken = dir.path().join("broken.toml");
    std::fs::write(&broken, "symmetry = \"orthotropic\"\nE1 = = 1.0\n").expect("write");
    let huge = dir.path().join("huge.toml");
    std::fs::write(
        &huge,
        "symmetry = \"orthotropic\"\nunits = \"MPa\"\nE1 = 1e300\nE2 = 0.188\nE3 = 0.228\nnu12 = 0.26\nnu13 = 0.3\n\
         nu23 = 0.31\nG12 = 0.0571\nG13 = 0.0658\nG23 = 0.0711\n",
    )
    .expect("write");
    let params_b = dir.path().join("params_b.json");
    std::fs::write(&params_b, r#"{"object":"B","params":{"k1":700,"k2":600,"k3":650,"d":0}}"#).expect("write");
    let params_x = dir.path().join("params_x.json");
    std::fs::write(&params_x, r#"{"object":"A","params":{"k1":700,"k2":600,"k3":650,"d":0,"k4":1}}"#).expect("write");
    let m = |p: &Path| p.to_str().expect("utf8").to_owned();
    let (missing_s, short_s, broken_s, huge_s) = (m(&missing), m(&short), m(&broken), m(&huge));
    let (pb, px) = (m(&params_b), m(&params_x));
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["msm", "--object", "A", "--k1", "1e-320", "--k2", "1", "--k3", "1", "--out", o], "k1"),
        (vec!["msm", "--object", "A", "--k1", "-inf", "--k2", "1", "--k3", "1", "--out", o], "k1"),
        (vec!["calibrate", "--object", "A", "--mutation", "-0.1", "--out", o], "mutation"),
        (vec!["calibrate", "--object", "A", "--seed", "-1", "--out", o], "--seed"),
        (vec!["calibrate", "--object", "A", "--bound", "k1=1e300:1e301", "--out", o], "k1"),
        (vec!["calibrate", "--object", "A", "--population", "100000", "--generations", "1000", "--out", o], "bound"),
        (vec!["fem", "--material", &huge_s, "--out", o], "E1"),
        (vec!["fem", "--material", &short_s, "--out", o], "for an orthotropic material"),
        (vec!["fem", "--material", &broken_s, "--out", o], "line 2"),
        (vec!["fem", "--material", &missing_s, "--out", o], "No such file"),
        (vec!["fem", "--object", "A", "--nodes", "40", "--bc", "patch", "--out", o], "at most"),
        (
            vec!["msm", "--object", "A", "--nodes", "65", "--k1", "1", "--k2", "1", "--k3", "1", "--out", o],
            "at most 64",
        ),
        (vec!["errors", "--params", &pb], "k3 must equal k2"),
        (vec!["errors", "--params", &px], "k4"),
        (vec!["render", "--case", "A_clamped_ax1_F10", "--magnify", "1e30", "--out", o], "magnify"),
        (vec!["fem", "--object", "A", "--bogus"], "--bogus"),
    ];
    for (args, needle) in cases {
        let r = run(&args);
        assert_eq!(r.status.code(), Some(1), "{args:?} should exit 1: {}", stderr(&r));
        let msg = stderr(&r);
        assert!(msg.contains(needle), "{args:?}: {msg}");
        assert!(!msg.contains("panicked"), "{args:?}: {msg}");
        assert!(!out.exists(), "{args:?} left a file");
        if !msg.contains("For more information") {
            assert_eq!(msg.trim_end().lines().count(), 1, "{args:?}: one line: {msg}");
        }
        assert!(msg.matches("os error").count() <= 1, "{args:?}: the OS error twice: {msg}");
    }
    // compute "gpu" where no adapter computes (DirectX 12 is not built in on Linux): one line.
    let script = dir.path().join("gpu.json");
    std::fs::write(&script, r#"{"object":"A","compute":"gpu","actions":[{"wait":{"duration_s":0.01}}]}"#)
        .expect("write");
    let r = run_env(&["simulate", "--script", &m(&script), "--out", o], &[("WGPU_BACKEND", "dx12")], &[]);
    assert_eq!(r.status.code(), Some(1), "{}", stderr(&r));
    let msg = stderr(&r);
    assert!(msg.contains("no GPU adapter that computes") && msg.trim_end().lines().count() == 1, "{msg}");
    assert!(!out.exists());
    // The same for `bench --gpu`, before any work.
    let r = run_env(&["bench", "--gpu", "--json"], &[("WGPU_BACKEND", "dx12")], &[]);
    assert_eq!(r.status.code(), Some(1), "{}", stderr(&r));
    let msg = stderr(&r);
    assert!(msg.contains("no GPU adapter that computes") && msg.trim_end().lines().count() == 1, "{msg}");
    // A window system that does not answer: say so, name the headless commands, no source paths.
    let r = run_env(&["view", "--frames", "1"], &[("DISPLAY", ":97")], &["WAYLAND_DISPLAY"]);
    assert_eq!(r.status.code(), Some(1));
    let msg = stderr(&r);
    assert!(msg.contains("headless commands") && msg.contains(":97"), "{msg}");
    assert!(!msg.contains(".cargo") && !msg.contains(".rs:"), "{msg}");
}
