//! The recording as a `simulate` script: what the physics thread recorded, with what the state
//! knows of the scene (the object, the model, the grid, the clamp, where steps are computed).

use anyhow::Context as _;

use super::ViewerState;
use crate::app::recording::Recording;
use crate::mechanics::object::Object;
use crate::sim::Model;
use crate::study::script::{Recorded, Script};

impl ViewerState {
    /// The script that replays `rec` on the scene shown (the material by its object, or by its
    /// file's absolute path).
    pub fn recording_script(&self, rec: Recording) -> anyhow::Result<Script> {
        let m = &self.shown.material;
        let (object, material) = match &self.shown.material_file {
            // The file it was read from, wherever the script is written.
            Some(file) => (None, Some(std::path::absolute(file).context("the material file's path")?)),
            None => {
                let object = Object::ALL.into_iter().find(|o| {
                    let p = o.material();
                    p.name == m.name && p.stiffness == m.stiffness && p.density == m.density
                });
                (Some(object.context("the running material is neither a paper's object nor a file")?), None)
            }
        };
        let model = self.shown.model();
        let mut notes: Vec<String> = rec.note.into_iter().collect();
        if let Model::Lattice(t) = model {
            match crate::sim::shipped::msm_params_at(m, t, &self.grid) {
                Ok(p) if p == self.shown.params => {}
                Ok(_) => notes.push(
                    "the lattice's parameters were edited or calibrated in the viewer; the script runs its shipped \
                     tissue"
                        .into(),
                ),
                Err(_) => notes.push(format!(
                    "no calibrated lattice is shipped for {}: the replay refuses the lattice (record the FEM)",
                    m.name
                )),
            }
        }
        if self.shown.exercise.is_some() {
            notes.push(
                "the lump hidden to find is not in the script: the replay presses the material without it".into(),
            );
        }
        Ok(Script {
            object,
            material,
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
