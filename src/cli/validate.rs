//! `tissue-sim validate`: the touch benchmark of one model.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;

use super::args::{GridArgs, ObjectArgs, params_from_file_with_inclusions};
use super::output::{say, say_raw};
use crate::mechanics::sparse::DirectSolve;
use crate::sim::Model;
use crate::validate::touch::score as touch_score;

/// The flags of `validate`.
#[derive(Debug, Args)]
#[allow(missing_docs)] // flattened argument groups document their own fields
pub struct ValidateArgs {
    /// The paper's object: A or B (with --material, the label of the report).
    #[arg(long, value_parser = ["A", "B"], ignore_case = true)]
    pub object: Option<String>,
    /// A material file (TOML, or JSON by extension) in place of the object's constants; with
    /// inclusions, the presses are over them, and the model is also scored against the material
    /// with them under a pressure over each.
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
    /// Where the material's probe forces are kept (default: $XDG_CACHE_HOME/tissue-sim, else
    /// ~/.cache/tissue-sim). The paper's objects ship theirs.
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// Score against the same-mesh FEM only, not the probe presses against the material.
    #[arg(long)]
    pub own_mesh_only: bool,
    /// How the probe touches in the presses against the material: `surface` (the viewer's: the
    /// material's surface compliance on a 2 mm lattice of the free surface, computed once per
    /// material, about a minute, and kept in the cache folder) or `nodes` (the model's surface nodes).
    #[arg(long, default_value = "surface")]
    pub contact: crate::sim::press::Contact,
}

/// Scores the model against the same-mesh FEM and prints the report.
pub fn run(args: ValidateArgs) -> anyhow::Result<()> {
    let ValidateArgs { object, material, grid, params, model, json, cache, own_mesh_only, contact } = args;
    let label = object.as_ref().map(|o| o.to_ascii_uppercase());
    // A material file replaces the object's constants; the object then only labels the report.
    let object = match material {
        Some(path) => ObjectArgs { object: None, material: Some(path) },
        None => ObjectArgs { object, material: None },
    };
    let grid = grid.grid()?;
    let (material, model) = match (params, model.as_deref()) {
        (Some(path), _) => {
            let (material, p) = params_from_file_with_inclusions(&object, &path)?;
            (material, (Model::Lattice(p.topology()), Some(p)))
        }
        (None, Some(name)) => (
            object.material_with_inclusions(None)?,
            (Model::try_from(name.to_owned()).map_err(anyhow::Error::msg)?, None),
        ),
        (None, None) => {
            let material = object.material_with_inclusions(None)?;
            let p = crate::sim::shipped::default_params(&material)
                .context("the default tissue: give --params FILE.json or --model fem-linear")?;
            (material, (Model::Lattice(p.topology()), Some(p)))
        }
    };
    DirectSolve::TouchBenchmark.check_grid(grid.n()).map_err(anyhow::Error::msg)?;
    if !own_mesh_only && !material.inclusions.is_empty() {
        crate::validate::inclusions::refinement(grid)?;
    }
    // A cache folder given by name must be usable before any work.
    if let Some(dir) = &cache {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot use the cache folder {}", dir.display()))?;
    }
    let reference = touch_score::Reference::new(&material, grid)?;
    let mut report = touch_score::evaluate(&reference, &material, model.0, model.1)
        .with_context(|| format!("scoring {} of material {}", model.0.name(), material.name))?;
    let inclusions = if own_mesh_only || material.inclusions.is_empty() {
        None
    } else {
        eprintln!("the model against the material with its inclusions: reference solves ...");
        Some(crate::validate::inclusions::evaluate(&material, model.0, model.1, grid)?)
    };
    let material = if own_mesh_only { None } else { Some(against_material(&material, grid, model, cache, contact)?) };
    if let Some(label) = label {
        report.object = label;
    }
    let full = Full { report, material, inclusions };
    let line = summary_line(&full, contact);
    let result = if json {
        say(&serde_json::to_string_pretty(&full)?)
    } else {
        let mut text = full.report.to_text();
        if let Some(m) = &full.material {
            text += "\n";
            text += &m.to_text();
        }
        if let Some(l) = &full.inclusions {
            text += "\n";
            text += &l.to_text();
        }
        say_raw(&text)
    };
    super::output::summary("validate", &line);
    result
}

/// The JSON of `validate`: the touch benchmark's keys and, unless `--own-mesh-only`, `material`.
#[derive(serde::Serialize)]
struct Full {
    #[serde(flatten)]
    report: touch_score::Report,
    #[serde(skip_serializing_if = "Option::is_none")]
    material: Option<crate::validate::probe::score::MaterialReport>,
    /// For a material with inclusions: the model against the material with them.
    #[serde(skip_serializing_if = "Option::is_none")]
    inclusions: Option<crate::validate::inclusions::InclusionReport>,
}

/// The probe presses of `model` against the material, the same-mesh FEM beside it.
fn against_material(
    material: &crate::mechanics::material::Material,
    grid: crate::mechanics::grid::Grid,
    model: (Model, Option<crate::mechanics::msm::MsmParams>),
    cache: Option<PathBuf>,
    contact: crate::sim::press::Contact,
) -> anyhow::Result<crate::validate::probe::score::MaterialReport> {
    use crate::validate::continuum::{self, cache as continuum_cache};
    use crate::validate::probe::score as probe_score;
    let dir = cache.or_else(crate::io::cache_dir);
    let mut kept = continuum_cache::ContinuumCache::open(material, dir.as_deref());
    let (mut responder, _) = touch_score::responder(model.0, model.1, material, grid)?;
    let fem = Model::Fem(crate::mechanics::fem::dynamics::Formulation::Linear);
    let (mut own, _) = touch_score::responder(fem, None, material, grid)?;
    let start = std::time::Instant::now();
    let mut model_force: Box<dyn FnMut(&continuum::Press) -> anyhow::Result<f64>> =
        if contact == crate::sim::press::Contact::Surface {
            let mut report = crate::sim::material_surface::stderr_report();
            let compliance =
                crate::sim::material_surface::load_or_compute(material, dir.as_deref(), &mut |e| report.event(e))?;
            let mut scratch = crate::sim::material_surface::compliance::SurfaceContactScratch::default();
            Box::new(move |press| probe_score::compliance_force_n(&compliance, &mut scratch, press))
        } else {
            Box::new(move |press| probe_score::responder_force_n(&mut responder, press))
        };
    probe_score::evaluate(
        material,
        contact,
        &mut *model_force,
        &mut own,
        &mut kept,
        continuum::DEFAULT_TOLERANCE,
        &mut |i, n, case, spacing| {
            eprintln!(
                "the material's force, press {}/{n} ({}): {:.2} mm spacing, {:.0} s",
                i + 1,
                case.id,
                spacing * 1e3,
                start.elapsed().as_secs_f64()
            );
        },
    )
    .with_context(|| {
        format!(
            "the probe against the material (answers kept in {})",
            dir.as_deref().map_or("no cache folder".into(), |d| d.display().to_string())
        )
    })
}

/// The closing line: the model's touch score and the probe's against the material.
fn summary_line(full: &Full, contact: crate::sim::press::Contact) -> String {
    let r = &full.report;
    let mut line = format!(
        "{} of material {} at {}^3 against the same-mesh FEM on the held-out touches: force error worst {:.1} %, \
         median {:.1} %",
        r.model.name(),
        r.object,
        r.nodes_per_axis,
        100.0 * r.worst_force_error,
        100.0 * r.median_force_error
    );
    if let Some(m) = &full.material {
        line.push_str(&format!(
            "; the probe against the material ({} contact) on the held-out presses: worst {:.1} %, median {:.1} %",
            contact.name(),
            100.0 * m.worst_error,
            100.0 * m.median_error
        ));
        if !m.missing.is_empty() {
            line.push_str(&format!("; warning: {} presses missing (the continuum did not converge)", m.missing.len()));
        }
    }
    line
}
