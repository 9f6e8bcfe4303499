//! `tissue-sim reproduce`: the paper's tables and figures.

use std::path::PathBuf;

use clap::Args;

/// The flags of `reproduce`.
#[derive(Debug, Args)]
pub struct ReproduceArgs {
    /// Output directory (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Seeds per method and object.
    #[arg(long, default_value_t = 10, allow_hyphen_values = true, value_parser = clap::value_parser!(u64).range(1..=1000))]
    pub seeds: u64,
    /// Skip the richer lattices' calibrations (shear and hex, about 55 s per object).
    #[arg(long)]
    pub no_shear: bool,
}

/// Writes the report and its data.
pub fn run(args: ReproduceArgs) -> anyhow::Result<()> {
    let ReproduceArgs { out, seeds, no_shear } = args;
    crate::study::reproduce::run(&out, &crate::study::reproduce::Options { seeds, shear: !no_shear })?;
    super::output::summary(
        "reproduce",
        &format!(
            "the paper's Tables III-V and Figs. 5-6 written to {} (report.md, the SVG and PNG plots, their data)",
            out.display()
        ),
    );
    Ok(())
}
