//! The recording as a `simulate` script: what the physics thread recorded, with what the state
//! knows of the scene (the object, the model, the grid, the clamp, where steps are computed).

use super::ViewerState;
use crate::app::recording::Recording;
use crate::mechanics::object::Object;
use crate::sim::Model;
use crate::study::script::{Recorded, Script};

impl ViewerState {
    /// The script that replays `rec` on the scene shown; refused for a material a script cannot
    /// name.
    pub fn recording_script(&self, rec: Recording) -> anyhow::Result<Script> {
        let m = &self.shown.material;
        let object = Object::ALL
            .into_iter()
            .find(|o| {
                let p = o.material();
                p.name == m.name && p.stiffness == m.stiffness && p.density == m.density
            })
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "the material \"{}\" is not one of the paper's objects, and a script names A or B",
                    m.name
                )
            })?;
        let model = self.shown.model();
        let mut notes: Vec<String> = rec.note.into_iter().collect();
        if let Model::Lattice(t) = model
            && crate::sim::shipped::msm_params_at(m, t, &self.grid).ok() != Some(self.shown.params)
        {
            notes.push(
                "the lattice's parameters were edited or calibrated in the viewer; the script runs its shipped \
                 tissue"
                    .into(),
            );
        }
        Ok(Script {
            object,
            model,
            dt: rec.dt,
            integrator: Some(rec.integrator),
            damping_ratio: rec.damping_ratio.filter(|_| model.takes_damping_ratio()),
            clamp: self.shown.case_active.as_ref().map_or_else(|| "bottom".into(), |c| c.id.clone()),
            nodes: self.grid.n(),
            contact: rec.contact,
            compute: self.settings.compute,
            actions: rec.actions,
            recorded: Some(Recorded {
                force_path: rec.force_path,
                note: (!notes.is_empty()).then(|| notes.join("; ")),
            }),
        })
    }
}
