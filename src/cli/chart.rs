//! `tissue-sim chart`: speed against accuracy of every model, resolution and integrator.

use std::path::PathBuf;

use clap::Args;

use crate::study::chart::ChartOptions;

/// The flags of `chart`.
#[derive(Debug, Args)]
pub struct ChartArgs {
    /// Output directory (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Objects to chart.
    #[arg(long, value_delimiter = ',', default_value = "A,B")]
    pub objects: Vec<String>,
    /// Resolutions, nodes per axis (2..=32).
    #[arg(long, value_delimiter = ',', default_value = "4,8,16,32", allow_hyphen_values = true)]
    pub resolutions: Vec<usize>,
    /// Skip the stability study (about 40 s).
    #[arg(long)]
    pub no_stability: bool,
}

/// Computes the chart (and the stability study) and writes it.
pub fn run(args: ChartArgs) -> anyhow::Result<()> {
    let ChartArgs { out, objects, resolutions, no_stability } = args;
    let opts = ChartOptions::new(objects, resolutions)?;
    let points = crate::study::write_chart(&out, &opts, !no_stability, &mut |m| crate::io::progress(m))?;
    super::output::summary("chart", &format!("wrote {} points and chart.md to {}", points.len(), out.display()));
    Ok(())
}
