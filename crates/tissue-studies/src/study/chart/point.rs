//! One point of the speed-against-accuracy chart: a model, resolution, integrator and step, with
//! its cost and its errors; the models charted.

use crate::mechanics::fem::dynamics::Formulation;
use crate::mechanics::msm::Topology;
use crate::sim::{Integrator, Model};
pub use crate::study::names::integrator_chart_name;

/// The models charted: every one but the paper's axis lattice, whose only calibration is on the
/// paper's cases (the chart's static cases) and which the touch benchmark cannot score (no shear
/// stiffness at rest), so no held-out figure exists for it.
pub const CHARTED: [Model; 4] = [
    Model::Lattice(Topology::Shear),
    Model::Lattice(Topology::Hex),
    Model::Fem(Formulation::Linear),
    Model::Fem(Formulation::Corotational),
];

/// One point of the chart.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChartPoint {
    /// The object.
    pub object: crate::mechanics::object::Object,
    /// The model (`msm-axis`, ..., `fem-corotational` in files).
    #[serde(
        serialize_with = "crate::study::names::serialize_model",
        deserialize_with = "crate::study::names::deserialize_model"
    )]
    pub model: Model,
    /// Nodes per axis.
    pub n: usize,
    /// Symplectic Euler (`explicit` in files) or prefactored backward Euler (`implicit`).
    #[serde(
        serialize_with = "crate::study::names::serialize_integrator",
        deserialize_with = "crate::study::names::deserialize_integrator"
    )]
    pub integrator: Integrator,
    /// Wall time of one step, s.
    pub step_s: f64,
    /// Largest stable explicit step (`damped_explicit_limit` of `omega_max` and the damping rate), s;
    /// infinite for implicit.
    pub dt_max_s: f64,
    /// The time step of the point, s: 0.9 of `dt_max_s` (explicit), one of
    /// [`IMPLICIT_STEPS_S`] (implicit) or of [`NEWMARK_STEPS_S`] (newmark).
    pub dt_s: f64,
    /// Wall time per simulated second, `step_s / dt_s`, s.
    pub cost_per_sim_s: f64,
    /// Wall time of the static answer of one case, s.
    pub static_s: f64,
    /// Bytes held by state, model and factor.
    pub memory_bytes: usize,
    /// Average nodal error, % of the paper's h.
    pub avg_err_pct: f64,
    /// Maximum nodal error, % of the paper's h.
    pub max_err_pct: f64,
    /// Worst touch force error on the touch benchmark's validation set, percent, against the
    /// FEM on the same mesh (0 for the FEM itself). Scored at the viewer's resolution (the
    /// paper's 8^3 grid, the scene a user touches) only; NaN at other resolutions, where a point
    /// load's answer depends on the mesh and no common touch reference exists.
    pub force_err_pct: f64,
    /// Worst probe force error against the material (the converged continuum,
    /// [`crate::validate::continuum`]) on the validation presses, percent, with the model's own
    /// surface-node contact at this resolution; NaN where the model has no small-displacement
    /// answer (the axis lattice). At every resolution: the reference does not depend on the mesh.
    #[serde(default = "not_scored")]
    pub probe_err_pct: f64,
    /// The same with the material's surface compliance as the probe's contact
    /// ([`crate::sim::material_surface`]), whatever the model: one figure per object.
    #[serde(default = "not_scored")]
    pub surface_probe_err_pct: f64,
    /// Wall time the surface compliance adds to a 1 ms tick with the probe sliding (one contact
    /// solve per tick), s.
    #[serde(default = "not_scored")]
    pub surface_probe_tick_s: f64,
    /// Dynamic error: the worst trajectory error against the FEM's converged transients (the
    /// viewer scene's top-face step load and its release, first 0.2 s), percent; model and
    /// integrator together. At the viewer's 8^3 only (NaN elsewhere), as the touch scores.
    pub dyn_err_pct: f64,
    /// The probe tap's force error (run in the viewer's simulation, its contact and readout)
    /// against the FEM's converged tap, percent (8^3 only).
    pub tap_err_pct: f64,
    /// The integrator's period error on the model's own fundamental, measured by time stepping,
    /// percent (8^3 only).
    pub period_err_pct: f64,
    /// The integrator's damping ratio error on the model's own fundamental, percent of critical
    /// (8^3 only).
    pub damping_err_pct: f64,
    /// On the Pareto front of (cost per simulated second, average static error) for its object.
    pub pareto: bool,
    /// On the Pareto front of (cost per simulated second, dynamic error) for its object.
    pub pareto_dynamic: bool,
}

/// An error that was not measured (older chart files have no probe columns).
fn not_scored() -> f64 {
    f64::NAN
}

/// The steps of the implicit points, s: from 0.1 ms to one frame at 60 Hz.
pub const IMPLICIT_STEPS_S: [f64; 6] = [1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 1.0 / 60.0];
/// The steps of the Newmark points, s: the viewer's 1 ms tick.
pub const NEWMARK_STEPS_S: [f64; 1] = [1e-3];
/// The damping ratio of every chart point (mass-proportional at each model's fundamental).
pub const CHART_DAMPING_RATIO: f64 = crate::response::damping::DEFAULT_DAMPING_RATIO;

impl ChartPoint {
    /// Wall time to advance `1 / rate_hz` of simulated time: as many steps of `dt_s` as the
    /// tick needs (at least one).
    pub fn tick_s(&self, rate_hz: f64) -> f64 {
        self.substeps(rate_hz) * self.step_s
    }

    /// Steps of `dt_s` per tick at `rate_hz`.
    pub fn substeps(&self, rate_hz: f64) -> f64 {
        (1.0 / rate_hz / self.dt_s * (1.0 - 1e-9)).ceil().max(1.0)
    }

    /// Whether its step fits in a tick at `rate_hz` (an implicit step longer than the tick
    /// cannot run at that rate).
    pub fn fits_rate(&self, rate_hz: f64) -> bool {
        self.dt_s <= 1.0 / rate_hz * (1.0 + 1e-9)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn model_and_integrator_names_round_trip() {
        for kind in Model::ALL {
            assert_eq!(Model::from_chart_name(&kind.chart_name()), Some(kind));
            assert_eq!(format!("{}", kind.chart_name()), kind.chart_name());
        }
        assert_eq!(Model::from_chart_name("msm-other"), None);
        assert_eq!(format!("{:<9}|", integrator_chart_name(Integrator::Symplectic)), "explicit |");
    }
}
