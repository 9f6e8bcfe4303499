//! Panel section "Tools": the mouse tool, the probe's size, the force on the tool, the
//! force-depth plot, and the paper's load cases with the live error against their FEM answer.

use egui_plot::{Line, PlotPoints};
use glam::DVec3;

use super::PanelContext;
use crate::app::overlay::error_vs_fem;
use crate::app::state::{Request, Shown, ToolKind, ViewSettings};
use crate::mechanics::cases::FORCES_N;
use crate::sim::Tool;

/// With `view --record`: the button that writes the recording now (at the top, beside the tools).
pub fn recording(ui: &mut egui::Ui, settings: &ViewSettings, requests: &mut Vec<Request>) {
    let Some(path) = &settings.recording else { return };
    ui.horizontal_wrapped(|ui| {
        let save = ui.button("Save recording").on_hover_text(
            "Write what was done so far as a simulate script that replays it (also written when the viewer closes)",
        );
        if save.clicked() {
            requests.push(Request::SaveRecording);
        }
        ui.label(format!("to {}", path.display()));
    });
}

/// Draws the section.
pub fn show(
    ui: &mut egui::Ui,
    settings: &mut ViewSettings,
    shown: &Shown,
    ctx: &PanelContext<'_>,
    requests: &mut Vec<Request>,
) {
    ui.label("Left mouse: the tool; right mouse: rotate; wheel: zoom.");
    if settings.tool == ToolKind::Probe {
        probe_settings(ui, settings);
    }
    let f = ctx.published.tool_force;
    let norm = DVec3::from(f).length();
    if settings.tool == ToolKind::Probe {
        // The number beside the sphere, said once.
        match ctx.published.probe {
            Some((_, r)) => {
                ui.label(format!("probe force {:.2} N at {:.1} mm indentation", r.force_n, r.depth_m * 1e3))
            }
            None => ui.label(format!("probe force {norm:.2} N")),
        };
        ui.label(contact_line(shown, ctx));
    } else {
        ui.label(format!("force on tool: |F| = {norm:.4} N  ({:.4}, {:.4}, {:.4})", f[0], f[1], f[2]));
    }
    if let Tool::Drag { .. } = shown.tool {
        ui.label(format!(
            "red arrow: the force on the tissue, {:.0} mm per newton",
            crate::app::overlay::ARROW_M_PER_N * 1e3
        ));
    }
    if settings.tool == ToolKind::Probe && shown.last_reading.is_some() {
        comparison(ui, shown, requests);
    }
    if settings.tool == ToolKind::Probe {
        force_depth_plot(ui, shown, ctx);
    }
    ui.separator();
    ui.label("Paper's load case (clamped face, force on the opposite face):");
    ui.horizontal(|ui| {
        for a in 1..=3 {
            ui.selectable_value(&mut settings.case_axis, a, format!("axis {a}"));
        }
    });
    ui.horizontal(|ui| {
        for f in FORCES_N {
            ui.selectable_value(&mut settings.case_force, f, format!("{f} N"));
        }
    });
    ui.horizontal(|ui| {
        if ui.button("Apply case").clicked() {
            requests.push(Request::ApplyCase);
        }
        if ui.button("Free cube").clicked() {
            requests.push(Request::FreeCube);
        }
    });
    if let (Some(case), Some(fem)) = (&shown.case_active, &shown.fem_answer) {
        let (avg, max) = error_vs_fem(&ctx.published.positions, ctx.rest, fem);
        let h = ctx.grid.h();
        ui.label(format!(
            "{}: MSM vs FEM now: average {:.3} % of h, max {:.3} % of h",
            case.id,
            100.0 * avg / h,
            100.0 * max / h
        ));
    }
}

/// The left-button tool, by the buttons or the keyboard (where no text field takes the keys):
/// `p` probe, `d` drag, `c` camera.
pub fn tool_picker(ui: &mut egui::Ui, settings: &mut ViewSettings) {
    if !ui.ctx().egui_wants_keyboard_input() {
        for (key, tool) in
            [(egui::Key::P, ToolKind::Probe), (egui::Key::D, ToolKind::Drag), (egui::Key::C, ToolKind::Orbit)]
        {
            if ui.ctx().input(|i| i.key_pressed(key)) {
                settings.tool = tool;
            }
        }
    }
    ui.horizontal(|ui| {
        ui.selectable_value(&mut settings.tool, ToolKind::Drag, "drag (d)");
        ui.selectable_value(&mut settings.tool, ToolKind::Probe, "probe (p)");
        ui.selectable_value(&mut settings.tool, ToolKind::Orbit, "camera only (c)");
    });
}

/// The last press beside the material's force for it and the running model's own, each said
/// for what it is.
fn comparison(ui: &mut egui::Ui, shown: &Shown, requests: &mut Vec<Request>) {
    ui.horizontal_wrapped(|ui| {
        let busy = shown.comparing;
        let button = ui.add_enabled(!busy, egui::Button::new("Compare this press with the material")).on_hover_text(
            "The force shown for the last press beside the material's own force on the same press at rest (the \
             converged continuum: graded hex8 meshes refined until the force changes by less than 1 %) and the \
             running model's with its own surface nodes as the contact",
        );
        if button.clicked() {
            requests.push(Request::ComparePress);
        }
        if busy {
            ui.label("computing the material's force...");
        }
    });
    let Some(cmp) = &shown.comparison else { return };
    let p = &cmp.press;
    let at = p.at.map(|c| format!("{:.1}", 1e3 * c)).join(", ");
    ui.label(format!(
        "press of a {} sphere {} deep at ({at}) mm:",
        crate::io::length(p.radius),
        crate::io::length(p.depth)
    ));
    let rel = |f: f64, of: f64| if of > 0.0 { format!(" ({:+.1} %)", 100.0 * (f / of - 1.0)) } else { String::new() };
    let material = cmp.material_n.as_ref().ok().copied();
    let shown_what = match cmp.shown_contact {
        crate::sim::press::Contact::Surface => "the material's surface compliance, with its modes",
        crate::sim::press::Contact::Nodes => "the model's surface nodes",
    };
    ui.label(format!(
        "  shown {:.2} N{}: what the probe felt ({shown_what})",
        cmp.shown_n,
        material.map_or(String::new(), |m| rel(cmp.shown_n, m))
    ));
    match &cmp.material_n {
        Ok(m) => ui.label(format!("  the material {m:.2} N: the converged continuum, at rest")),
        Err(e) => ui.label(format!("  the material: {e}")),
    };
    match &cmp.model_n {
        Ok(f) => ui.label(format!(
            "  the running model's own nodes {f:.2} N{}: what the model alone gives (static, its surface nodes the \
             contact); the probe does not feel this",
            material.map_or(String::new(), |m| rel(*f, m))
        )),
        Err(e) => ui.label(format!("  the running model's own nodes: {e}")),
    };
}

/// How to press and slide the probe, and its size.
fn probe_settings(ui: &mut egui::Ui, settings: &mut ViewSettings) {
    ui.label(
        "Probe: press with the left button where it should touch and move down to push it in along the \
         surface's inward normal there (0.1 mm a pixel) or turn the wheel (0.25 mm a notch); hold Shift and move \
         to slide it across the surface at that depth (palpation). The depth is the indentation along the push; \
         the force shows next to the sphere.",
    );
    ui.checkbox(&mut settings.probe_along_view, "push along the view ray instead");
    let (lo, hi) = (crate::sim::press::MIN_RADIUS_M * 1e3, crate::sim::press::MAX_RADIUS_M * 1e3);
    ui.add(egui::Slider::new(&mut settings.probe_radius_mm, lo..=hi).text("probe radius (mm)"));
}

/// The probe's force against its depth since the press began, and which contact gave it where
/// that is not the material's.
fn force_depth_plot(ui: &mut egui::Ui, shown: &Shown, ctx: &PanelContext<'_>) {
    if !ctx.published.surface_probe {
        let when = shown.material_contact_in.as_deref().map_or(String::new(), |w| format!(", {w}"));
        ui.colored_label(egui::Color32::from_rgb(255, 170, 60), format!("force from the model nodes{when}"));
    }
    super::fitted_plot(ui, "force_depth", "probe depth (mm)", "probe force (N)").include_x(0.0).include_y(0.0).show(
        ui,
        |p| {
            p.line(Line::new("force vs depth", PlotPoints::from(shown.force_depth.clone())));
        },
    );
}

/// What the probe touches: the material's surface compliance, or the model's nodes until it is
/// ready.
fn contact_line(shown: &Shown, ctx: &PanelContext<'_>) -> String {
    match (&shown.contact_status, ctx.published.surface_probe) {
        (Some(status), _) => status.clone(),
        (None, true) => {
            let inclusions = shown.inclusions.len() + usize::from(shown.exercise.is_some());
            let felt =
                if inclusions > 0 { format!("; its {inclusions} inclusion(s) felt within 3 %") } else { String::new() };
            format!(
                "probe contact: the material's surface compliance (every free face, 2 mm grid, 1 mm across the edges; \
                 within 3.6 % of the material on every scored press{felt}) with its 192 lowest modes (inertia and \
                 damping: a fast tap within 4 % of the material's)"
            )
        }
        (None, false) => "probe contact: the model's surface nodes".into(),
    }
}
