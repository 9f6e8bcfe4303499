//! `tissue-sim validate`: the touch benchmark of one model.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;

use super::args::{GridArgs, ObjectArgs, params_from_file};
use super::output::{say, say_raw};
use crate::mechanics::sparse::DirectSolve;
use crate::sim::Model;
use crate::validate::touch_score;

/// The flags of `validate`.
#[derive(Debug, Args)]
#[allow(missing_docs)] // flattened argument groups document their own fields
pub struct ValidateArgs {
    /// The paper's object: A or B (with --material, the label of the report).
    #[arg(long, value_parser = ["A", "B"], ignore_case = true)]
    pub object: Option<String>,
    /// A material file (TOML, or JSON by extension) in place of the object's constants.
    #[arg(long)]
    pub material: Option<PathBuf>,
    #[command(flatten)]
    pub grid: GridArgs,
    /// A calibration result (JSON with `params`); default: the viewer's default tissue.
    #[arg(long, value_name = "FILE.json", conflicts_with = "model")]
    pub params: Option<PathBuf>,
    /// A FEM model instead of a spring lattice.
    #[arg(long, value_parser = ["fem-linear", "fem-corotational"])]
    pub model: Option<String>,
    /// Print JSON (the benchmark's contract) instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// Scores the model against the same-mesh FEM and prints the report.
pub fn run(args: ValidateArgs) -> anyhow::Result<()> {
    let ValidateArgs { object, material, grid, params, model, json } = args;
    let label = object.as_ref().map(|o| o.to_ascii_uppercase());
    // A material file replaces the object's constants; the object then only labels the report.
    let object = match material {
        Some(path) => ObjectArgs { object: None, material: Some(path) },
        None => ObjectArgs { object, material: None },
    };
    let grid = grid.grid()?;
    let (material, model) = match (params, model.as_deref()) {
        (Some(path), _) => {
            let (material, p) = params_from_file(&object, &path)?;
            (material, (Model::Lattice(p.topology()), Some(p)))
        }
        (None, Some(name)) => {
            (object.material(None)?, (Model::try_from(name.to_owned()).map_err(anyhow::Error::msg)?, None))
        }
        (None, None) => {
            let material = object.material(None)?;
            let p = crate::sim::shipped::default_params(&material)
                .context("the default tissue: give --params FILE.json or --model fem-linear")?;
            (material, (Model::Lattice(p.topology()), Some(p)))
        }
    };
    DirectSolve::TouchBenchmark.check_grid(grid.n()).map_err(anyhow::Error::msg)?;
    let reference = touch_score::Reference::new(&material, grid)?;
    let mut report = touch_score::evaluate(&reference, &material, model.0, model.1)
        .with_context(|| format!("scoring {} of material {}", model.0.name(), material.name))?;
    if let Some(label) = label {
        report.object = label;
    }
    if json { say(&serde_json::to_string_pretty(&report)?) } else { say_raw(&report.to_text()) }
}
