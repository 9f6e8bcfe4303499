//! The cache folder (`XDG_CACHE_HOME` pointed at a temporary folder): a kept surface compliance
//! is used only where it proves to be the material's (its key and checksum), a special file in
//! its place never blocks, and a folder that cannot keep the answer is found before the work:
//! the run goes on with the answer in memory. Each refusal is one line naming the file and why.
//!
//! Computing a surface compliance takes about 40 s: the tests compute as few as they can, and
//! copy a good file from the tests' own cache folder (`tests/support/test_cache.rs`) where there
//! is one.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use tissue_core::mechanics::material::Material;
use tissue_core::sim::material_surface::compliance::{DEFAULT_DIVISIONS, SurfaceCompliance};
use tissue_core::sim::material_surface::file_name;

use crate::*;

/// How long a run that computes a compliance may take before it counts as blocked, s (about
/// 40 s alone; the tests run side by side on two cores).
const BLOCKED_AFTER_S: u64 = 400;

fn s(p: &Path) -> &str {
    p.to_str().expect("utf8")
}

/// A script that presses the probe 4 mm into the top face of `object` and holds it.
fn press_script(dir: &Path, object: &str) -> PathBuf {
    let script = dir.join(format!("press-{object}.json"));
    std::fs::write(
        &script,
        format!(
            r#"{{"object":"{object}","dt":1e-3,"actions":[
            {{"probe":{{"at":[0.03,0.05,0.1],"direction":[0,0,-1],"radius":0.015,"depth":0.004,
              "duration_s":0.1,"samples":2}}}},{{"wait":{{"duration_s":0.2}}}}]}}"#
        ),
    )
    .expect("write");
    script
}

/// The last probe force (z, newtons) of a `simulate` output file.
fn probe_force(out: &Path) -> f64 {
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out).expect("read")).expect("json");
    let events = v["events"].as_array().expect("events");
    events.last().and_then(|e| e["tool_force_n"][2].as_f64()).expect("a probe force")
}

/// Runs `simulate` on `script` with the cache folder `home/tissue-sim`: the probe's last force
/// (newtons) and standard error.
fn simulate(script: &Path, home: &Path) -> (f64, String) {
    let out = script.with_extension("out.json");
    let o = run_env(&["simulate", "--script", s(script), "--out", s(&out)], &[("XDG_CACHE_HOME", s(home))], &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    (probe_force(&out), stderr(&o))
}

/// The lines about the cache (those starting with `tissue-sim:`).
fn cache_lines(err: &str) -> Vec<&str> {
    err.lines().filter(|l| l.starts_with("tissue-sim:")).collect()
}

/// Copies `material`'s surface compliance into `folder` from the tests' cache folder where a
/// regular file there proves to be it; whether it did.
fn copy_good(material: &Material, folder: &Path) -> bool {
    let Some(from) = tissue_core::io::cache_dir().map(|d| d.join(file_name(material))) else { return false };
    if !std::fs::metadata(&from).is_ok_and(|m| m.is_file()) {
        return false;
    }
    let Ok(bytes) = std::fs::read(&from) else { return false };
    if SurfaceCompliance::from_bytes(&bytes, material, DEFAULT_DIVISIONS).is_err() {
        return false;
    }
    std::fs::create_dir_all(folder).expect("folder");
    std::fs::write(folder.join(file_name(material)), bytes).expect("copy");
    true
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * b.abs()
}

/// (i) Object A's compliance copied under B's file name is not used for B: B's probe force is
/// the one B's own compliance gives, and the line names the file. (ii) A megabyte of zeros in
/// the middle of a file is refused by its checksum, and the file computed again.
#[test]
#[ignore = "slow: in the slow group, cargo test --release -- --ignored"]
fn a_kept_compliance_is_used_only_where_it_proves_to_be_the_materials() {
    let home = tempfile::tempdir().expect("tempdir");
    let folder = home.path().join("tissue-sim");
    let (a, b) = (Material::object_a(), Material::object_b());
    let (a_file, b_file) = (folder.join(file_name(&a)), folder.join(file_name(&b)));
    copy_good(&a, &folder);
    let (force_a, err) = simulate(&press_script(home.path(), "A"), home.path());
    assert!(cache_lines(&err).is_empty(), "{err}");
    assert!(a_file.is_file(), "A's compliance kept");

    // (i) A's file under B's name.
    std::fs::copy(&a_file, &b_file).expect("copy");
    let script_b = press_script(home.path(), "B");
    let (force_b, err) = simulate(&script_b, home.path());
    assert_eq!(
        cache_lines(&err),
        [format!("tissue-sim: cache file {} is for another material; computing it again", b_file.display())],
        "{err}"
    );
    assert!((force_b - force_a).abs() > 0.2 * force_b, "B's force {force_b} N is not A's {force_a} N");
    // B's compliance is now kept: read back silently, the same force.
    let (again, err) = simulate(&script_b, home.path());
    assert!(cache_lines(&err).is_empty() && !err.contains("computing"), "{err}");
    assert!(close(again, force_b), "{again} against {force_b}");
    // Where the tests' cache folder holds a good compliance of B, it gives the same force.
    let users = home.path().join("users");
    if copy_good(&b, &users.join("tissue-sim")) {
        let (kept, _) = simulate(&script_b, &users);
        assert!(close(kept, force_b), "{force_b} N against the kept compliance's {kept} N");
    }

    // (ii) A megabyte of zeros in the middle of B's file.
    let good = std::fs::read(&b_file).expect("read");
    let mut zeroed = good.clone();
    let mid = zeroed.len() / 2;
    zeroed[mid - (1 << 19)..mid + (1 << 19)].fill(0);
    assert!(zeroed != good, "the middle megabyte was not all zeros");
    std::fs::write(&b_file, &zeroed).expect("write");
    let (fresh, err) = simulate(&script_b, home.path());
    assert_eq!(
        cache_lines(&err),
        [format!(
            "tissue-sim: cache file {} is damaged (its checksum does not match); computing it again",
            b_file.display()
        )],
        "{err}"
    );
    assert!(close(fresh, force_b), "{fresh} against {force_b}");
    let rewritten = std::fs::read(&b_file).expect("read");
    assert!(SurfaceCompliance::from_bytes(&rewritten, &b, DEFAULT_DIVISIONS).is_ok(), "B's file written again");
}

/// (iii) A FIFO in the file's place is never opened: the run does not block, says so in one
/// line, computes the compliance in memory and leaves the FIFO as it was.
#[test]
#[ignore = "slow: in the slow group, cargo test --release -- --ignored"]
fn a_fifo_in_the_files_place_does_not_block_the_run() {
    use std::os::unix::fs::FileTypeExt as _;
    let home = tempfile::tempdir().expect("tempdir");
    let folder = home.path().join("tissue-sim");
    std::fs::create_dir_all(&folder).expect("folder");
    let fifo = folder.join(file_name(&Material::object_a()));
    assert!(Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs").success());
    let script = press_script(home.path(), "A");
    let out = home.path().join("out.json");
    let mut child = Command::new(env!("CARGO_BIN_EXE_tissue-sim"))
        .args(["simulate", "--script", s(&script), "--out", s(&out)])
        .env("XDG_CACHE_HOME", home.path())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary starts");
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if start.elapsed() > Duration::from_secs(BLOCKED_AFTER_S) {
            let _ = child.kill();
            panic!("simulate blocked for {BLOCKED_AFTER_S} s with a FIFO in the cache file's place");
        }
        std::thread::sleep(Duration::from_millis(200));
    };
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().expect("stderr"), &mut err).expect("stderr");
    assert!(status.success(), "{err}");
    assert_eq!(
        cache_lines(&err),
        [format!(
            "tissue-sim: cache file {} is a FIFO, not a regular file: the surface compliance is computed in memory \
             and not kept",
            fifo.display()
        )],
        "{err}"
    );
    assert!(err.contains("computing the material's surface compliance (about a minute, not kept)"), "{err}");
    assert!(probe_force(&out) > 1.0);
    assert!(std::fs::symlink_metadata(&fifo).expect("there").file_type().is_fifo(), "the FIFO is left as it was");
}

/// (iv) A cache folder that cannot keep the answer (read-only; for root, who writes into any
/// folder, one under a regular file): said in one line before the work, the run succeeds with
/// the answer in memory, and nothing is written.
#[test]
#[ignore = "slow: in the slow group, cargo test --release -- --ignored"]
fn a_cache_folder_that_cannot_keep_the_answer_is_said_before_the_work() {
    use std::os::unix::fs::PermissionsExt as _;
    let home = tempfile::tempdir().expect("tempdir");
    let folder = home.path().join("tissue-sim");
    std::fs::create_dir_all(&folder).expect("folder");
    std::fs::set_permissions(&folder, std::fs::Permissions::from_mode(0o555)).expect("chmod");
    let privileged = std::fs::write(folder.join("trial"), b"").is_ok();
    let (cache_home, unwritable) = if privileged {
        std::fs::remove_file(folder.join("trial")).expect("remove");
        let blocked = home.path().join("blocked");
        std::fs::write(&blocked, b"a file").expect("write");
        let folder = blocked.join("tissue-sim");
        (blocked, folder)
    } else {
        (home.path().to_owned(), folder.clone())
    };
    let (force, err) = simulate(&press_script(home.path(), "A"), &cache_home);
    std::fs::set_permissions(&folder, std::fs::Permissions::from_mode(0o755)).expect("chmod back");
    let lines = cache_lines(&err);
    assert_eq!(lines.len(), 1, "{err}");
    let head = format!("tissue-sim: the cache folder {} is not writable (", unwritable.display());
    assert!(lines[0].starts_with(&head), "{err}");
    assert!(lines[0].ends_with("): the surface compliance is computed in memory and not kept"), "{err}");
    assert!(err.find(&head) < err.find("computing the material's surface compliance"), "said before the work: {err}");
    assert!(err.contains("the material's surface compliance: 100 %"), "{err}");
    assert!(force > 1.0);
    assert_eq!(std::fs::read_dir(&folder).expect("folder").count(), 0, "nothing written");
    if privileged {
        assert_eq!(std::fs::read(&cache_home).expect("read"), b"a file");
    }
}
