//! Panel section "Find the lump": hide a seeded random lump under the top face, palpate with the
//! probe, mark it where the probe last pressed, and see how near the mark was, how much the probe
//! could feel of it and how long it took.

use crate::app::exercise::{CLINICAL, FELT_DEPTH_M, LIMITS, Ranges};
use crate::app::state::{Request, Shown, ViewSettings};

/// Draws the section.
pub fn show(ui: &mut egui::Ui, settings: &mut ViewSettings, shown: &Shown, requests: &mut Vec<Request>) {
    if !shown.inclusions.is_empty() {
        ui.label(format!(
            "The probe feels the material file's {} inclusion(s); the model shown takes them too.",
            shown.inclusions.len()
        ));
    }
    map_row(ui, settings, shown, requests);
    let Some(e) = &shown.exercise else {
        ui.label("A lump is hidden under the top face, drawn from these ranges:");
        let r = &mut settings.inclusion_ranges;
        range(ui, "radius (mm)", &mut r.radius_mm, LIMITS.radius_mm, 0.5);
        range(ui, "top under the face (mm)", &mut r.depth_mm, LIMITS.depth_mm, 0.5);
        range(ui, "stiffness (x the tissue)", &mut r.contrast, LIMITS.contrast, 0.1);
        presets(ui, r);
        ui.horizontal(|ui| {
            ui.label("seed");
            ui.add(egui::DragValue::new(&mut settings.inclusion_seed));
            if ui.button("Hide a lump").clicked() {
                requests.push(Request::HideLump);
            }
        });
        return;
    };
    match (e.ready, e.mark) {
        (None, _) => {
            ui.label("Hiding the lump: the probe feels the tissue as before until it is in (see the probe's contact).");
        }
        (Some(ready), None) => {
            ui.label(format!(
                "A lump is hidden under the top face ({:.0} s). Palpate with the probe (key p), then mark it where \
                 the probe last pressed.",
                ready.elapsed().as_secs_f64()
            ));
            if ui.button("Mark it here").clicked() {
                requests.push(Request::MarkLump);
            }
        }
        (Some(_), Some((mark, took))) => {
            let lump = &e.lump;
            let c = lump.inclusion.centre;
            ui.label(format!(
                "The lump: centre ({:.1}, {:.1}) mm on the face, {:.1} mm in radius, its top {:.1} mm deep, {:.1} times \
                 as stiff (seed {}).",
                c[0] * 1e3,
                c[1] * 1e3,
                lump.inclusion.radius * 1e3,
                lump.depth_m * 1e3,
                lump.contrast,
                lump.seed
            ));
            ui.label(format!(
                "Your mark ({:.1}, {:.1}) mm: {:.1} mm from its centre, after {:.0} s.",
                mark[0] * 1e3,
                mark[1] * 1e3,
                e.miss().unwrap_or(f64::NAN) * 1e3,
                took.as_secs_f64()
            ));
            if let (Some(contrast), Some([with, without])) = (e.contrast_felt(), e.felt) {
                ui.label(format!(
                    "Pressed {:.0} mm over its centre the probe feels {with:.2} N against {without:.2} N without it: \
                     {:+.1} % ({}).",
                    FELT_DEPTH_M * 1e3,
                    100.0 * contrast,
                    if contrast.abs() > crate::study::palpate::FELT_CONTRAST {
                        "a hand tells 7 % apart"
                    } else {
                        "below the 7 % a hand tells apart"
                    }
                ));
            }
        }
    }
    ui.horizontal(|ui| {
        if e.ready.is_some() && ui.button("Hide another").clicked() {
            requests.push(Request::HideLump);
        }
        if ui.button("End").clicked() {
            requests.push(Request::EndExercise);
        }
    });
}

/// Two values `[low, high]` within `limits`, the low at most the high.
fn range(ui: &mut egui::Ui, label: &str, value: &mut [f64; 2], limits: [f64; 2], speed: f64) {
    ui.horizontal(|ui| {
        ui.label(label);
        let [low, high] = *value;
        ui.add(egui::DragValue::new(&mut value[0]).range(limits[0]..=high).speed(speed));
        ui.label("to");
        ui.add(egui::DragValue::new(&mut value[1]).range(low..=limits[1]).speed(speed));
    });
}

/// The palpation map of the face last pressed: compute it, show it or not, what it found.
fn map_row(ui: &mut egui::Ui, settings: &mut ViewSettings, shown: &Shown, requests: &mut Vec<Request>) {
    let hidden = shown.exercise.as_ref().is_some_and(|e| e.mark.is_none());
    ui.horizontal_wrapped(|ui| {
        let map = ui
            .add_enabled(!hidden, egui::Button::new("Map the face"))
            .on_hover_text(
                "The probe (its radius now) pressed 4 mm at 21 x 21 points of the face it last pressed (the top face \
                 before any press): its force as the face's colours (tissue-sim palpate's map)",
            )
            .on_disabled_hover_text("it would show the hidden lump: mark it first");
        if map.clicked() {
            requests.push(Request::MapFace);
        }
        if hidden {
            ui.weak("(after you mark the lump: the map would show where it is)");
        }
        ui.checkbox(&mut settings.show_map, "show the map");
        ui.checkbox(&mut settings.map_contrast, "as contrast");
    });
    match &shown.face_map {
        Some(Ok(m)) => {
            let [low, high] = m.range;
            let mut line = format!("map of the {} face: {low:.2} to {high:.2} N", m.map.face);
            if let Some((peak, at)) = m.map.peak().filter(|_| !m.map.inclusions.is_empty()) {
                line.push_str(&format!(
                    "; largest contrast against the tissue without its inclusions {:+.1} % at ({:.0}, {:.0}, {:.0}) mm, \
                     beyond 7 % at {} of {} points",
                    100.0 * peak,
                    at[0] * 1e3,
                    at[1] * 1e3,
                    at[2] * 1e3,
                    m.map.felt(),
                    m.map.points.len()
                ));
            }
            ui.label(line);
        }
        Some(Err(why)) => {
            ui.label(format!("map: {why}"));
        }
        None => {}
    }
}

/// The two presets of the ranges: lumps a hand feels (the default) and the clinical ones.
fn presets(ui: &mut egui::Ui, r: &mut Ranges) {
    ui.horizontal(|ui| {
        if ui
            .selectable_label(*r == Ranges::default(), "felt (default)")
            .on_hover_text("lumps a hand feels: the weakest raises the probe's force over it by 11 %")
            .clicked()
        {
            *r = Ranges::default();
        }
        if ui
            .selectable_label(*r == CLINICAL, "clinical (harder)")
            .on_hover_text("5 to 10 mm, 5 to 20 mm deep, 2 to 10 times: many below the 7 % a hand tells apart")
            .clicked()
        {
            *r = CLINICAL;
        }
    });
}
