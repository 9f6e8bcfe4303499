//! Find the lump in the viewer's state: a lump hidden in the probe's material (its surface
//! compliance computed again in the background, the probe feeling the last material meanwhile),
//! marked where the probe last pressed, then revealed.

use super::ViewerState;
use crate::app::exercise::{Exercise, hide};
use crate::mechanics::grid::CUBE_SIDE_M;

impl ViewerState {
    /// Hides a new lump under the top face, drawn from the settings' ranges and seed (the next
    /// seed is one more).
    pub(super) fn hide_inclusion(&mut self) {
        match hide(
            &self.shown.material,
            &self.shown.inclusions,
            &self.settings.inclusion_ranges,
            self.settings.inclusion_seed,
        ) {
            Ok(lump) => {
                self.shown.exercise = Some(Exercise { lump, ready: None, mark: None, felt: None });
                self.settings.inclusion_seed = self.settings.inclusion_seed.wrapping_add(1);
                self.start_compliance();
            }
            Err(why) => self.shown.note = Some(why),
        }
    }

    /// Marks the hidden lump under the probe's last press (its centre's point on the top face),
    /// once the probe feels it; the panel then reveals it.
    pub(super) fn mark_inclusion(&mut self) {
        let Some(e) = self.shown.exercise.as_mut() else { return };
        let (Some(ready), None) = (e.ready, e.mark) else { return };
        match self.shown.last_probe {
            Some((centre, _)) => {
                let on_face = [centre[0].clamp(0.0, CUBE_SIDE_M), centre[1].clamp(0.0, CUBE_SIDE_M)];
                e.mark = Some((on_face, ready.elapsed()));
            }
            None => {
                self.shown.note = Some("press the top face with the probe where you feel the lump, then mark".into())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::app::physics::Command;
    use crate::app::state::{Request, ViewerState};

    #[test]
    fn a_hidden_lump_is_felt_marked_and_ended() {
        let (mut state, _) = ViewerState::new(|| {}).expect("the viewer state");
        let mut sent = Vec::new();
        state.handle(Request::HideLump, &mut |c| sent.push(c));
        let e = state.shown.exercise.clone().expect("a lump hidden");
        assert_eq!((e.lump.seed, state.settings.inclusion_seed), (1, 2));
        assert_eq!(state.shown.felt_material().inclusions, vec![e.lump.inclusion.clone()]);
        assert!(state.shown.modelled_material().inclusions.is_empty(), "the model does not show the hidden lump");
        // Not yet felt: no mark.
        state.handle(Request::MarkLump, &mut |c| sent.push(c));
        assert!(state.shown.exercise.as_ref().is_some_and(|e| e.mark.is_none()));
        state.shown.exercise.as_mut().expect("under way").ready = Some(std::time::Instant::now());
        state.shown.last_probe = Some(([0.04, 0.06, 0.11], 0.015));
        state.handle(Request::MarkLump, &mut |c| sent.push(c));
        let e = state.shown.exercise.clone().expect("under way");
        assert_eq!(e.mark.map(|m| m.0), Some([0.04, 0.06]));
        assert!(e.miss().is_some());
        state.handle(Request::EndExercise, &mut |c| sent.push(c));
        assert!(state.shown.exercise.is_none() && state.shown.felt_material().inclusions.is_empty());
        assert!(!sent.iter().any(|c| matches!(c, Command::SetSurfaceProbe(None))), "the probe keeps its contact");
    }

    #[test]
    fn a_material_file_with_a_lump_runs_its_backgrounds_tissue_and_steps_and_feels_the_lump() {
        let (mut state, _) = ViewerState::new(|| {}).expect("the viewer state");
        state.settings.object = crate::app::settings::Source::File;
        state.settings.material_path =
            concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/examples/lump_5x_r8.toml").into();
        state.handle(Request::LoadObject, &mut |_| {});
        // Its background is A's tissue: the shipped lattice runs, with nothing to say.
        assert_eq!(state.shown.note, None);
        let a = crate::mechanics::material::Material::object_a();
        assert_eq!(state.shown.params, crate::sim::shipped::default_params(&a).expect("A's tissue"));
        assert!(state.shown.material.inclusions.is_empty());
        assert_eq!(state.shown.inclusions.len(), 1);
        assert_eq!(state.shown.felt_material().inclusions.len(), 1);
        assert_eq!(state.shown.modelled_material().inclusions.len(), 1);
        assert_eq!(state.shown.material.stiffness, crate::mechanics::material::Material::object_a().stiffness);
    }
}
