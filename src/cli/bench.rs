//! `tissue-sim bench`: the speed benchmark of the physics core.

use clap::Args;

use super::output::{say, say_raw};

/// The flags of `bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs the benchmark and prints its report.
pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    let report = crate::study::bench::run()?;
    if args.json { say(&serde_json::to_string_pretty(&report)?) } else { say_raw(&report.to_text()) }
}
