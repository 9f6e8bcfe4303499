//! `tissue-sim msm`: the static MSM equilibrium of the paper's clamped cases, as JSON.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;

use super::args::{GridArgs, ObjectArgs, ParamArgs};
use super::output::{cases_summary, progress_bar};
use crate::io::write_json_atomic;
use crate::mechanics::cases::{Bc, benchmark_cases};
use crate::mechanics::displacement_file::{CaseRecord, DisplacementFile};
use crate::mechanics::msm::{MsmModel, statics};
use crate::validate::accuracy::msm_context;

/// The flags of `msm`.
#[derive(Debug, Args)]
#[allow(missing_docs)] // flattened argument groups document their own fields
pub struct MsmArgs {
    #[command(flatten)]
    pub object: ObjectArgs,
    #[command(flatten)]
    pub params: ParamArgs,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Output JSON file.
    #[arg(long)]
    pub out: PathBuf,
}

/// Solves the cases and writes their node displacements.
pub fn run(args: MsmArgs) -> anyhow::Result<()> {
    let MsmArgs { object, params, grid, out } = args;
    crate::io::check_output(&out)?;
    let started = std::time::Instant::now();
    let material = object.material_with_inclusions(None)?;
    let params = params.resolve(&material)?;
    let grid = grid.grid()?;
    statics::check_grid(params.topology(), grid.n(), !material.inclusions.is_empty()).map_err(anyhow::Error::msg)?;
    let model = MsmModel::new(grid, params, material.density)?.with_inclusions(&material);
    let cases = benchmark_cases(&grid, &material.name, Bc::Clamped);
    let bar = progress_bar(cases.len() as u64, "cases");
    let sols = statics::solve_cases_with_progress(&model, &cases, &mut |i, id| {
        bar.set_position(i as u64);
        bar.set_message(id.to_owned());
    })
    .with_context(|| msm_context(&material, &params, grid.n()))?;
    bar.finish_and_clear();
    let file = DisplacementFile {
        object: material.name.clone(),
        bc: Bc::Clamped.name().into(),
        model: "msm".into(),
        nodes_per_axis: grid.n(),
        cases: sols.iter().map(CaseRecord::from_solution).collect(),
        params: Some(params),
    };
    file.check_finite()?;
    write_json_atomic(&out, &file)?;
    let what = format!(
        "{} clamped cases of the {} lattice of material {}",
        file.cases.len(),
        params.topology().name(),
        material.name
    );
    cases_summary("msm", &what, &file, &out, started);
    Ok(())
}
