//! The layers hold: inside each crate no module imports a sibling that imports it back, directly
//! or around a circle (read from the sources: every `crate::a::b` and `super::b` path of a
//! module, its tests included, against the modules beside it). Between crates Cargo refuses a
//! circle itself. And no source file is past 800 lines.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every module of the crate whose sources are in `src`: its path (`["sim", "press"]`) and file.
fn modules(src: &Path) -> BTreeMap<Vec<String>, PathBuf> {
    let mut out = BTreeMap::new();
    let mut folders = vec![src.to_path_buf()];
    while let Some(dir) = folders.pop() {
        for entry in std::fs::read_dir(&dir).expect("a readable folder") {
            let path = entry.expect("an entry").path();
            if path.is_dir() {
                folders.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let rel = path.strip_prefix(src).expect("inside").with_extension("");
            let mut name: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
            if name.last().is_some_and(|n| n == "mod") {
                name.pop();
            }
            if name == ["lib"] || name == ["main"] {
                name.clear();
            }
            out.insert(name, path);
        }
    }
    out
}

/// The module paths `text` (the file of `module`) names: `crate::a::b` and `super::...::b`, with
/// comments left out.
fn named_paths(text: &str, module: &[String]) -> Vec<Vec<String>> {
    let code: String = text.lines().map(|l| l.find("//").map_or(l, |i| &l[..i])).collect::<Vec<_>>().join("\n");
    let mut out = Vec::new();
    let bytes = code.as_bytes();
    for head in ["crate::", "super::"] {
        let mut from = 0;
        while let Some(i) = code[from..].find(head).map(|i| i + from) {
            from = i + head.len();
            if i > 0 && (bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_') {
                continue;
            }
            let tail: String =
                code[i..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == ':').collect();
            let mut parts = tail.split("::").filter(|p| !p.is_empty());
            let mut base: Vec<String> = match parts.next() {
                Some("crate") => Vec::new(),
                _ => module[..module.len().saturating_sub(1)].to_vec(),
            };
            let mut rest: Vec<&str> = parts.collect();
            while rest.first() == Some(&"super") {
                base.pop();
                rest.remove(0);
            }
            base.extend(rest.iter().map(|s| s.to_string()));
            out.push(base);
        }
    }
    out
}

/// The circles among siblings of the crate in `src`, each as its parent and members.
fn circles(src: &Path) -> Vec<(String, BTreeSet<String>)> {
    let mods = modules(src);
    // Parent -> (child -> siblings it uses).
    let mut uses: BTreeMap<Vec<String>, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    for (module, file) in &mods {
        let text = std::fs::read_to_string(file).expect("a readable source");
        for path in named_paths(&text, module) {
            let Some(target) = (1..=path.len()).rev().map(|k| &path[..k]).find(|p| mods.contains_key(*p)) else {
                continue;
            };
            let common = module.iter().zip(target).take_while(|(a, b)| a == b).count();
            if common < module.len() && common < target.len() {
                let siblings = uses.entry(module[..common].to_vec()).or_default();
                siblings.entry(module[common].clone()).or_default().insert(target[common].clone());
            }
        }
    }
    let mut found = Vec::new();
    for (parent, graph) in &uses {
        // A child is on a circle where it reaches itself.
        let reaches = |from: &String| -> BTreeSet<String> {
            let mut seen = BTreeSet::new();
            let mut todo: Vec<&String> = graph.get(from).into_iter().flatten().collect();
            while let Some(n) = todo.pop() {
                if seen.insert(n.clone()) {
                    todo.extend(graph.get(n).into_iter().flatten());
                }
            }
            seen
        };
        let on: BTreeSet<String> = graph.keys().filter(|c| reaches(c).contains(*c)).cloned().collect();
        if !on.is_empty() {
            found.push((parent.join("::"), on));
        }
    }
    found
}

#[test]
fn no_module_imports_in_a_circle() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut sources = vec![root.join("src"), root.join("python/src")];
    for entry in std::fs::read_dir(root.join("crates")).expect("the crates") {
        sources.push(entry.expect("an entry").path().join("src"));
    }
    let mut all = Vec::new();
    for src in sources.iter().filter(|s| s.is_dir()) {
        assert!(modules(src).len() > 1 || src.ends_with("python/src"), "no modules read in {}", src.display());
        all.extend(circles(src).into_iter().map(|(p, c)| format!("{}: {p}: {c:?}", src.display())));
    }
    assert!(all.is_empty(), "import circles:\n{}", all.join("\n"));
}

#[test]
fn a_circle_is_seen() {
    let dir = tempfile::tempdir().expect("a folder");
    let src = dir.path();
    std::fs::write(src.join("lib.rs"), "mod a;\nmod b;\n").expect("written");
    std::fs::write(src.join("a.rs"), "use crate::b::B;\npub struct A;\n").expect("written");
    std::fs::create_dir(src.join("b")).expect("made");
    std::fs::write(src.join("b/mod.rs"), "mod inner;\npub struct B;\n").expect("written");
    std::fs::write(
        src.join("b/inner.rs"),
        "// crate::a is only named here\nfn f() -> super::super::a::A { todo!() }\n",
    )
    .expect("written");
    let found = circles(src);
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].1, BTreeSet::from(["a".to_string(), "b".to_string()]));
}

/// Files are sized by concept; one past 800 lines holds more than one.
#[test]
fn no_source_file_is_past_800_lines() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut sources = vec![root.join("src"), root.join("tests"), root.join("examples"), root.join("python/src")];
    for entry in std::fs::read_dir(root.join("crates")).expect("the crates") {
        sources.push(entry.expect("an entry").path().join("src"));
    }
    let mut long = Vec::new();
    for src in sources.iter().filter(|s| s.is_dir()) {
        let mut folders = vec![src.clone()];
        while let Some(dir) = folders.pop() {
            for entry in std::fs::read_dir(&dir).expect("a readable folder") {
                let path = entry.expect("an entry").path();
                if path.is_dir() {
                    folders.push(path);
                } else if path.extension().is_some_and(|e| e == "rs") {
                    let lines = std::fs::read_to_string(&path).expect("a readable source").lines().count();
                    if lines > 800 {
                        long.push(format!("{} ({lines} lines)", path.display()));
                    }
                }
            }
        }
    }
    assert!(long.is_empty(), "files past 800 lines: {long:?}");
}
