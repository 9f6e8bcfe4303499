//! `tissue-sim fem`: the linear static FEM reference of the benchmark cases, as JSON.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;

use super::args::{GridArgs, ObjectArgs};
use super::output::{cases_summary, progress_bar};
use crate::io::write_json_atomic;
use crate::mechanics::cases::{Bc, benchmark_cases};
use crate::mechanics::displacement_file::{CaseRecord, DisplacementFile};
use crate::mechanics::fem::FemModel;
use crate::mechanics::sparse::DirectSolve;

/// The flags of `fem`.
#[derive(Debug, Args)]
#[allow(missing_docs)] // flattened argument groups document their own fields
pub struct FemArgs {
    #[command(flatten)]
    pub object: ObjectArgs,
    /// Boundary conditions.
    #[arg(long, value_parser = crate::cli::values::parser::<Bc>(), default_value = "clamped")]
    pub bc: Bc,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Output JSON file.
    #[arg(long)]
    pub out: PathBuf,
}

/// Solves the cases and writes their node displacements.
pub fn run(args: FemArgs) -> anyhow::Result<()> {
    let FemArgs { object, bc, grid, out } = args;
    crate::io::check_output(&out)?;
    let started = std::time::Instant::now();
    let material = object.material_with_inclusions(None)?;
    let grid = grid.grid()?;
    // The patch cases, and any case of a material with inclusions (no mirror symmetry), solve
    // the full system.
    if bc == Bc::Patch || !material.inclusions.is_empty() {
        DirectSolve::FemPatch.check_grid(grid.n()).map_err(anyhow::Error::msg)?;
    }
    let cases = benchmark_cases(&grid, &material.name, bc);
    let bar = progress_bar(cases.len() as u64, "cases");
    let sols = FemModel::new(grid, &material)
        .solve_cases_with_progress(&cases, &mut |i, id| {
            bar.set_position(i as u64);
            bar.set_message(id.to_owned());
        })
        .with_context(|| {
            format!(
                "solving the FEM stiffness system of material {} at {n}^3 ({} cases)",
                material.name,
                bc.name(),
                n = grid.n()
            )
        })?;
    bar.finish_and_clear();
    let file = DisplacementFile {
        object: material.name.clone(),
        bc: bc.name().into(),
        model: "fem".into(),
        nodes_per_axis: grid.n(),
        cases: sols.iter().map(CaseRecord::from_solution).collect(),
        params: None,
    };
    file.check_finite()?;
    write_json_atomic(&out, &file)?;
    let what = format!("{} {} cases of material {}", file.cases.len(), bc.name(), material.name);
    cases_summary("fem", &what, &file, &out, started);
    Ok(())
}
