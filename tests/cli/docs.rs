//! The documents stay true: README's two commands are the ones CI and the binary run, its
//! headless command lines parse as written (and the quick ones run), its script example is the
//! shipped file and runs, its links resolve, and its layout table names exactly the folders
//! there are.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use clap::Parser as _;

use crate::*;

/// The headless commands run in full here (each within half a minute; the material's answers
/// come from the cache the other tests fill); the others (`reproduce`, `chart`, `choose`,
/// `bench`: minutes each; `view`: a display) are checked by the argument parser and their input
/// files here, and run by their own tests and `.ci/run`.
const RUN_IN_FULL: [&str; 8] = ["fem", "msm", "errors", "validate", "calibrate", "dynamics", "render", "simulate"];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn readme() -> String {
    std::fs::read_to_string(root().join("README.md")).expect("README.md")
}

/// The text of the section under `## heading`, up to the next `## ` heading.
fn section(text: &str, heading: &str) -> String {
    let start = text.find(&format!("\n## {heading}\n")).unwrap_or_else(|| panic!("README has no \"## {heading}\""));
    let body = &text[start + heading.len() + 5..];
    body[..body.find("\n## ").unwrap_or(body.len())].to_owned()
}

/// The fenced code blocks of `lang` in `text`.
fn blocks(text: &str, lang: &str) -> Vec<String> {
    let fence = format!("```{lang}\n");
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find(&fence) {
        let body = &rest[i + fence.len()..];
        let end = body.find("```").expect("a fenced block is closed");
        out.push(body[..end].to_owned());
        rest = &body[end + 3..];
    }
    out
}

/// The commands of a bash block: each non-blank line without its `# comment`, split into words.
fn command_lines(block: &str) -> Vec<Vec<String>> {
    block
        .lines()
        .map(|l| l.split(" #").next().unwrap_or("").trim())
        .filter(|l| !l.is_empty())
        .map(|l| {
            assert!(!l.contains(['"', '\'', '\\', '$', '|', ';', '&']), "keep README's commands plain words: {l}");
            l.split_whitespace().map(str::to_owned).collect()
        })
        .collect()
}

#[test]
fn the_two_commands_are_the_ones_ci_and_the_binary_run() {
    let text = readme();
    let two = blocks(&section(&text, "Two commands"), "bash");
    assert_eq!(two.len(), 1, "one bash block under \"Two commands\"");
    let lines: Vec<String> = command_lines(&two[0]).iter().map(|w| w.join(" ")).collect();
    assert_eq!(lines, ["cargo run --release", "cargo test --release"]);
    let ci = std::fs::read_to_string(root().join(".ci/run")).expect(".ci/run");
    assert!(ci.contains("cargo test --release"), ".ci/run runs README's test command");
    assert!(ci.contains("target/release/tissue-sim view"), ".ci/run opens the viewer");
    // Without a display, the main command says so and names every headless command.
    let o = run_env(&[], &[], &["DISPLAY", "WAYLAND_DISPLAY"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("no display"), "{err}");
    for words in command_lines(&blocks(&section(&text, "Headless commands"), "bash")[0]) {
        let sub = &words[3];
        if sub != "view" {
            assert!(err.contains(sub.as_str()), "the no-display hint names {sub}: {err}");
        }
    }
}

#[test]
#[ignore = "slow: in the slow group, cargo test --release -- --ignored"]
fn the_headless_commands_run_as_written() {
    let text = readme();
    let block = blocks(&section(&text, "Headless commands"), "bash");
    assert_eq!(block.len(), 1, "one bash block under \"Headless commands\"");
    let commands = command_lines(&block[0]);
    assert!(commands.len() >= 15, "README lists the headless commands");
    // They run in a folder of their own, with the repository's assets beside them.
    let dir = tempfile::tempdir().expect("tempdir");
    std::os::unix::fs::symlink(root().join("assets"), dir.path().join("assets")).expect("link assets");
    let mut ran = BTreeSet::new();
    for words in &commands {
        let line = words.join(" ");
        assert_eq!(words[..3], ["cargo", "run", "--release"], "{line}");
        assert_eq!(words[3], "--", "{line}");
        let args = &words[4..];
        if let Err(e) =
            tissue_sim::cli::Cli::try_parse_from(std::iter::once("tissue-sim").chain(args.iter().map(String::as_str)))
        {
            panic!("README: {line}: {e}");
        }
        for a in args.iter().filter(|a| a.starts_with("assets/")) {
            assert!(root().join(a).is_file(), "README: {line}: {a} does not exist");
        }
        if RUN_IN_FULL.contains(&args[0].as_str()) {
            let o = std::process::Command::new(env!("CARGO_BIN_EXE_tissue-sim"))
                .args(args)
                .current_dir(dir.path())
                .output()
                .expect("binary runs");
            assert!(o.status.success(), "README: {line}: {}", stderr(&o));
            if let Some(i) = args.iter().position(|a| a == "--out") {
                let out = dir.path().join(&args[i + 1]);
                assert!(out.metadata().is_ok_and(|m| m.len() > 0), "README: {line}: wrote nothing");
            }
            ran.insert(args[0].clone());
        }
    }
    assert_eq!(ran.len(), RUN_IN_FULL.len(), "README shows each quick command: {ran:?}");
}

#[test]
fn the_script_example_is_the_shipped_file() {
    let text = readme();
    let scripts = blocks(&section(&text, "Scripts"), "json");
    assert_eq!(scripts.len(), 1, "one script example");
    let shipped = std::fs::read_to_string(root().join("assets/examples/interaction.json")).expect("example");
    assert_eq!(scripts[0], shipped, "README's script is assets/examples/interaction.json (which it runs)");
    let script: tissue_studies::study::script::Script = serde_json::from_str(&shipped).expect("a valid script");
    assert!(!script.actions.is_empty());
}

#[test]
fn the_links_resolve() {
    for doc in ["README.md", "ARCHITECTURE.md", "CHANGELOG.md"].into_iter().map(PathBuf::from).chain(
        std::fs::read_dir(root().join("docs"))
            .expect("docs/")
            .map(|e| Path::new("docs").join(e.expect("entry").file_name())),
    ) {
        let text = std::fs::read_to_string(root().join(&doc)).expect("readable");
        let base = root().join(&doc).parent().expect("a folder").to_owned();
        let mut rest = text.as_str();
        while let Some(i) = rest.find("](") {
            let tail = &rest[i + 2..];
            let end = tail.find(')').expect("a link is closed");
            let target = tail[..end].split('#').next().unwrap_or("");
            if !target.is_empty() && !target.contains("://") {
                assert!(base.join(target).exists(), "{}: link to {target} does not resolve", doc.display());
            }
            rest = &tail[end..];
        }
    }
}

#[test]
fn the_layout_table_names_every_folder() {
    let table = section(&readme(), "Layout");
    let named: BTreeSet<String> = table
        .lines()
        .filter_map(|l| l.strip_prefix("| `"))
        .map(|l| l[..l.find('`').expect("a closed name")].trim_end_matches('/').to_owned())
        .collect();
    let folders = |dir: &Path| -> Vec<String> {
        std::fs::read_dir(dir)
            .expect("readable")
            .map(|e| e.expect("entry"))
            .filter(|e| e.path().is_dir())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| !n.starts_with('.') && n != "target")
            .collect()
    };
    let mut there = BTreeSet::new();
    for top in folders(&root()) {
        if top == "crates" {
            there.extend(folders(&root().join("crates")).into_iter().map(|s| format!("crates/{s}")));
        } else {
            there.insert(top);
        }
    }
    assert_eq!(named, there, "README's layout table against the folders of the repository");
}
