//! Command-line round trips and bad-input handling of the `tissue-sim` binary.

#[path = "../support/test_cache.rs"]
mod test_cache;

use std::path::Path;
use std::process::{Command, Output};

use tissue_core::mechanics::displacement_file::DisplacementFile;

mod bad_input;
mod cache;
mod calibrate;
mod chart;
mod commands;
mod docs;
mod palpate;
mod simulate;
mod validate;

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tissue-sim")).args(args).output().expect("binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn read(path: &Path) -> DisplacementFile {
    serde_json::from_str(&std::fs::read_to_string(path).expect("file written")).expect("valid JSON")
}

/// Runs the binary with `envs` set and `DISPLAY`-style variables removed where `clear` says.
fn run_env(args: &[&str], envs: &[(&str, &str)], clear: &[&str]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_tissue-sim"));
    c.args(args);
    for k in clear {
        c.env_remove(k);
    }
    for (k, v) in envs {
        c.env(k, v);
    }
    c.output().expect("binary runs")
}
