//! `tissue-sim errors`: the paper's Tables IV and V for one parameter set.

use std::path::PathBuf;

use clap::Args;

use super::args::{GridArgs, ObjectArgs, ParamArgs, material_and_params};
use super::output::{say, say_raw};

/// The flags of `errors`.
#[derive(Debug, Args)]
#[allow(missing_docs)] // flattened argument groups document their own fields
pub struct ErrorsArgs {
    #[command(flatten)]
    pub object: ObjectArgs,
    #[command(flatten)]
    pub params: ParamArgs,
    /// Read the parameters (and the object, unless given) from a calibration result JSON.
    #[arg(long = "params", value_name = "FILE.json", conflicts_with_all = ["k1", "k2", "k3", "d", "c12", "c13", "c23", "b"])]
    pub params_file: Option<PathBuf>,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Print JSON instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// Prints the errors of the parameters against the FEM, as a table or JSON.
pub fn run(args: ErrorsArgs) -> anyhow::Result<()> {
    let (material, params) = material_and_params(&args.object, &args.params, args.params_file.as_deref())?;
    let report = crate::validate::accuracy::errors_report(&material, params, args.grid.grid()?)?;
    if args.json {
        // Through a `serde_json::Value`, whose keys are sorted: the order `errors --json` prints.
        say(&serde_json::to_string_pretty(&serde_json::to_value(&report)?)?)?;
    } else {
        say_raw(&report.to_text())?;
    }
    super::output::summary("errors", &report.headline());
    Ok(())
}
