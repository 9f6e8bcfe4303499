//! `tissue-sim dynamics`: one model, integrator and step measured against the FEM's dynamic
//! reference.

use crate::mechanics::object::Object;
use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;

use super::args::{ObjectArgs, params_from_file};
use super::output::{say, say_raw};
use crate::mechanics::grid::Grid;
use crate::sim::{Integrator, Model};
use crate::validate::dynamic::{measure as dynamic_measure, reference as dynamic_reference};

/// The flags of `dynamics`.
#[derive(Debug, Args)]
pub struct DynamicsArgs {
    /// The paper's object: A or B.
    #[arg(long)]
    pub object: Object,
    /// A calibration result (JSON with `params`); default: the viewer's default tissue.
    #[arg(long, value_name = "FILE.json", conflicts_with = "model")]
    pub params: Option<PathBuf>,
    /// The model: a lattice with its shipped tissue, or the FEM.
    #[arg(long, value_parser = ["hex", "shear", "axis", "fem-linear", "fem-corotational"])]
    pub model: Option<String>,
    /// Integrator; default: the viewer's automatic choice for --dt (its dynamic budget).
    #[arg(long, value_parser = crate::cli::values::parser::<Integrator>())]
    pub integrator: Option<Integrator>,
    /// Time step, s (default: the viewer's, 1e-4).
    #[arg(long, default_value_t = 1e-4, allow_hyphen_values = true)]
    pub dt: f64,
    /// Damping ratio at the fundamental (mass-proportional).
    #[arg(long, default_value_t = crate::response::damping::DEFAULT_DAMPING_RATIO, allow_hyphen_values = true)]
    pub damping_ratio: f64,
    /// The scene of the trajectories and modes: the viewer's (face z = 0 clamped, a 1 N
    /// top-face shear, the probe tap) or the paper's clamped case along axis 1, 2 or 3 (10 N).
    #[arg(long, default_value = "view", value_parser = ["view", "clamped-1", "clamped-2", "clamped-3"])]
    pub scene: String,
    /// Print JSON (the contract) instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Measures the model and prints the report.
pub fn run(args: DynamicsArgs) -> anyhow::Result<()> {
    let DynamicsArgs { object, params, model, integrator, dt, damping_ratio, scene, json } = args;
    crate::sim::check_dt(dt).map_err(|e| anyhow::anyhow!("--dt {e}"))?;
    let zeta =
        crate::response::damping::check_ratio(damping_ratio).map_err(|e| anyhow::anyhow!("--damping-ratio: {e}"))?;
    let object_args = ObjectArgs { object: Some(object.name().to_owned()), material: None };
    let (material, choice, p) = match (params, model.as_deref()) {
        (Some(path), _) => {
            let (material, p) = params_from_file(&object_args, &path)?;
            (material, Model::Lattice(p.topology()), Some(p))
        }
        (None, name) => {
            let material = object_args.material(None)?;
            let choice = match name {
                Some(n) => Model::try_from(n.to_owned()).map_err(|e| anyhow::anyhow!("{e}"))?,
                None => Model::Lattice(crate::sim::shipped::DEFAULT_TOPOLOGY),
            };
            (material, choice, None)
        }
    };
    if !choice.takes_damping_ratio() {
        anyhow::bail!("dynamics: {}", crate::response::modal::AXIS_HAS_NO_MODES);
    }
    // The viewer's policy picks the integrator and step (or checks the one asked for).
    let tissue = choice.build(&material, p, zeta)?;
    let (integrator, dt, note) = crate::sim::choose_step(
        integrator,
        dt,
        tissue.step_limit(),
        tissue.damping(),
        crate::sim::DEFAULT_DYNAMIC_BUDGET,
    )
    .map_err(|e| anyhow::anyhow!("dynamics: {e}; lower --dt or choose --integrator prefactored"))?;
    choice.check_integrator(integrator).map_err(|e| anyhow::anyhow!("dynamics: {e}"))?;
    let grid = Grid::paper();
    let scene = match scene.strip_prefix("clamped-").and_then(|a| a.parse::<usize>().ok()) {
        Some(axis) => dynamic_reference::paper_scene(&grid, &material.name, axis),
        None => dynamic_reference::view_scene(&grid),
    };
    let refs = dynamic_measure::References::with_scene(&material, zeta, scene)?;
    let config = dynamic_measure::Configuration { model: choice, params: p, integrator, dt };
    let report = dynamic_measure::measure(&refs, config)
        .with_context(|| format!("measuring {} with {} at dt = {} s", choice.name(), integrator.name(), dt))?;
    if json {
        say(&serde_json::to_string_pretty(&report)?)?
    } else {
        say_raw(&report.to_text(note.as_deref()))?
    }
    super::output::summary(
        "dynamics",
        &format!(
            "{} of material {} with {} at dt = {} s measured (the report above)",
            choice.name(),
            material.name,
            integrator.name(),
            crate::io::num(dt)
        ),
    );
    Ok(())
}
