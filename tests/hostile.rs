//! Hostile but fair input, one test per class: every input bounded and checked before the work
//! starts, every failure one line that names its cause, nothing left behind.

#[path = "support/test_cache.rs"]
mod test_cache;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tissue-sim"))
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Fails with exit code 1 and one short line that contains `needle`, within `seconds`.
fn refused(args: &[&str], needle: &str, seconds: f64) -> String {
    let t = Instant::now();
    let o = run(args);
    let took = t.elapsed().as_secs_f64();
    let msg = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{args:?} should exit 1: {msg}");
    assert_eq!(msg.trim_end().lines().count(), 1, "{args:?}: one line: {msg}");
    assert!(msg.len() < 600, "{args:?}: a brief line, not {} bytes", msg.len());
    assert!(msg.contains(needle), "{args:?}: {msg}");
    assert!(!msg.contains("panicked"), "{args:?}: {msg}");
    assert!(took < seconds, "{args:?} took {took:.1} s before failing");
    msg
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write");
    p
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf8")
}

fn script(actions: &str, extra: &str) -> String {
    format!(r#"{{"object":"A"{extra},"actions":[{actions}]}}"#)
}

/// Class: an input file of any kind (material, script, parameters, chart) is read through one
/// bounded path: an oversized file is refused at the bound, and a device or a FIFO (which would
/// wait for a writer) as not a regular file, before it is opened; each quickly.
#[test]
fn every_input_file_is_bounded() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = dir.path().join("o.json");
    let big = dir.path().join("big.toml");
    std::fs::write(&big, format!("symmetry = \"orthotropic\"\n# {}\n", "x".repeat(20 << 20))).expect("write");
    let fifo = dir.path().join("fifo.toml");
    assert!(Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs").success());
    for (input, needle) in [
        ("/dev/zero", "is a device, not a regular file"),
        (s(&fifo), "is a FIFO, not a regular file"),
        (s(&big), "bound"),
    ] {
        refused(&["fem", "--material", input, "--out", s(&o)], needle, 2.0);
        refused(&["calibrate", "--material", input, "--out", s(&o)], needle, 2.0);
        refused(&["simulate", "--script", input, "--out", s(&o)], needle, 2.0);
        refused(&["errors", "--params", input], needle, 2.0);
        refused(&["choose", "--chart", input], needle, 2.0);
    }
    assert!(!o.exists());
}

/// Class: the tools do not break the step choice. The README's script at the viewer's FEM step
/// (1 ms) runs for every model under the automatic choice, and with prefactored Euler asked for
/// by name (the drag is a split step after symplectic Euler and inside the implicit solves,
/// stable at any step; a refusal would have to say why). A
/// drag of an unclamped cube carries it along without a blow-up.
#[test]
fn every_allowed_script_runs_or_is_refused_with_the_true_reason() {
    let dir = tempfile::tempdir().expect("tempdir");
    let example = std::fs::read_to_string("assets/examples/interaction.json").expect("example");
    let out = dir.path().join("out.json");
    for model in ["hex", "shear", "fem-linear", "fem-corotational"] {
        let text = example.replace("\"dt\": 1e-4", "\"dt\": 1e-3").replace("\"hex\"", &format!("\"{model}\""));
        let p = write(dir.path(), "s.json", &text);
        let o = run(&["simulate", "--script", s(&p), "--out", s(&out)]);
        assert!(o.status.success(), "{model} at 1 ms: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).expect("out")).expect("json");
        assert_eq!(v["blow_ups"].as_array().map(Vec::len), Some(0), "{model}: {v}");
        // Asked for by name: runs without a blow-up (when the drag was an explicit force, its
        // spring refused 1 ms on the lighter nodes).
        let named = text.replace("\"clamp\"", "\"integrator\": \"prefactored\", \"clamp\"");
        let p = write(dir.path(), "n.json", &named);
        let x = dir.path().join("x.json");
        let o = run(&["simulate", "--script", s(&p), "--out", s(&x)]);
        assert!(o.status.success(), "{model} prefactored: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&x).expect("out")).expect("json");
        assert_eq!(v["blow_ups"].as_array().map(Vec::len), Some(0), "{model} prefactored: {v}");
    }
    let free = script(
        r#"{"drag":{"node":511,"to":[0.19,0.19,0.19],"duration_s":0.5}},{"wait":{"duration_s":0.5}}"#,
        r#","clamp":"none""#,
    );
    let p = write(dir.path(), "free.json", &free);
    let o = run(&["simulate", "--script", s(&p), "--out", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).expect("out")).expect("json");
    assert_eq!(v["blow_ups"].as_array().map(Vec::len), Some(0), "{v}");
}

/// Class: every check that can be made before the work is: a bad action at the end of a long
/// script, and an output path that cannot be written, fail at once.
#[test]
fn checks_come_before_the_work() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = dir.path().join("o.json");
    let wait = r#"{"wait":{"duration_s":100}}"#;
    let bad = [
        (r#"{"drag":{"node":512,"to":[0,0,0],"duration_s":0}}"#, "node 512"),
        (r#"{"drag":{"node":0,"to":[5,0,0],"duration_s":0}}"#, "metres"),
        (
            r#"{"probe":{"at":[0.05,0.05,0.1],"direction":[0,0,0],"radius":0.01,"depth":0.001,"duration_s":0}}"#,
            "direction",
        ),
        (r#"{"probe":{"at":[0.05,0.05,0.1],"direction":[0,0,-1],"radius":-1,"depth":0.001,"duration_s":0}}"#, "radius"),
    ];
    for (action, needle) in bad {
        let p = write(dir.path(), "s.json", &script(&format!("{wait},{wait},{action}"), ""));
        refused(&["simulate", "--script", s(&p), "--out", s(&o)], needle, 1.0);
    }
    let missing = dir.path().join("missing-dir").join("x.json");
    refused(&["calibrate", "--object", "A", "--out", s(&missing)], "missing-dir", 1.0);
    refused(&["simulate", "--script", "assets/examples/interaction.json", "--out", s(&missing)], "missing-dir", 1.0);
    refused(&["fem", "--object", "A", "--out", s(&missing)], "missing-dir", 1.0);
    assert!(!o.exists());
}

/// Class: no non-finite result is written, as an image or as a table.
#[test]
fn non_finite_results_are_never_written() {
    let dir = tempfile::tempdir().expect("tempdir");
    let png = dir.path().join("x.png");
    refused(&["render", "--case", "A_clamped_ax1_F1e308", "--out", s(&png)], "not finite", 30.0);
    assert!(!png.exists());
    let json = dir.path().join("x.json");
    refused(
        &["msm", "--object", "A", "--k1", "1e-300", "--k2", "1e-300", "--k3", "1e-300", "--out", s(&json)],
        "k1",
        5.0,
    );
    assert!(!json.exists());
}

/// Class: a signal leaves nothing behind: an interrupted run exits without a temporary file.
#[cfg(unix)]
#[test]
fn a_signal_leaves_nothing_behind() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("cal.json");
    for signal in ["INT", "TERM"] {
        let child = bin()
            .args(["calibrate", "--object", "A", "--generations", "40000", "--out", s(&out)])
            .stderr(Stdio::null())
            .spawn()
            .expect("spawn");
        std::thread::sleep(Duration::from_millis(700));
        let ok = Command::new("kill").args([&format!("-{signal}"), &child.id().to_string()]).status().expect("kill");
        assert!(ok.success());
        let o = child.wait_with_output().expect("wait");
        assert!(!o.status.success(), "SIG{signal}: {:?}", o.status);
        let left: Vec<_> = std::fs::read_dir(dir.path()).expect("dir").flatten().map(|e| e.file_name()).collect();
        assert!(left.is_empty(), "SIG{signal} left {left:?}");
    }
}

/// Class: bounds are exact and stated, duplicates and unknown keys are refused, and a missing
/// constant is named on every path.
#[test]
fn bounds_are_exact_and_nothing_is_silently_changed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = dir.path().join("o.json");
    let rec = r#"{"wait":{"duration_s":0,"record":true}}"#;
    let at200 = script(&vec![rec; 200].join(","), "");
    let p = write(dir.path(), "200.json", &at200);
    let r = run(&["simulate", "--script", s(&p), "--out", s(&o)]);
    assert!(r.status.success(), "200 recorded actions are within the bound: {}", stderr(&r));
    let p = write(dir.path(), "201.json", &script(&vec![rec; 201].join(","), ""));
    refused(&["simulate", "--script", s(&p), "--out", s(&o)], "201", 1.0);
    for samples in ["0", "10001"] {
        let a = format!(
            r#"{{"probe":{{"at":[0.05,0.05,0.1],"direction":[0,0,-1],"radius":0.01,"depth":0.001,"duration_s":0.01,"samples":{samples}}}}}"#
        );
        let p = write(dir.path(), "p.json", &script(&a, ""));
        refused(&["simulate", "--script", s(&p), "--out", s(&o)], "samples", 1.0);
    }
    refused(&["calibrate", "--object", "A", "--bound", "k1=1:2", "--bound", "k1=3:4", "--out", s(&o)], "k1", 1.0);
    let model_key =
        write(dir.path(), "m.json", r#"{"object":"A","model":"hex","params":{"k1":700,"k2":600,"k3":650,"d":0}}"#);
    refused(&["errors", "--params", s(&model_key)], "model", 1.0);
    let no_c23 =
        write(dir.path(), "c.json", r#"{"object":"A","params":{"k1":700,"k2":600,"k3":650,"d":0,"c12":10,"c13":10}}"#);
    refused(&["errors", "--params", s(&no_c23)], "c23", 2.0);
    refused(&["validate", "--params", s(&no_c23)], "c23", 2.0);
    refused(&["dynamics", "--object", "A", "--params", s(&no_c23)], "c23", 2.0);
}

/// Class: messages are brief and on one line: long strings are quoted briefly, numbers in short
/// form, argument errors on one line, nothing printed twice, no "NaN %".
#[test]
fn messages_are_brief_and_plain() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = dir.path().join("o.json");
    let long = write(dir.path(), "long.json", &format!(r#"{{"object":"{}","actions":[]}}"#, "A".repeat(100_000)));
    refused(&["simulate", "--script", s(&long), "--out", s(&o)], "object", 1.0);
    let o = s(&o).to_owned();
    let huge: [(Vec<&str>, &str); 5] = [
        (vec!["errors", "--object", "A", "--k1", "1e308", "--k2", "1e308", "--k3", "1e308"], "k1"),
        (vec!["render", "--magnify", "-1e308", "--out", &o], "magnify"),
        (vec!["choose", "--rate", "1e308"], "rate"),
        (vec!["choose", "--max-error", "-1e-300"], "max-error"),
        (vec!["calibrate", "--object", "A", "--mutation", "1e308", "--out", &o], "mutation"),
    ];
    for (args, needle) in huge {
        let msg = refused(&args, needle, 5.0);
        assert!(!msg.contains("000000000"), "{msg}");
    }
    refused(&["fem", "--object", "A", "--nodes", "x"], "--nodes", 1.0);
    refused(&["fem", "--object"], "--object", 1.0);
    refused(&["nonsense"], "nonsense", 1.0);
    let r = run(&["dynamics", "--object", "A", "--dt", "0.05"]);
    let text = format!("{}{}", String::from_utf8_lossy(&r.stdout), stderr(&r));
    assert!(!text.contains("NaN %") && !text.contains("  "), "{text}");
}

/// Class: writing to a closed standard output is an error, not a silent success.
#[cfg(unix)]
#[test]
fn a_closed_standard_output_is_an_error() {
    for args in ["fem --object A --out -", "simulate --script assets/examples/interaction.json --out -"] {
        let o = Command::new("sh")
            .args(["-c", &format!("exec \"$0\" {args} >&-"), env!("CARGO_BIN_EXE_tissue-sim")])
            .output()
            .expect("sh runs");
        assert_eq!(o.status.code(), Some(1), "{args}: wrote nothing: {}", stderr(&o));
        assert!(stderr(&o).contains("standard output"), "{args}: {}", stderr(&o));
    }
}

/// Presses the contact cannot resolve are refused before the first step, each with its reason:
/// before, a 1 mm sphere read 0.21 N, then -0.11 N, then 0 N as it went deeper; a 15 mm sphere
/// pressed past its radius pulled; a press into the clamped bottom read 0 N at every depth; a
/// 0.1 m sphere fell back to the model's nodes under the name "surface".
#[test]
fn presses_the_contact_cannot_resolve_are_refused_with_their_reason() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = dir.path().join("o.json");
    let press = |at: &str, dir: &str, r: f64, d: f64| {
        format!(r#"{{"probe":{{"at":{at},"direction":{dir},"radius":{r},"depth":{d},"duration_s":0.01,"samples":1}}}}"#)
    };
    let top = "[0.05,0.05,0.1]";
    let down = "[0,0,-1]";
    for (name, action, why) in [
        ("small", press(top, down, 0.001, 0.0005), "smaller than the material's surface grid resolves"),
        ("wide", press(top, down, 0.1, 0.004), "wider than the contact can hold"),
        ("window", press(top, down, 0.05, 0.02), "wider than the contact can hold"),
        ("deep", press(top, down, 0.015, 0.016), "deeper than a probe of radius 15 mm can be pressed"),
        ("inside", press("[0.05,0.05,0.09]", down, 0.015, 0.004), "inside the tissue"),
        ("away", press(top, "[0,0,1]", 0.015, 0.004), "does not enter the tissue"),
        ("above", press("[0.05,0.05,0.12]", down, 0.015, 0.004), "does not enter the tissue"),
        ("clamped", press("[0.05,0.05,0.0]", "[0,0,1]", 0.015, 0.004), "clamped face"),
        (
            "path",
            r#"{"probe_path":{"radius":0.015,"direction":[0,0,-1],"sample_hz":100,"keys":[
                {"t":0,"at":[0.05,0.05,0.1],"depth":0},{"t":0.1,"at":[0.05,0.05,0.1],"depth":0.02}]}}"#
                .to_owned(),
            "keys[1]: depth 20 mm is deeper",
        ),
    ] {
        let p = write(dir.path(), &format!("{name}.json"), &script(&action, ""));
        refused(&["simulate", "--script", s(&p), "--out", s(&o)], why, 2.0);
    }
    assert!(!o.exists());
}

/// A probe never pulls, and every sample says which contact produced its force: pressed to 3/4
/// of its radius on the top face and on a side face (both the material's surface compliance).
#[test]
fn a_probe_never_pulls_and_each_force_says_its_contact() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = dir.path().join("o.json");
    let path = |at: &str, dir: &str| {
        format!(
            r#"{{"probe_path":{{"radius":0.015,"direction":{dir},"sample_hz":200,"keys":[
                {{"t":0,"at":{at},"depth":0}},{{"t":0.3,"at":{at},"depth":0.01125}},{{"t":0.5,"at":{at},"depth":0.01125}}]}}}}"#
        )
    };
    let actions =
        format!("{},{{\"release\":{{}}}},{}", path("[0.05,0.05,0.1]", "[0,0,-1]"), path("[0.0,0.05,0.05]", "[1,0,0]"));
    let p = write(dir.path(), "p.json", &script(&actions, r#","dt":1e-3"#));
    let r = run(&["simulate", "--script", s(&p), "--out", s(&o)]);
    assert!(r.status.success(), "{}", stderr(&r));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&o).expect("read")).expect("json");
    let samples = v["force_path"].as_array().expect("force_path");
    assert!(samples.len() > 150);
    for sample in samples {
        let f = sample["force_n"].as_f64().expect("force");
        assert!(f >= 0.0, "a probe pulled: {sample}");
        assert_eq!(sample["contact"], "surface", "{sample}");
    }
    let deepest = samples.iter().filter(|s| s["action"] == 0).map(|s| s["force_n"].as_f64().unwrap_or(0.0));
    assert!(deepest.fold(0.0, f64::max) > 20.0, "the press at 3/4 of the radius pushes back");
}

/// Class: a reader checks shape as well as values, alike in TOML and JSON. An inclusion's
/// `centre` with four numbers, or two, and a key of the wrong type are refused with one line
/// naming the file, the inclusion and the key; trailing data after a JSON document is refused.
#[test]
fn a_material_file_of_the_wrong_shape_is_named_the_same_in_toml_and_json() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = dir.path().join("o.json");
    let background = "\"symmetry\": \"orthotropic\", \"units\": \"kPa\", \"E1\": 10.0, \"E2\": 12.0, \"E3\": 15.0, \
                      \"nu12\": 0.3, \"nu13\": 0.3, \"nu23\": 0.3, \"G12\": 4.0, \"G13\": 4.0, \"G23\": 4.0";
    let toml_background = "symmetry = \"orthotropic\"\nunits = \"kPa\"\nE1 = 10.0\nE2 = 12.0\nE3 = 15.0\nnu12 = 0.3\n\
                           nu13 = 0.3\nnu23 = 0.3\nG12 = 4.0\nG13 = 4.0\nG23 = 4.0";
    for (centre, needle) in [("[0.05, 0.05, 0.08, 0.3]", "got 4"), ("[0.05, 0.05]", "got 2")] {
        let toml = write(
            dir.path(),
            "m.toml",
            &format!("{toml_background}\n\n[[inclusion]]\ncentre = {centre}\nradius = 0.008\nscale = 5.0\n"),
        );
        let json = write(
            dir.path(),
            "m.json",
            &format!("{{{background}, \"inclusion\": [{{\"centre\": {centre}, \"radius\": 0.008, \"scale\": 5.0}}]}}"),
        );
        for file in [&toml, &json] {
            let msg = refused(&["fem", "--material", s(file), "--bc", "patch", "--out", s(&o)], needle, 2.0);
            assert!(msg.contains(s(file)) && msg.contains("inclusion 1, centre: expected 3 numbers"), "{msg}");
        }
    }
    let json = write(
        dir.path(),
        "m.json",
        &format!("{{{background}, \"inclusion\": [{{\"centre\": [0.05, 0.05, 0.08], \"radius\": \"big\"}}]}}"),
    );
    refused(&["fem", "--material", s(&json), "--bc", "patch", "--out", s(&o)], "inclusion 1, radius: ", 2.0);
    let json = write(dir.path(), "m.json", &format!("{{{background}}} {{}}"));
    refused(&["fem", "--material", s(&json), "--bc", "patch", "--out", s(&o)], "trailing", 2.0);
    assert!(!o.exists());
}

/// Class: an output that cannot be written is refused before the work: a recording whose folder
/// takes no file before the viewer's window opens, a palpation map into such a folder or over a
/// write-protected map, each in one line within a second (`/proc` takes no new file even for
/// root).
#[test]
fn an_output_that_cannot_be_written_is_refused_before_the_work() {
    refused(&["view", "--record", "/proc/tissue-sim-recording.json", "--frames", "1"], "does not take a new file", 2.0);
    refused(&["palpate", "--object", "A", "--out", "/proc/tissue-sim-map"], "not writable", 2.0);
    let dir = tempfile::tempdir().expect("tempdir");
    let map = dir.path().join("map");
    std::fs::create_dir(&map).expect("a map folder");
    let png = write(&map, "map.png", "an old map");
    let mut locked = std::fs::metadata(&png).expect("meta").permissions();
    locked.set_readonly(true);
    std::fs::set_permissions(&png, locked).expect("chmod");
    refused(&["palpate", "--object", "A", "--out", s(&map)], "write-protected", 2.0);
    assert_eq!(std::fs::read_to_string(&png).expect("the old map"), "an old map");
    assert_eq!(std::fs::read_dir(&map).expect("listed").count(), 1, "nothing written beside the old map");
}

/// Class: a recording is itself and its replay says where it is not. A recorded sample whose
/// `force_n` is not its force along the push (tripled) is refused on reading with the sample
/// named; a sample whose contact was changed replays with that sample named as differing.
#[test]
fn a_recording_that_contradicts_itself_is_refused_and_a_changed_one_is_named() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = dir.path().join("o.json");
    let path = r#"{"probe_path":{"radius":0.015,"direction":[0,0,-1],"sample_hz":100,"keys":[
        {"t":0,"at":[0.05,0.05,0.1],"depth":0},{"t":0.05,"at":[0.05,0.05,0.1],"depth":0.002}]}}"#;
    let plain = write(dir.path(), "plain.json", &script(path, r#","model":"axis","contact":"nodes""#));
    let out = dir.path().join("plain_out.json");
    let r = run(&["simulate", "--script", s(&plain), "--out", s(&out)]);
    assert!(r.status.success(), "{}", stderr(&r));
    let result: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).expect("read")).expect("json");
    let samples = result["force_path"].clone();
    assert!(samples.as_array().is_some_and(|a| a.len() > 3), "{samples}");
    let recording = |samples: &serde_json::Value| {
        let text = script(path, &format!(r#","model":"axis","contact":"nodes","recorded":{{"force_path":{samples}}}"#));
        write(dir.path(), "recording.json", &text)
    };
    // Replayed as recorded: nothing differs.
    let same = recording(&samples);
    let r = run(&["simulate", "--script", s(&same), "--out", s(&o)]);
    assert!(stderr(&r).contains("differ") && stderr(&r).contains(" 0 differ"), "{}", stderr(&r));
    // force_n tripled: refused on reading.
    let mut tripled = samples.clone();
    let f = tripled[2]["force_n"].as_f64().expect("a force");
    tripled[2]["force_n"] = serde_json::json!(3.0 * f + 1.0);
    let bad = recording(&tripled);
    refused(&["simulate", "--script", s(&bad), "--out", s(&o)], "recorded sample 2: force_n", 2.0);
    // The contact changed: the replay names the sample.
    let mut changed = samples.clone();
    changed[3]["contact"] = serde_json::json!("surface");
    let other = recording(&changed);
    let r = run(&["simulate", "--script", s(&other), "--out", s(&o)]);
    assert!(r.status.success(), "{}", stderr(&r));
    assert!(stderr(&r).contains(" 1 differ") && stderr(&r).contains("sample 3 "), "{}", stderr(&r));
    assert!(stderr(&r).contains("contact surface recorded, nodes replayed"), "{}", stderr(&r));
}
