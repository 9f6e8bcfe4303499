//! `tissue-sim calibrate`: the MSM calibrated against the FEM reference.

use std::path::PathBuf;

use anyhow::{Context as _, bail};
use clap::Args;

use super::args::{GridArgs, ObjectArgs};
use super::output::{progress_bar, summary};
use crate::calibrate::{CaseSet, CostMode, GeneSpace, Method, Problem, Settings, calibrate};
use crate::io::write_json_atomic;
use crate::mechanics::msm::Topology;

/// The flags of `calibrate`.
#[derive(Debug, Args)]
#[allow(missing_docs)] // flattened argument groups document their own fields
pub struct CalibrateArgs {
    #[command(flatten)]
    pub object: ObjectArgs,
    /// Search method.
    #[arg(long, value_parser = crate::cli::values::parser::<Method>(), default_value = "hybrid")]
    pub method: Method,
    /// Random seed (same seed and settings: same result).
    #[arg(long, default_value_t = 1, allow_hyphen_values = true)]
    pub seed: u64,
    /// Population size [default: 10 for the shear and hex lattices' static cost, which the
    /// gradient polish finishes at the same optimum; the paper's 50 otherwise].
    #[arg(long, allow_hyphen_values = true)]
    pub population: Option<usize>,
    /// Generations (temperature steps for SA) [default: 10 for the shear and hex lattices' static
    /// cost; the paper's 100 otherwise].
    #[arg(long, allow_hyphen_values = true)]
    pub generations: Option<usize>,
    /// Mutation probability per chromosome.
    #[arg(long, default_value_t = 0.2, allow_hyphen_values = true)]
    pub mutation: f64,
    /// Crossover probability per selected pair.
    #[arg(long, default_value_t = 0.8, allow_hyphen_values = true)]
    pub crossover: f64,
    /// Cost: static equilibria (the paper's), or the state 20 ms after a step load, which identifies
    /// damping (on the paper's cases only).
    #[arg(long, value_parser = crate::cli::values::parser::<CostMode>(), default_value = "static")]
    pub cost: CostMode,
    /// MSM topology: the paper's axis springs, axis + face-diagonal (shear) springs, or the hex-element lattice.
    #[arg(long, value_parser = crate::cli::values::parser::<Topology>(), default_value = "axis")]
    pub model: Topology,
    /// Training cases: the paper's nine face loads, the touch benchmark's training set, both, or
    /// the material's training presses (refused on a grid where no press touches a node).
    #[arg(long, value_parser = crate::cli::values::parser::<CaseSet>(), default_value = "paper")]
    pub cases: CaseSet,
    /// Override a gene's search bounds, e.g. `--bound k1=100:5000` (repeatable).
    #[arg(long = "bound", value_name = "GENE=LO:HI")]
    pub bounds: Vec<String>,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Output JSON file (the spec's calibration result).
    #[arg(long)]
    pub out: PathBuf,
}

/// Calibrates and writes the result.
pub fn run(args: CalibrateArgs) -> anyhow::Result<()> {
    let CalibrateArgs {
        object,
        method,
        seed,
        population,
        generations,
        mutation,
        crossover,
        cost,
        model,
        cases,
        bounds,
        grid,
        out,
    } = args;
    crate::io::check_output(&out)?;
    let material = object.material(None)?;
    let grid = grid.grid()?;
    let (default_population, default_generations) = Settings::default_search(model, cost);
    let (population, generations) =
        (population.unwrap_or(default_population), generations.unwrap_or(default_generations));
    let settings = Settings { method, seed, population, generations, mutation, crossover, cost, ..Settings::default() };
    settings.validate().map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut space = GeneSpace::new(&material, &grid, model);
    let mut seen: Vec<&str> = Vec::new();
    for b in &bounds {
        let (name, range) = b.split_once('=').with_context(|| format!("--bound {b:?}: expected GENE=LO:HI"))?;
        if seen.contains(&name.trim()) {
            anyhow::bail!("--bound {} is given twice; give each gene's bounds once", name.trim());
        }
        seen.push(name.trim());
        let (lo, hi) = range.split_once(':').with_context(|| format!("--bound {b:?}: expected GENE=LO:HI"))?;
        let lo: f64 = lo.trim().parse().with_context(|| format!("--bound {b:?}: bad lower bound"))?;
        let hi: f64 = hi.trim().parse().with_context(|| format!("--bound {b:?}: bad upper bound"))?;
        space.set_bound(name.trim(), lo, hi).map_err(|e| anyhow::anyhow!("--bound: {e}"))?;
    }
    crate::mechanics::msm::statics::check_grid(model, grid.n(), false).map_err(anyhow::Error::msg)?;
    // Settings the cost cannot use are refused here, before any reference is computed.
    crate::calibrate::check_setup(&settings, cases, model, grid)?;
    let name = material.name.clone();
    let problem = Problem::new(material, grid, model)
        .and_then(|p| p.with_cases(cases))
        .with_context(|| format!("the FEM reference of material {name} at {}^3", grid.n()))?;
    let bar = progress_bar(generations as u64, "generations");
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let result = calibrate(&problem, &space, &settings, &cancel, &mut |s| {
        bar.set_position(s.generation as u64);
        bar.set_message(format!("best cost {:.6e} m", s.best_cost));
    })
    .with_context(|| format!("calibrating the {model:?} MSM of material {name}"))?;
    bar.finish_and_clear();
    if !result.cost.is_finite() {
        bail!(
            "calibration of material {name} found no parameter set with a finite cost inside the bounds \
             (every evaluation failed); widen or move the --bound ranges"
        );
    }
    write_json_atomic(&out, &result)?;
    summary("calibrate", &summary_line(&result, model, &name, &out));
    Ok(())
}

/// The closing line: the genes found, the cost, and a warning for each gene on a bound.
fn summary_line(
    result: &crate::calibrate::CalibrationResult,
    model: Topology,
    name: &str,
    out: &std::path::Path,
) -> String {
    let genes: Vec<String> = result
        .bounds
        .names
        .iter()
        .filter(|n| result.d_identified || n.as_str() != "d")
        .filter_map(|n| Some(format!("{n} = {}", crate::io::num(GeneSpace::value(&result.params, n)?))))
        .collect();
    let (unit, _) = crate::calibrate::cost_meaning(result.cases, result.cost_mode);
    let mut line = format!(
        "the {} lattice of material {name} written to {}: {} ({}), cost {}{}{unit}, {} evaluations, {:.1} s",
        model.name(),
        out.display(),
        genes.join(", "),
        if result.d_identified { "N/m; d N s/m" } else { "N/m" },
        crate::io::num(result.cost),
        if unit.is_empty() { "" } else { " " },
        result.evaluations,
        result.wall_s
    );
    for (gene, value, side) in result.bounds.on_bounds(&result.params) {
        if gene != "d" || result.d_identified {
            line.push_str(&format!(
                "; warning: {gene} = {} is on its {side} bound (widen it with --bound {gene}=LO:HI)",
                crate::io::num(value)
            ));
        }
    }
    if result.cancelled {
        line.push_str("; cancelled: the best so far");
    }
    line
}
