//! Which model runs: another object or material file, and another resolution.

use super::ViewerState;
use crate::app::physics::Command;
use crate::app::settings::Source;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::msm::Topology;

impl ViewerState {
    pub(super) fn load_object(&mut self, topology: Topology, send: &mut dyn FnMut(Command)) {
        self.shown.note = None;
        let (material, file) = match self.settings.object {
            Source::File => {
                let path = std::path::PathBuf::from(self.settings.material_path.trim());
                match Material::from_file(&path) {
                    Ok(m) => (m, Some(path)),
                    Err(e) => {
                        self.shown.note = Some(format!("{e:#}"));
                        return;
                    }
                }
            }
            Source::Object(object) => (object.material(), None),
        };
        // The shown material is the background (its calibrated tissue); the model steps the
        // inclusions too ([`crate::app::settings::Shown::modelled_material`]).
        let inclusions = material.inclusions.clone();
        let material = material.background();
        let params = crate::sim::shipped::msm_params_at(&material, topology, &self.grid).unwrap_or_else(|_| {
            // No shipped calibration: start from the material-derived scale and suggest calibrating.
            let space = crate::calibrate::GeneSpace::new(&material, &self.grid, topology);
            let mid: Vec<f64> = space.lo.iter().zip(&space.hi).map(|(l, h)| (l * h).sqrt()).collect();
            self.shown.note = Some(format!(
                "{}: no calibrated tissue shipped; using the material's scale k* — press Calibrate",
                material.name
            ));
            space.params(&mid)
        });
        self.shown.inclusions = inclusions;
        self.shown.material = material;
        self.shown.material_file = file;
        self.shown.exercise = None;
        self.shown.params = params;
        self.shown.case_active = None;
        self.shown.fem_answer = None;
        self.shown.comparison = None;
        self.start_validation();
        send(Command::SetSurfaceProbe(None));
        send(Command::Replace(self.replacement()));
        self.start_compliance();
    }

    /// The model on a grid of `n` nodes per edge: a lattice's shipped tissue carried over by its
    /// stiffness scale ([`crate::sim::shipped::msm_params_at`]; edited or calibrated parameters
    /// are not), the scene back to the bottom clamp.
    pub(super) fn set_resolution(&mut self, n: usize, send: &mut dyn FnMut(Command)) {
        let grid = match Grid::new(n) {
            Ok(g) if g != self.grid => g,
            Ok(_) => return,
            Err(e) => {
                self.shown.note = Some(e.to_string());
                return;
            }
        };
        if self.shown.fem.is_none() {
            match crate::sim::shipped::msm_params_at(&self.shown.material, self.shown.topology(), &grid) {
                Ok(p) => self.shown.params = p,
                Err(e) => {
                    self.shown.note = Some(format!("{e:#}"));
                    return;
                }
            }
        }
        self.grid = grid;
        self.forget_map();
        self.shown.case_active = None;
        self.shown.fem_answer = None;
        self.shown.comparison = None;
        self.shown.note = Some(format!(
            "{n}^3 nodes ({:.1} mm apart); a lattice carries its shipped tissue over by its stiffness scale",
            1e3 * grid.h()
        ));
        self.start_validation();
        send(Command::Replace(self.replacement()));
    }
}
