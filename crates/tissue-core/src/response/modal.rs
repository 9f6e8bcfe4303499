//! A model's small-displacement dynamics: its rest stiffness `K` and lumped masses `M` on a
//! clamp, the lowest modes `K phi = omega^2 M phi`, and static shapes `K u = f`.

use crate::mechanics::cases::LoadCase;
use crate::mechanics::fem::FemModel;
use crate::mechanics::grid::Grid;
use crate::mechanics::msm::{MsmModel, MsmParams, Topology};
use crate::mechanics::sparse::SparseError;
use crate::response::linear::{GroupedStiffness, SceneSolver, group_values};
pub use crate::response::modes::Mode;

/// A model's rest stiffness and node masses.
#[derive(Debug, Clone)]
pub struct ModalModel {
    /// The grid.
    pub grid: Grid,
    pub(crate) stiffness: GroupedStiffness,
    pub(crate) theta: Vec<f64>,
    /// Mass of each node, kg.
    pub node_masses: Vec<f64>,
}

impl ModalModel {
    /// The rest stiffness, by groups.
    pub fn stiffness(&self) -> &GroupedStiffness {
        &self.stiffness
    }

    /// The groups' stiffness values (what [`ModalModel::stiffness`] scales).
    pub fn theta(&self) -> &[f64] {
        &self.theta
    }
}

/// Why a model has no modes to speak of.
pub const AXIS_HAS_NO_MODES: &str = "the paper's axis-spring lattice has no shear stiffness at rest, so no \
     fundamental to set a damping ratio at: it keeps the paper's nodal damping d";

impl ModalModel {
    /// A spring lattice (its masses as [`MsmModel::masses`]); the axis lattice is refused.
    pub fn lattice(model: &MsmModel) -> Result<Self, String> {
        lattice_topology_ok(model.params)?;
        Ok(Self {
            grid: model.grid,
            stiffness: GroupedStiffness::lattice_in(model.grid, model.params.topology(), model.inclusions.as_ref()),
            theta: group_values(&model.params).to_vec(),
            node_masses: model.masses.clone(),
        })
    }

    /// The hex8 FEM with lumped masses of `density`.
    pub fn fem(model: &FemModel, density: f64) -> Self {
        Self {
            grid: model.grid,
            stiffness: GroupedStiffness::fem(model),
            theta: vec![1.0],
            node_masses: crate::mechanics::msm::model::lumped_masses(&model.grid, density),
        }
    }

    /// Masses per dof, zero on the dofs `fixed`.
    pub fn dof_masses(&self, fixed: &[bool]) -> Vec<f64> {
        fixed.iter().enumerate().map(|(d, &f)| if f { 0.0 } else { self.node_masses[d / 3] }).collect()
    }

    /// The stiffness with `fixed` held, factorised.
    pub fn solver(&self, fixed: &[bool]) -> Result<SceneSolver, SparseError> {
        let mut s = SceneSolver::with_fixed(&self.grid, &self.stiffness, fixed.to_vec())?;
        s.factor(&self.stiffness, &self.theta)?;
        Ok(s)
    }

    /// The lowest `count` modes with `fixed` held.
    pub fn modes(&self, fixed: &[bool], count: usize) -> Result<Vec<Mode>, SparseError> {
        let mut solver = self.solver(fixed)?;
        crate::response::modes::lowest_modes(&mut solver, &self.dof_masses(fixed), count)
    }

    /// The fundamental with `fixed` held.
    pub fn fundamental(&self, fixed: &[bool]) -> Result<Mode, SparseError> {
        self.modes(fixed, 1)?.into_iter().next().ok_or(SparseError::NotPositiveDefinite)
    }

    /// The static shape `K u = f` of `case` (its clamp and loads), all dofs.
    pub fn static_shape(&self, case: &LoadCase) -> Result<Vec<f64>, SparseError> {
        let mut u = case.load.clone();
        self.solver(&case.fixed)?.solve(&mut u)?;
        Ok(u)
    }
}

/// The fundamental of the viewer's scene (face z = 0 clamped), rad/s.
pub fn scene_fundamental(model: &ModalModel) -> Result<f64, String> {
    let fixed = crate::response::linear::scene_fixed_dofs(&model.grid);
    model.fundamental(&fixed).map(|m| m.omega).map_err(|e| format!("the fundamental: {e}"))
}

fn lattice_topology_ok(params: MsmParams) -> Result<(), String> {
    if params.topology() == Topology::Axis { Err(AXIS_HAS_NO_MODES.to_owned()) } else { Ok(()) }
}
