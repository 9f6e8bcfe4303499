//! `palpate`: the map of a face over a lump, its three files and what they hold.

use crate::*;

#[test]
#[ignore = "slow: in the slow group, cargo test --release -- --ignored"]
fn palpate_maps_a_lump_and_writes_json_csv_and_png() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("map");
    let lump = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/examples/lump_5x_r8.toml");
    let o = run(&["palpate", "--material", lump, "--face", "+z", "--grid", "5", "--out", out.to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("5 x 5 presses on face +z") && text.contains("largest"), "{text}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("map.json")).expect("map.json")).expect("json");
    let numbers = |key: &str| -> Vec<f64> {
        v[key].as_array().expect(key).iter().map(|x| x.as_f64().expect("a number")).collect()
    };
    let (forces, background, contrast) = (numbers("forces"), numbers("background_forces"), numbers("contrast"));
    assert_eq!((forces.len(), v["points"].as_array().map(Vec::len)), (25, Some(25)));
    assert_eq!(v["points"][12], serde_json::json!([0.05, 0.05, 0.1]));
    assert_eq!((v["face"].as_str(), v["grid"].as_u64()), (Some("+z"), Some(5)));
    // The lump is under the middle: the largest contrast is there, and it is the shipped lump's
    // (about +8 %, 10 mm deep); the corners feel nothing of it.
    let peak = contrast.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(contrast[12], peak);
    assert!((0.05..0.11).contains(&peak), "{peak}");
    assert!(contrast[0].abs() < 1e-3 && (forces[0] - background[0]).abs() < 1e-3 * forces[0], "{contrast:?}");
    let csv = std::fs::read_to_string(out.join("map.csv")).expect("map.csv");
    assert_eq!(csv.lines().count(), 26);
    assert!(csv.starts_with("x_m,y_m,z_m,force_n,background_force_n,contrast"));
    let png = std::fs::read(out.join("map.png")).expect("map.png");
    assert!(png.starts_with(b"\x89PNG"));

    // A side face of the homogeneous object: no contrast anywhere.
    let side = dir.path().join("side");
    let o = run(&["palpate", "--object", "A", "--face", "-x", "--grid", "3", "--out", side.to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(side.join("map.json")).expect("map.json")).expect("json");
    assert!(v["contrast"].as_array().expect("contrast").iter().all(|c| c.as_f64() == Some(0.0)));
    assert!(v["points"].as_array().expect("points").iter().all(|p| p[0].as_f64() == Some(0.0)));
}

#[test]
fn palpate_refuses_bad_input_in_one_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("never");
    let o = out.to_str().expect("utf8");
    let missing = dir.path().join("missing.toml");
    let cases: [(Vec<&str>, &str); 7] = [
        (vec!["--object", "A", "--depth", "1e-6"], "touches none of the material's surface nodes"),
        (vec!["--object", "A", "--depth", "1e-12"], "every press of the grid touches from"),
        (vec!["--object", "A", "--face", "-z"], "-z"),
        (vec!["--object", "A", "--grid", "0"], "grid of 0"),
        (vec!["--object", "A", "--depth", "0.02"], "deeper than"),
        (vec!["--object", "A", "--radius", "0.001"], "at least 5 mm"),
        (vec!["--material", missing.to_str().expect("utf8")], "No such file"),
    ];
    for (args, needle) in cases {
        let r = run(&[&["palpate", "--out", o][..], &args].concat());
        let msg = stderr(&r);
        assert_eq!(r.status.code(), Some(1), "{args:?}: {msg}");
        assert!(msg.contains(needle) && !msg.contains("panicked"), "{args:?}: {msg}");
        assert!(!out.exists(), "{args:?} left a file");
    }
}
