//! The viewer's probe gesture as a person makes it: pointer events at the default window (1280 x
//! 720, the panel 380 px wide) and camera, the button pressed over the middle of the top face and
//! moved 40 pixels down. The sphere starts tangent to the surface and goes in along its inward
//! normal, 0.1 mm a pixel (before, it started along the view ray, already 10 mm under the top
//! face at depth 0, and read 32.1 N where the material gives 9.7 N), and its force is the
//! material's at that indentation. Recorded on the viewer's simulation, the press replays to its
//! forces.

use egui::{Event, PointerButton, Pos2, RawInput, Rect};
use tissue_core::mechanics::grid::Grid;
use tissue_core::mechanics::material::Material;
use tissue_core::sim::Tool;
use tissue_core::sim::material_surface::compliance::SurfaceContactScratch;
use tissue_studies::validate::continuum::cache::ContinuumCache;
use tissue_studies::validate::continuum::{DEFAULT_TOLERANCE, Press};
use tissue_viewer::app::gestures::{Gesture, Scene, view_input};
use tissue_viewer::app::state::{Request, ToolKind};
use tissue_viewer::render::camera::OrbitCamera;
use tissue_viewer::render::mesh::SurfaceMesh;

const WINDOW: [f32; 2] = [1280.0, 720.0];
const PANEL: f32 = 380.0;

/// One frame of the 3D view with `events`, at `time` seconds.
fn frame(
    ctx: &egui::Context,
    events: Vec<Event>,
    time: f64,
    state: (&mut OrbitCamera, &mut Gesture),
    scene: &Scene<'_>,
) -> Vec<Request> {
    let (camera, gesture) = state;
    let mut requests = Vec::new();
    let raw = RawInput {
        screen_rect: Some(Rect::from_min_size(Pos2::ZERO, egui::vec2(WINDOW[0], WINDOW[1]))),
        events,
        time: Some(time),
        ..Default::default()
    };
    let _ = ctx.run_ui(raw, |ui| {
        egui::CentralPanel::default().frame(egui::Frame::NONE).show(ui, |ui| {
            let rect = Rect::from_min_max(Pos2::new(PANEL, 0.0), Pos2::new(WINDOW[0], WINDOW[1]));
            let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
            view_input(&response, ui.ctx(), camera, gesture, scene, &mut requests);
        });
    });
    requests
}

/// The gesture a person makes at the default window and camera: the button pressed over the
/// middle of the top face and moved 40 pixels down, a pixel a frame (50 frames a second); the
/// probe's press after each frame, if the gesture pressed it.
fn forty_pixels_down(radius_mm: f64) -> Vec<Option<tissue_viewer::app::recording::Press>> {
    let grid = Grid::paper();
    let mut mesh = SurfaceMesh::new(&grid);
    let positions: Vec<[f32; 3]> = grid.positions().iter().map(|p| p.map(|v| v as f32)).collect();
    mesh.update(&positions, None);
    let scene = Scene {
        mesh: &mesh,
        positions: &positions,
        tool: ToolKind::Probe,
        probe_radius_mm: radius_mm,
        probe_along_view: false,
    };
    let mut camera = OrbitCamera::default();
    let mut gesture = Gesture::None;
    // The middle of the top face on the screen.
    let aspect = (WINDOW[0] - PANEL) / WINDOW[1];
    let clip = camera.view_proj(aspect) * glam::Vec4::new(0.05, 0.05, 0.1, 1.0);
    let ndc = clip.truncate() / clip.w;
    let p0 = Pos2::new(PANEL + 0.5 * (ndc.x + 1.0) * (WINDOW[0] - PANEL), 0.5 * (1.0 - ndc.y) * WINDOW[1]);
    let ctx = egui::Context::default();
    let press = |pressed: bool, pos: Pos2| Event::PointerButton {
        pos,
        button: PointerButton::Primary,
        pressed,
        modifiers: egui::Modifiers::NONE,
    };
    let mut t = 0.0;
    let mut frames: Vec<Vec<Event>> = vec![vec![Event::PointerMoved(p0)], vec![press(true, p0)]];
    frames.extend((1..=40).map(|k| vec![Event::PointerMoved(p0 + egui::vec2(0.0, k as f32))]));
    let mut out = Vec::new();
    for events in frames {
        t += 0.02;
        let mut pressed = None;
        for r in frame(&ctx, events, t, (&mut camera, &mut gesture), &scene) {
            if let Request::Press(p) = r {
                assert!(matches!(p.tool(), Tool::Probe { .. }));
                pressed = Some(p);
            }
        }
        out.push(pressed);
    }
    out
}

#[test]
fn the_probe_goes_in_along_the_normal_a_tenth_of_a_millimetre_a_pixel_with_the_materials_force() {
    let radius_mm = 15.0;
    let last = forty_pixels_down(radius_mm).into_iter().flatten().last().map(|p| (p.centre(), p.radius));
    let (centre, radius) = last.expect("the gesture pressed the probe");
    assert_eq!(radius, radius_mm * 1e-3);
    // Straight down along the top face's normal, from tangent: 40 pixels, 4 mm.
    let at = [centre[0], centre[1], 0.1];
    let depth = 0.1 + radius - centre[2];
    assert!((depth - 0.004).abs() < 1e-6, "indentation {depth} m for 40 pixels");
    assert!((at[0] - 0.05).abs() < 0.002 && (at[1] - 0.05).abs() < 0.002, "touched {at:?}");
    // The force the viewer's contact gives there (the material's surface compliance, which a
    // held press settles to) against the material's own.
    let material = Material::object_a();
    let dir = tissue_core::io::cache_dir();
    let compliance = tissue_core::sim::material_surface::load_or_compute(&material, dir.as_deref(), &mut |_| true)
        .expect("the surface compliance");
    let viewer = compliance.press(centre, radius, &mut SurfaceContactScratch::default()).expect("a press")[2];
    let mut kept = ContinuumCache::open(&material, dir.as_deref());
    let press = Press::normal(at, radius).depth(depth);
    let truth = kept.force(&material, &press, DEFAULT_TOLERANCE, &mut |_| {}).expect("the material's force").force_n;
    kept.save();
    assert!((viewer / truth - 1.0).abs() < 0.07, "the viewer's {viewer} N against the material's {truth} N");
}

/// The same gesture on the viewer's simulation (object A's default tissue, the material's surface
/// contact), each frame's press handed to the physics timeline as the viewer's physics thread
/// does and 20 ms stepped, then held 1 s: recorded, written as a script, read back and replayed
/// by `simulate`, the forces agree within 1 %, the recorded indentation is the mouse's (0.1 mm a
/// pixel) and its force the material's there within 7 %.
#[test]
fn the_viewers_press_recorded_replays_to_its_forces() {
    use tissue_core::sim::{Integrator, Model, Simulation};
    use tissue_studies::study::script::{Recorded, Script, run};
    use tissue_viewer::app::recording::Timeline;
    let material = Material::object_a();
    let grid = Grid::paper();
    let model = Model::Lattice(tissue_core::sim::shipped::DEFAULT_TOPOLOGY);
    let tissue = model.build_on(grid, &material, None, 0.2).expect("the default tissue");
    let case = tissue_core::mechanics::cases::LoadCase::bottom_clamp(&grid, "A");
    let mut sim = Simulation::with_tissue(tissue, Integrator::Prefactored, 1e-4, Some(&case));
    let _ = sim.set_integrator(None, 1e-4);
    let dir = tissue_core::io::cache_dir();
    let surface =
        tissue_core::sim::material_surface::MaterialSurface::load_or_compute(&material, dir.as_deref(), &mut |_| true)
            .expect("the surface compliance");
    sim.set_surface_probe(Some(tissue_core::sim::material_surface::SurfaceProbe::on(&surface, grid, Some(0.2))));
    let mut timeline = Timeline::new(true);
    let step = |timeline: &mut Timeline, sim: &mut Simulation, seconds: f64| {
        for _ in 0..(seconds / sim.dt).round() as usize {
            timeline.before_step(sim);
            sim.step().expect("a healthy step");
            timeline.after_step(sim);
        }
    };
    for press in forty_pixels_down(15.0) {
        if let Some(p) = press {
            timeline.press(p, 0.02, &mut sim);
        }
        step(&mut timeline, &mut sim, 0.02);
    }
    step(&mut timeline, &mut sim, 1.0);
    let rec = timeline.recording(&sim);
    let last = rec.force_path.last().expect("force samples").clone();
    assert!((last.depth_m - 0.004).abs() < 1e-6, "recorded indentation {} m for 40 pixels", last.depth_m);
    let script = Script {
        object: Some(tissue_core::mechanics::object::Object::A),
        material: None,
        model,
        dt: rec.dt,
        integrator: Some(rec.integrator),
        damping_ratio: rec.damping_ratio,
        clamp: "bottom".into(),
        nodes: grid.n(),
        contact: rec.contact,
        compute: tissue_gpu::Compute::Cpu,
        actions: rec.actions,
        recorded: Some(Recorded { force_path: rec.force_path, note: None }),
    };
    let text = serde_json::to_string_pretty(&script).expect("JSON");
    let replay = run(&serde_json::from_str(&text).expect("the script reads back")).expect("the replay runs");
    let cmp = replay.replay.expect("the replay compared");
    assert_eq!(cmp.matched, cmp.recorded);
    assert!(cmp.relative_l2 < 0.01, "{cmp:?}");
    let mut kept = ContinuumCache::open(&material, dir.as_deref());
    let at = [last.at[0], last.at[1], 0.1];
    let press = Press::normal(at, 0.015).depth(last.depth_m);
    let truth = kept.force(&material, &press, DEFAULT_TOLERANCE, &mut |_| {}).expect("the material's force").force_n;
    kept.save();
    assert!((last.force_n / truth - 1.0).abs() < 0.07, "recorded {} N against the material's {truth} N", last.force_n);
}
