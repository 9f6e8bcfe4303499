//! The flag groups several subcommands share (the material, the grid, the MSM parameters) and
//! the calibration result file they read parameters from.

use std::path::{Path, PathBuf};

use anyhow::{Context as _, bail};
use clap::Args;

use crate::io::read_json;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::msm::MsmParams;

/// Which material: a preset object or a file.
#[derive(Debug, Args)]
pub struct ObjectArgs {
    /// The paper's object: A (orthotropic) or B (transversely isotropic).
    #[arg(long, value_parser = ["A", "B"], ignore_case = true, conflicts_with = "material")]
    pub object: Option<String>,
    /// A material file (TOML, or JSON by extension), see README.
    #[arg(long)]
    pub material: Option<PathBuf>,
}

/// Grid resolution.
#[derive(Debug, Args)]
pub struct GridArgs {
    /// Nodes per axis (the paper: 8).
    #[arg(long, default_value_t = 8, allow_hyphen_values = true)]
    pub nodes: usize,
}

/// MSM parameters on the command line.
#[derive(Debug, Default, Args)]
pub struct ParamArgs {
    /// Axis-1 spring stiffness, N/m.
    #[arg(long, allow_hyphen_values = true)]
    pub k1: Option<f64>,
    /// Axis-2 spring stiffness, N/m.
    #[arg(long, allow_hyphen_values = true)]
    pub k2: Option<f64>,
    /// Axis-3 spring stiffness, N/m (equal to k2 for a transversely isotropic object).
    #[arg(long, allow_hyphen_values = true)]
    pub k3: Option<f64>,
    /// Nodal damping, N s/m (no effect on a static answer).
    #[arg(long, allow_hyphen_values = true)]
    pub d: Option<f64>,
    /// Face-diagonal stiffness, 1-2 plane, N/m (shear model).
    #[arg(long, allow_hyphen_values = true)]
    pub c12: Option<f64>,
    /// Face-diagonal stiffness, 1-3 plane, N/m (shear model; = c12 for transversely isotropic).
    #[arg(long, allow_hyphen_values = true)]
    pub c13: Option<f64>,
    /// Face-diagonal stiffness, 2-3 plane, N/m (shear model).
    #[arg(long, allow_hyphen_values = true)]
    pub c23: Option<f64>,
    /// Body-diagonal stiffness, N/m (hex model, which also needs the c's).
    #[arg(long, allow_hyphen_values = true)]
    pub b: Option<f64>,
}

impl ObjectArgs {
    /// The chosen material, or `fallback` (an object label from a file) when none is given.
    pub fn material(&self, fallback: Option<&str>) -> anyhow::Result<Material> {
        let material = self.material_with_inclusions(fallback)?;
        // Read and checked whole (the inclusions too), then refused where not modelled yet.
        material.require_homogeneous("this command")?;
        Ok(material)
    }

    /// [`ObjectArgs::material`] for a command that models inclusions.
    pub fn material_with_inclusions(&self, fallback: Option<&str>) -> anyhow::Result<Material> {
        if let Some(path) = &self.material {
            return Ok(Material::from_file(path)?);
        }
        let name = self.object.as_deref().or(fallback).context("give --object A|B or --material FILE")?;
        Material::preset(&name.to_ascii_uppercase())
            .with_context(|| format!("unknown object {name:?}: the presets are A and B (or use --material FILE)"))
    }
}

impl GridArgs {
    /// The grid of `--nodes`.
    pub fn grid(&self) -> anyhow::Result<Grid> {
        Grid::new(self.nodes).context("invalid --nodes")
    }
}

impl ParamArgs {
    /// Completes and checks the parameters for `material`: `k3` (and `c13`) default to `k2`
    /// (`c12`) for a transversely isotropic object and must equal them if given.
    pub fn resolve(&self, material: &Material) -> anyhow::Result<MsmParams> {
        let k1 = self.k1.context("missing --k1")?;
        let k2 = self.k2.context("missing --k2")?;
        let ti = material.is_transversely_isotropic();
        let k3 = match (self.k3, ti) {
            (Some(k3), _) => k3,
            (None, true) => k2,
            (None, false) => bail!("missing --k3 (object {} is orthotropic)", material.name),
        };
        let mut p = MsmParams::axis(k1, k2, k3, self.d.unwrap_or(0.0));
        if self.c12.is_some() || self.c13.is_some() || self.c23.is_some() {
            let c12 = self.c12.context("the shear model needs --c12")?;
            let c23 = self.c23.context("the shear model needs --c23")?;
            let c13 = match (self.c13, ti) {
                (Some(c13), _) => c13,
                (None, true) => c12,
                (None, false) => bail!("the shear model needs --c13 (object {} is orthotropic)", material.name),
            };
            (p.c12, p.c13, p.c23) = (Some(c12), Some(c13), Some(c23));
        }
        if let Some(b) = self.b {
            if p.c12.is_none() {
                bail!("the hex model (--b) also needs --c12, --c13 and --c23");
            }
            p.b = Some(b);
        }
        p.validate()?;
        p.check_ties(ti).with_context(|| format!("object {}", material.name))?;
        Ok(p)
    }
}

/// The keys of a calibration result that `--params FILE.json` reads.
#[derive(Debug, serde::Deserialize)]
struct ParamsFile {
    object: Option<String>,
    /// The lattice the file says it holds (a calibration result's `model`), checked against
    /// `params`, never ignored.
    model: Option<crate::mechanics::msm::Topology>,
    params: MsmParams,
}

/// The parameters of a calibration result file, checked, with the material of `object` (the
/// file's object when `object` names none).
pub fn params_from_file(object: &ObjectArgs, path: &Path) -> anyhow::Result<(Material, MsmParams)> {
    let (material, params) = params_from_file_with_inclusions(object, path)?;
    material.require_homogeneous("this command")?;
    Ok((material, params))
}

/// [`params_from_file`] for a command that models inclusions.
pub fn params_from_file_with_inclusions(object: &ObjectArgs, path: &Path) -> anyhow::Result<(Material, MsmParams)> {
    let file: ParamsFile = read_json(path)?;
    let material = object.material_with_inclusions(file.object.as_deref())?;
    file.params.validate().with_context(|| format!("in {}", path.display()))?;
    if let Some(model) = file.model
        && model != file.params.topology()
    {
        anyhow::bail!(
            "in {}: \"model\" is {} but the parameters are those of the {} lattice (the constants given \
             decide: axis k1..k3, shear also c12..c23, hex also b)",
            path.display(),
            model.name(),
            file.params.topology().name()
        );
    }
    file.params
        .check_ties(material.is_transversely_isotropic())
        .with_context(|| format!("in {} (object {})", path.display(), material.name))?;
    Ok((material, file.params))
}

/// The material and parameters: from a calibration result file ([`params_from_file`]), or from
/// the flags.
pub fn material_and_params(
    object: &ObjectArgs,
    params: &ParamArgs,
    params_file: Option<&Path>,
) -> anyhow::Result<(Material, MsmParams)> {
    match params_file {
        Some(path) => params_from_file(object, path),
        None => {
            let material = object.material(None)?;
            let p = params.resolve(&material)?;
            Ok((material, p))
        }
    }
}
