//! The mass-spring lattices as a [`Tissue`].

use super::explicit_form::{ExplicitForm, FamilyForm, ForceForm};
use super::integrator::Integrator;
use super::tissue::Tissue;
use crate::mechanics::cases::LoadCase;
use crate::mechanics::grid::Grid;
use crate::mechanics::msm::{Dynamics, MsmModel, MsmParams};
use crate::response::damping::Damping;
use crate::response::single_mode::damped_explicit_limit;
use glam::DVec3;

/// The mass-proportional damping of `zeta` for `model` (a lattice), and the rate applied; its
/// fundamental is solved unless `known` (the same model's).
fn lattice_ratio_damping(model: &mut MsmModel, zeta: f64, known: Option<f64>) -> Result<Damping, String> {
    let zeta = crate::response::damping::check_ratio(zeta)?;
    let omega_1 = match known {
        Some(w) => w,
        None => crate::response::modal::scene_fundamental(&crate::response::modal::ModalModel::lattice(model)?)?,
    };
    let damping = Damping::Ratio { zeta, omega_1 };
    model.set_mass_damping(damping.rate());
    Ok(damping)
}

/// A mass-spring lattice as a [`Tissue`].
#[derive(Debug)]
pub struct MsmTissue {
    /// The model.
    pub model: MsmModel,
    /// Its state.
    pub dynamics: Dynamics,
    density: f64,
    dt_limit: f64,
    /// The ratio asked for (kept across parameters; the axis lattice uses its nodal `d`).
    ratio: Option<f64>,
    damping: Damping,
    /// The nodes' masses summed, kg (the blow-up guard asks every step).
    total_mass: f64,
}

impl MsmTissue {
    /// `model` at rest (built for `density`, kg/m^3), damped by the parameters' nodal `d`.
    pub fn new(model: MsmModel, density: f64) -> Self {
        let dynamics = Dynamics::new(&model);
        let dt_limit = explicit_dt_limit(&model);
        let damping = Damping::Nodal(model.params.d);
        let total_mass = model.masses.iter().sum();
        Self { model, dynamics, density, dt_limit, ratio: None, damping, total_mass }
    }

    /// The lattice of `params` on the paper's grid for a material of `density`.
    pub fn build(params: MsmParams, density: f64) -> Result<Self, crate::mechanics::msm::ParamError> {
        Ok(Self::new(MsmModel::new(Grid::paper(), params, density)?, density))
    }
}

impl Tissue for MsmTissue {
    fn explicit_form(&self) -> Result<ExplicitForm, String> {
        let model = &self.model;
        let h = model.grid.h();
        let force = ForceForm::Springs(
            model
                .families
                .iter()
                .map(|f| FamilyForm {
                    offset: f.offset,
                    rest: f.family.offset.map(|o| f64::from(o) * h),
                    rest_length: f.rest_length,
                    stiffness: f.stiffness.clone(),
                })
                .collect(),
        );
        Ok(ExplicitForm {
            grid: model.grid,
            force,
            inv_mass: model.masses.iter().map(|m| 1.0 / m).collect(),
            damping_rate: model.damping.iter().zip(&model.masses).map(|(c, m)| c / m).collect(),
            free: std::array::from_fn(|_| self.dynamics.free.clone()),
        })
    }
    fn modal(&self) -> Result<crate::response::modal::ModalModel, String> {
        crate::response::modal::ModalModel::lattice(&self.model)
    }
    fn newton_solves(&self) -> Option<crate::mechanics::newton_krylov::NewtonSolves> {
        self.dynamics.newton_solves()
    }
    fn set_anchor(&mut self, anchor: Option<crate::mechanics::anchor::Anchor>) -> bool {
        self.dynamics.anchor = anchor;
        true
    }
    fn grid(&self) -> Grid {
        self.model.grid
    }
    fn total_mass(&self) -> f64 {
        self.total_mass
    }
    fn node_mass(&self, p: usize) -> f64 {
        self.model.masses[p]
    }
    fn x(&self) -> &[Vec<f64>; 3] {
        &self.dynamics.x
    }
    fn x_mut(&mut self) -> &mut [Vec<f64>; 3] {
        &mut self.dynamics.x
    }
    fn v(&self) -> &[Vec<f64>; 3] {
        &self.dynamics.v
    }
    fn v_mut(&mut self) -> &mut [Vec<f64>; 3] {
        &mut self.dynamics.v
    }
    fn x_v_mut(&mut self) -> (&mut [Vec<f64>; 3], &mut [Vec<f64>; 3]) {
        (&mut self.dynamics.x, &mut self.dynamics.v)
    }
    fn f_ext_mut(&mut self) -> &mut [Vec<f64>; 3] {
        &mut self.dynamics.f_ext
    }
    fn free(&self) -> &[f64] {
        &self.dynamics.free
    }
    fn forces(&mut self) -> &[Vec<f64>; 3] {
        self.dynamics.forces(&self.model)
    }
    fn step(&mut self, integrator: Integrator, dt: f64) -> Result<(), String> {
        match integrator {
            Integrator::Symplectic => {
                self.dynamics.step_symplectic(&self.model, dt);
                Ok(())
            }
            Integrator::Implicit => self.dynamics.step_implicit(&self.model, dt).map_err(|e| e.to_string()),
            Integrator::Prefactored => self.dynamics.step_prefactored(&self.model, dt).map_err(|e| e.to_string()),
            Integrator::Newmark => self.dynamics.step_newmark(&self.model, dt).map_err(|e| e.to_string()),
        }
    }
    fn kinetic_energy(&self) -> f64 {
        self.dynamics.kinetic_energy(&self.model)
    }
    fn set_single_precision(&mut self, single: bool) -> Result<(), String> {
        self.dynamics.set_single_precision(&self.model, single);
        Ok(())
    }
    fn carries_contact_loads(&self) -> bool {
        self.model.params.topology() != crate::mechanics::msm::Topology::Axis
    }
    fn explicit_dt_limit(&self) -> f64 {
        self.dt_limit
    }
    fn apply_case(&mut self, case: &LoadCase) {
        self.dynamics.apply_case(case);
    }
    fn params(&self) -> Option<MsmParams> {
        Some(self.model.params)
    }
    fn set_params(&mut self, params: MsmParams) -> Result<(), String> {
        let mut model = self.model.with_params(params, self.density).map_err(|e| e.to_string())?;
        // The paper's axis lattice has no fundamental to set a ratio at: its nodal `d`.
        let damping = match self.ratio {
            Some(zeta) if params.topology() != crate::mechanics::msm::Topology::Axis => {
                lattice_ratio_damping(&mut model, zeta, None)?
            }
            _ => Damping::Nodal(params.d),
        };
        self.model = model;
        self.damping = damping;
        self.dynamics.set_model(&self.model);
        self.dt_limit = explicit_dt_limit(&self.model);
        self.total_mass = self.model.masses.iter().sum();
        Ok(())
    }
    fn set_damping_ratio(&mut self, zeta: f64) -> Result<(), String> {
        // The parameters are unchanged: the fundamental already solved is the model's.
        self.damping = lattice_ratio_damping(&mut self.model, zeta, self.damping.omega_1())?;
        self.ratio = Some(zeta);
        self.dynamics.set_model(&self.model);
        self.dt_limit = explicit_dt_limit(&self.model);
        Ok(())
    }
    fn damping(&self) -> Damping {
        self.damping
    }
}

/// The critical time step of symplectic Euler for a lattice on its rest stiffness: `omega_max^2`
/// the Lanczos upper estimate with no node held ([`crate::response::stiffest_mode`]; holding
/// nodes only lowers it), capped by Gershgorin's bound `max_i sum_j |K_ij| / m` (`m` each node's
/// mass), and the largest nodal damping rate `c_p / m_p` treated explicitly
/// ([`damped_explicit_limit`]).
pub fn explicit_dt_limit(model: &MsmModel) -> f64 {
    use crate::response::stiffest_mode::{LIMIT_ITERATIONS, LIMIT_TOLERANCE, lattice};
    let held = vec![false; model.grid.num_nodes()];
    let estimate = lattice(model, &held, LIMIT_TOLERANCE, LIMIT_ITERATIONS).upper();
    let gamma = model.masses.iter().zip(&model.damping).map(|(m, c)| c / m).fold(0.0, f64::max);
    damped_explicit_limit(estimate.min(gershgorin(model)).sqrt(), gamma)
}

/// Gershgorin's bound `omega_max^2 <= max_i sum_j |K_ij| / m` on a lattice's rest stiffness.
fn gershgorin(model: &MsmModel) -> f64 {
    let mut row = vec![0.0f64; model.grid.num_nodes()];
    for s in model.springs() {
        let k = model.families[s.family].stiffness[s.a];
        let d = model.families[s.family].family.offset.map(|o| f64::from(o.abs()));
        let len = DVec3::from(d).length();
        // Row sums of k d d^T (and its off-diagonal copy) for the worst component.
        let w = (0..3).map(|c| d[c] / len * (d[0] + d[1] + d[2]) / len).fold(0.0, f64::max);
        row[s.a] += 2.0 * k * w;
        row[s.b] += 2.0 * k * w;
    }
    row.iter().zip(&model.masses).map(|(r, m)| r / m).fold(0.0, f64::max)
}
