//! The one model vocabulary: which model of the tissue runs, a spring lattice or the hex8 FEM,
//! and how it is built for the simulation.

use super::fem_tissue::FemTissue;
use super::integrator::Integrator;
use super::msm_tissue::MsmTissue;
use super::tissue::Tissue;
use crate::mechanics::fem::dynamics::Formulation;
use crate::mechanics::material::Material;
use crate::mechanics::msm::{MsmModel, MsmParams, Topology};

/// Which model runs: a spring lattice with the shipped tissue of its topology, or the hex8 FEM.
/// Written `axis`, `shear`, `hex`, `fem-linear` or `fem-corotational` (scripts, the command line).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum Model {
    /// A spring lattice.
    Lattice(Topology),
    /// The FEM cube.
    Fem(Formulation),
}

impl Model {
    /// Every model, cheapest first (the chart's order; the panel's colours follow it).
    pub const ALL: [Model; 5] = [
        Model::Lattice(Topology::Axis),
        Model::Lattice(Topology::Shear),
        Model::Lattice(Topology::Hex),
        Model::Fem(Formulation::Linear),
        Model::Fem(Formulation::Corotational),
    ];

    /// Its name in scripts, the command line and JSON: `hex`, ..., `fem-corotational`.
    pub fn name(self) -> String {
        match self {
            Model::Lattice(t) => t.name().to_owned(),
            Model::Fem(f) => format!("fem-{}", f.name()),
        }
    }

    /// Its name in the chart's files: `msm-hex`, ..., `fem-corotational`.
    pub fn chart_name(self) -> String {
        match self {
            Model::Lattice(t) => format!("msm-{}", t.name()),
            Model::Fem(_) => self.name(),
        }
    }

    /// The model of a [`Model::chart_name`].
    pub fn from_chart_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.chart_name() == name)
    }

    /// Whether the model steps with `integrator` (the FEM has no full-tangent implicit step).
    pub fn check_integrator(self, integrator: Integrator) -> Result<(), String> {
        match self {
            Model::Fem(_) => super::fem_tissue::check_integrator(integrator),
            Model::Lattice(_) => Ok(()),
        }
    }

    /// The running tissue of `material` (its inclusions too: the FEM's elements take them, a
    /// lattice's springs by [`crate::mechanics::msm::inclusions`]) at rest on the paper's grid: a
    /// lattice with `params` (the shipped tissue where `None`), or the FEM; damped by the ratio `zeta` at its
    /// fundamental ([`crate::response::damping`]), except the paper's axis lattice, which keeps
    /// its nodal `d`.
    pub fn build(self, material: &Material, params: Option<MsmParams>, zeta: f64) -> anyhow::Result<Box<dyn Tissue>> {
        self.build_on(crate::mechanics::grid::Grid::paper(), material, params, zeta)
    }

    /// [`Model::build`] on `grid`: a lattice without `params` takes its shipped tissue carried
    /// to the grid ([`crate::sim::shipped::msm_params_at`]).
    pub fn build_on(
        self,
        grid: crate::mechanics::grid::Grid,
        material: &Material,
        params: Option<MsmParams>,
        zeta: f64,
    ) -> anyhow::Result<Box<dyn Tissue>> {
        let mut tissue = self.build_undamped_on(grid, material, params)?;
        if self.takes_damping_ratio() {
            tissue.set_damping_ratio(zeta).map_err(|e| anyhow::anyhow!("{e}"))?;
        }
        Ok(tissue)
    }

    /// [`Model::build_on`] without the damping ratio (a lattice keeps its parameters' nodal
    /// `d`, the FEM is undamped): no fundamental is solved for, so it builds at any grid.
    pub fn build_undamped_on(
        self,
        grid: crate::mechanics::grid::Grid,
        material: &Material,
        params: Option<MsmParams>,
    ) -> anyhow::Result<Box<dyn Tissue>> {
        Ok(match self {
            Model::Lattice(t) => {
                let p = match params {
                    Some(p) => p,
                    None => crate::sim::shipped::msm_params_at(material, t, &grid)?,
                };
                let model = MsmModel::new(grid, p, material.density)?.with_inclusions(material);
                Box::new(MsmTissue::new(model, material.density))
            }
            Model::Fem(f) => Box::new(FemTissue::new(grid, material, f)),
        })
    }

    /// Whether the model is damped by a ratio (all but the paper's axis lattice, which keeps its
    /// nodal `d`).
    pub fn takes_damping_ratio(self) -> bool {
        self != Model::Lattice(Topology::Axis)
    }
}

impl From<Model> for String {
    fn from(m: Model) -> String {
        m.name()
    }
}

/// The model's [`Model::name`] (width and alignment honoured).
impl std::fmt::Display for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(&self.name())
    }
}

impl TryFrom<String> for Model {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        Model::ALL.into_iter().find(|m| m.name() == s).ok_or_else(|| {
            let known: Vec<String> = Model::ALL.iter().map(|m| m.name()).collect();
            format!("unknown model {s:?}: the models are {}", known.join(", "))
        })
    }
}
