//! The event loop and the frame: winit events in, one egui pass (panel and 3D view), requests to
//! the viewer state, the physics thread's latest state drawn through the [`Surface`]. Redraws on
//! demand: while something moves, a job reports, or egui asks; otherwise the loop sleeps.

use std::time::{Duration, Instant};

use anyhow::Context as _;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::window::WindowId;

use super::gestures::{Gesture, Scene, view_input};
use super::overlay::{ForceTrace, Overlay, Show, legend};
use super::panel::study::StudyPanel;
use super::panel::{self, PanelContext};
use super::physics::{Command, PhysicsThread, Published};
use super::state::{Request, ToolKind, ViewerState};
use super::stats::Stats;
use super::surface::{CubeFrame, EguiFrame, Surface};
use crate::render::camera::OrbitCamera;
use crate::render::gpu::SurfaceStyle;
use crate::render::mesh::SurfaceMesh;
use crate::render::scene::ColourMode;

/// A wake-up from another thread.
#[derive(Debug, Clone, Copy)]
pub enum Wake {
    /// egui asked for a repaint.
    Repaint,
    /// SIGINT or SIGTERM: close (writing the recording).
    Quit,
}

struct App {
    surface: Option<Surface>,
    egui: egui::Context,
    physics: PhysicsThread,
    physics_stopped: Option<String>,
    latest: Published,
    state: ViewerState,
    study: StudyPanel,
    camera: OrbitCamera,
    gesture: Gesture,
    /// The surface as drawn, on the material's lattice ([`super::dent`]).
    mesh: SurfaceMesh,
    /// The vertices near the probe's contact and where the material puts them, this frame.
    dent: Vec<crate::render::mesh::Dent>,
    overlay: Overlay,
    /// The probe's recent force, drawn next to the sphere.
    trace: ForceTrace,
    requests: Vec<Request>,
    view_rect: egui::Rect,
    max_frames: Option<u64>,
    screenshot: Option<std::path::PathBuf>,
    stats: Stats,
    repaint_after: Option<Instant>,
    input_until: Option<Instant>,
    cursor_moved: bool,
    /// The physics thread's message revision last drawn.
    drawn_revision: u64,
    /// The window has had the keyboard focus (else, where no window manager gives it, the tool
    /// keys are read raw while the pointer is over the window).
    had_focus: bool,
    /// The pointer is over the window.
    pointer_inside: bool,
    error: Option<anyhow::Error>,
}

impl App {
    fn new(proxy: EventLoopProxy<Wake>, options: super::ViewOptions) -> anyhow::Result<Self> {
        let super::ViewOptions { frames: max_frames, screenshot, model, compute, press, record, material } = options;
        if record.is_some() {
            // The first SIGINT or SIGTERM closes the viewer as its window would, writing the
            // recording; a second ends the process.
            let quit = proxy.clone();
            crate::io::on_interrupt(Box::new(move || {
                let _ = quit.send_event(Wake::Quit);
            }));
        }
        let egui = egui::Context::default();
        let wake_proxy = proxy.clone();
        egui.set_request_repaint_callback(move |info| {
            // A delayed request is honoured by `about_to_wait`; only an immediate one wakes now.
            if info.delay <= Duration::from_millis(16) {
                let _ = wake_proxy.send_event(Wake::Repaint);
            }
        });
        let repaint = egui.clone();
        let (mut state, first) = ViewerState::new(move || repaint.request_repaint())?;
        state.settings.recording.clone_from(&record);
        // The model and compute asked for on the command line, as the panel would ask.
        let mut requests = Vec::with_capacity(16);
        state.settings.compute = compute;
        if let Some(path) = material {
            state.settings.object = crate::app::settings::Source::File;
            state.settings.material_path = path.display().to_string();
            requests.push(Request::LoadObject);
        }
        match model {
            Some(crate::sim::Model::Fem(f)) => requests.push(Request::SelectFem(f)),
            Some(crate::sim::Model::Lattice(t)) => requests.push(Request::SelectTopology(t)),
            None if compute != crate::gpu::Compute::Cpu => requests.push(Request::SetCompute),
            None => {}
        }
        if let Some([x, y, depth]) = press {
            // As the probe tool would press it, at the settings' radius.
            state.settings.tool = crate::app::state::ToolKind::Probe;
            let radius = state.settings.probe_radius_mm * 1e-3;
            let at = [x, y, crate::mechanics::grid::CUBE_SIDE_M];
            let press = super::recording::Press { at, direction: Some([0.0, 0.0, -1.0]), radius, depth };
            if record.is_some() {
                // Recorded from its start on the material's contact: pressed once that is ready.
                state.shown.tool = press.tool();
                state.shown.last_probe = Some((press.centre(), press.radius));
                state.deferred_press = Some(press);
            } else {
                requests.push(Request::Press(press));
            }
        }
        let grid = state.grid();
        // The physics thread builds the model from its recipe: none is built here.
        let physics = PhysicsThread::spawn(first, record.is_some()).context("cannot start the physics thread")?;
        Ok(Self {
            surface: None,
            egui,
            physics,
            physics_stopped: None,
            latest: {
                let mut p = Published::default();
                p.contact.reserve(crate::sim::material_surface::compliance::MAX_CONTACT_NODES);
                p
            },
            state,
            study: StudyPanel::default(),
            camera: OrbitCamera::default(),
            gesture: Gesture::None,
            mesh: super::dent::display_mesh(&grid),
            dent: Vec::with_capacity(super::dent::MAX_DENT),
            overlay: Overlay::new(&grid),
            trace: ForceTrace::default(),
            requests,
            view_rect: egui::Rect::NOTHING,
            max_frames,
            screenshot,
            stats: Stats::default(),
            repaint_after: None,
            input_until: None,
            cursor_moved: false,
            drawn_revision: 0,
            had_focus: false,
            pointer_inside: false,
            error: None,
        })
    }

    /// Hands the frame's requests to the state; commands go to the physics thread.
    fn handle_requests(&mut self) {
        let physics = &self.physics;
        let stats = &mut self.stats;
        let mut dead = false;
        let mut send = |c: Command| {
            if matches!(c, Command::SetTool(_) | Command::Press(_)) {
                stats.sent();
            }
            dead |= physics.send(c).is_err();
        };
        let mut save = false;
        for r in self.requests.drain(..) {
            save |= r == Request::SaveRecording;
            self.state.handle(r, &mut send);
        }
        if dead && self.physics_stopped.is_none() {
            self.physics_stopped = Some("the physics thread has stopped; restart the viewer".into());
        }
        if save {
            self.state.shown.note = Some(self.save_recording().unwrap_or_else(|e| format!("{e:#}")));
        }
    }

    /// Writes the recording of the physics thread as the `simulate` script of the scene the
    /// panel shows, to the file `view --record FILE` names; says what it wrote.
    fn save_recording(&self) -> anyhow::Result<String> {
        use anyhow::Context as _;
        let Some(path) = &self.state.settings.recording else {
            anyhow::bail!("nothing is recorded: start the viewer with --record FILE");
        };
        let (tx, rx) = std::sync::mpsc::channel();
        let taken = self.physics.send(super::physics::Command::TakeRecording(tx)).is_ok();
        let rec = rx
            .recv_timeout(std::time::Duration::from_secs(5))
            .ok()
            .filter(|_| taken)
            .context("recording not written: the physics thread did not hand it over")?;
        let script = self.state.recording_script(rec).context("recording not written")?;
        crate::io::write_json_atomic(path, &script)
            .with_context(|| format!("recording not written to {}", path.display()))?;
        let samples = script.recorded.as_ref().map_or(0, |r| r.force_path.len());
        Ok(format!(
            "recording: {} actions and {samples} force samples written to {} (replay: tissue-sim simulate --script {} \
             --out FILE)",
            script.actions.len(),
            path.display(),
            path.display()
        ))
    }

    /// The egui pass: the panel and the 3D view's input.
    fn run_ui(&mut self) -> Option<egui::FullOutput> {
        let surface = self.surface.as_mut()?;
        let raw = surface.egui_state.take_egui_input(&surface.window);
        let ctx = self.egui.clone();
        let full = ctx.run_ui(raw, |ui| {
            egui::Panel::left("panel").exact_size(380.0).show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    let pctx = PanelContext {
                        published: &self.latest,
                        fps: self.stats.fps,
                        latency: self.stats.latency_shown,
                        physics_stopped: self.physics_stopped.as_deref(),
                        rest: self.overlay.rest(),
                        grid: self.state.grid(),
                    };
                    let s = &mut self.state;
                    panel::show(
                        ui,
                        &mut s.settings,
                        &s.shown,
                        &pctx,
                        &mut self.camera,
                        &mut self.study,
                        &mut self.requests,
                    );
                });
            });
            egui::CentralPanel::default().frame(egui::Frame::NONE).show(ui, |ui| {
                let rect = ui.max_rect();
                let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
                self.view_rect = response.rect;
                let settings = &self.state.settings;
                let scene = Scene {
                    mesh: &self.mesh,
                    positions: &self.latest.positions,
                    tool: settings.tool,
                    probe_radius_mm: settings.probe_radius_mm,
                    probe_along_view: settings.probe_along_view,
                };
                view_input(&response, ui.ctx(), &mut self.camera, &mut self.gesture, &scene, &mut self.requests);
                if !self.overlay.title.is_empty() {
                    legend(ui, rect, &self.overlay);
                }
                self.force_beside_the_probe(ui.painter(), rect);
            });
        });
        Some(full)
    }

    /// The tool as drawn: the probe's sphere where the physics step of the shown force had it
    /// (the hand's target runs ahead of it by the glide), else the tool asked for.
    fn drawn_tool(&self) -> crate::sim::Tool {
        match (self.state.shown.tool, self.latest.probe) {
            (crate::sim::Tool::Probe { .. }, Some((press, _))) => press.tool(),
            (tool, _) => tool,
        }
    }

    /// The probe's force and depth as numbers and a small plot of the force next to the sphere in
    /// the 3D view: the physics thread's one reading, of the step the sphere is drawn at.
    fn force_beside_the_probe(&mut self, painter: &egui::Painter, rect: egui::Rect) {
        let crate::sim::Tool::Probe { centre, radius } = self.drawn_tool() else {
            self.trace.clear();
            return;
        };
        // The force against the push and the depth (|F| until the first reading).
        let (f, depth) = self.latest.probe.map_or_else(
            || (glam::DVec3::from(self.latest.tool_force).length(), None),
            |(_, r)| (r.force_n, Some(r.depth_m)),
        );
        self.trace.push(f as f32, depth.map(|d| d as f32));
        let aspect = rect.width() / rect.height().max(1.0);
        let c = glam::DVec3::from(centre).as_vec3();
        let clip = self.camera.view_proj(aspect) * c.extend(1.0);
        if clip.w <= 0.0 {
            return;
        }
        let ndc = clip.truncate() / clip.w;
        let at = egui::pos2(
            rect.left() + 0.5 * (ndc.x + 1.0) * rect.width(),
            rect.top() + 0.5 * (1.0 - ndc.y) * rect.height(),
        );
        // Beside the sphere, kept inside the view.
        // Where the force is not the material's: which contact gave it, and when the
        // material's will (`model nodes, the material's in 12 s`).
        let nodes = self
            .latest
            .probe
            .map_or(!self.latest.surface_probe, |(_, r)| r.contact == crate::sim::press::Contact::Nodes);
        let note = nodes.then(|| match &self.state.shown.material_contact_in {
            Some(when) => format!("model nodes, {when}"),
            None => "model nodes".to_owned(),
        });
        let offset = egui::vec2(30.0 + 400.0 * radius as f32, -80.0);
        let corner = (at + offset).clamp(rect.min, rect.max - ForceTrace::size(note.is_some()));
        self.trace.draw(painter, corner, note.as_deref());
    }

    fn frame(&mut self) -> anyhow::Result<()> {
        self.physics.latest(&mut self.latest);
        self.state.observe_probe(self.latest.probe);
        self.drawn_revision = self.latest.revision;
        let physics = &self.physics;
        self.state.poll(&mut |c| {
            // A stopped physics thread is reported by its own poll.
            let _ = physics.send(c);
        });
        let Some(full) = self.run_ui() else { return Ok(()) };
        let sent = self.stats.tools_sent;
        self.handle_requests();
        if self.stats.tools_sent > sent {
            // Show this frame what the tool just did: wait (at most 3 ms, about 3 physics
            // ticks) for the physics thread to apply and step it, instead of a frame later.
            let deadline = Instant::now() + Duration::from_millis(3);
            while self.latest.tool_commands < self.stats.tools_sent && Instant::now() < deadline {
                std::thread::sleep(Duration::from_micros(200));
                self.physics.latest(&mut self.latest);
            }
        }
        self.draw(full)?;
        self.stats.count_frame(self.max_frames.is_some(), self.latest.rates);
        Ok(())
    }

    fn draw(&mut self, full: egui::FullOutput) -> anyhow::Result<()> {
        let grid = self.state.grid();
        let n = grid.num_nodes();
        if self.overlay.rest().len() != n {
            // Another resolution: the surface and overlays of the new grid.
            self.mesh = super::dent::display_mesh(&grid);
            self.overlay = Overlay::new(&grid);
        }
        if self.latest.positions.len() != n {
            self.latest.positions.clear();
            self.latest.positions.extend_from_slice(self.overlay.rest());
            self.latest.fixed.resize(n, false);
        }
        let s = &self.state.settings;
        let show = Show {
            colour: s.colour,
            springs: s.show_springs,
            nodes: s.show_nodes,
            map_contrast: s.map_contrast,
            fixed: s.show_fixed,
            tool: self.drawn_tool(),
            tool_force: self.latest.tool_force,
            lump: self.state.shown.exercise.as_ref().and_then(|e| {
                let (mark, _) = e.mark?;
                Some((e.lump.inclusion.centre, e.lump.inclusion.radius, mark))
            }),
        };
        let fem = self.state.shown.fem_answer.as_deref();
        let map =
            self.state.shown.face_map.as_ref().and_then(|m| m.as_ref().ok()).filter(|_| self.state.settings.show_map);
        match (self.state.felt_compliance(), self.latest.probe) {
            (Some(c), Some((press, _))) if self.latest.surface_probe => {
                let sphere = (press.centre(), press.radius);
                super::dent::fill(&mut self.dent, &self.mesh, c, &self.latest.contact, sphere);
            }
            _ => self.dent.clear(),
        }
        let mesh = &self.mesh;
        let dented = self
            .dent
            .iter()
            .map(|d| glam::Vec3::from(d.at).distance(glam::Vec3::from(mesh.rest_of(d.vertex))))
            .fold(0.0, f32::max);
        self.overlay.update(show, &self.latest.positions, &self.latest.fixed, fem, map, dented);
        let scalar = Some(self.overlay.scalar.as_slice());
        self.mesh.update_dented(&self.latest.positions, scalar, &self.dent, self.overlay.per_metre);
        let Some(surface) = self.surface.as_mut() else { return Ok(()) };
        surface.egui_state.handle_platform_output(&surface.window, full.platform_output);
        self.repaint_after = full
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .map(|v| v.repaint_delay)
            .filter(|d| *d < Duration::from_secs(3600))
            .map(|d| Instant::now() + d);
        let jobs = self.egui.tessellate(full.shapes, full.pixels_per_point);
        let camera = self.camera;
        let cube = CubeFrame {
            rect: self.view_rect,
            view_proj: &move |aspect| camera.view_proj(aspect),
            colour_map: s.colour != ColourMode::None
                || (s.show_map && self.state.shown.face_map.as_ref().is_some_and(Result::is_ok)),
            mesh: &self.mesh,
            lines: &self.overlay.lines,
            see_through: self.overlay.see_through,
        };
        let egui = EguiFrame { jobs, textures: full.textures_delta, pixels_per_point: full.pixels_per_point };
        // `--screenshot` with `--frames N`: the last frame is read back as the window shows it.
        if self.screenshot.is_some() && self.max_frames.is_some_and(|m| self.stats.frames + 1 >= m) {
            surface.request_capture();
        }
        if surface.draw(&cube, egui)? {
            self.stats.shown(self.latest.tool_commands);
        }
        Ok(())
    }

    /// Whether the next frame should be drawn now: something moves, a job reports, egui asked,
    /// or a smoke test counts frames.
    fn wants_redraw(&self) -> bool {
        self.max_frames.is_some()
            || self.latest.moving
            || self.latest.revision != self.drawn_revision
            || self.state.busy()
            || self.study.busy()
            || self.repaint_after.is_some_and(|t| Instant::now() >= t)
            || self.input_until.is_some_and(|t| Instant::now() < t)
    }
}

impl App {
    fn frame_or_exit(&mut self, event_loop: &ActiveEventLoop) {
        self.cursor_moved = false;
        if let Err(e) = self.frame() {
            self.error = Some(e);
            event_loop.exit();
        }
    }
}

impl ApplicationHandler<Wake> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.surface.is_none() {
            match Surface::new(event_loop, &self.egui, &self.mesh, self.overlay.lines.capacity()) {
                Ok(s) => self.surface = Some(s),
                Err(e) => {
                    self.error = Some(e);
                    event_loop.exit();
                }
            }
        }
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, event: Wake) {
        if let Wake::Quit = event {
            event_loop.exit();
        } else if let Some(s) = &self.surface {
            s.window.request_redraw();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let press = matches!(event, WindowEvent::MouseInput { state: winit::event::ElementState::Pressed, .. });
        if press && self.cursor_moved {
            // The pointer moved since the last frame: let egui see it hover before the press.
            self.frame_or_exit(event_loop);
        }
        self.cursor_moved |= matches!(event, WindowEvent::CursorMoved { .. });
        if let Some(s) = &mut self.surface
            && s.egui_state.on_window_event(&s.window, &event).repaint
            && !matches!(event, WindowEvent::RedrawRequested)
        {
            // Input: draw now and keep drawing a little while (a click spans frames).
            self.input_until = Some(Instant::now() + Duration::from_millis(500));
            s.window.request_redraw();
        }
        if press {
            // A press gets a frame of its own, so that a release arriving before the next redraw
            // still makes a click.
            self.frame_or_exit(event_loop);
        }
        match event {
            WindowEvent::Focused(true) => self.had_focus = true,
            WindowEvent::CursorEntered { .. } => self.pointer_inside = true,
            WindowEvent::CursorLeft { .. } => self.pointer_inside = false,
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(s) = &mut self.surface {
                    s.resize(size.width, size.height);
                }
            }
            WindowEvent::RedrawRequested => {
                self.frame_or_exit(event_loop);
                if self.max_frames.is_some_and(|m| self.stats.frames >= m) {
                    event_loop.exit();
                }
            }
            _ => {}
        }
    }

    /// The tool keys (p, d, c) where no window manager ever gave the window the keyboard (a
    /// virtual display): read raw while the pointer is over the window. With the focus, egui
    /// reads them ([`super::panel`]).
    fn device_event(
        &mut self,
        _event_loop: &ActiveEventLoop,
        _id: winit::event::DeviceId,
        event: winit::event::DeviceEvent,
    ) {
        use winit::keyboard::{KeyCode, PhysicalKey};
        let winit::event::DeviceEvent::Key(key) = event else { return };
        if self.had_focus || !self.pointer_inside || key.state != winit::event::ElementState::Pressed {
            return;
        }
        let tool = match key.physical_key {
            PhysicalKey::Code(KeyCode::KeyP) => ToolKind::Probe,
            PhysicalKey::Code(KeyCode::KeyD) => ToolKind::Drag,
            PhysicalKey::Code(KeyCode::KeyC) => ToolKind::Orbit,
            _ => return,
        };
        self.state.settings.tool = tool;
        if let Some(s) = &self.surface {
            s.window.request_redraw();
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        // Look at the physics often enough to notice motion; draw only when something changes.
        self.physics.latest(&mut self.latest);
        let stopped = self.physics_stopped.is_none() && {
            self.physics_stopped = self.physics.poll();
            self.physics_stopped.is_some()
        };
        if (stopped || self.wants_redraw())
            && let Some(s) = &self.surface
        {
            s.window.request_redraw();
        }
        event_loop.set_control_flow(ControlFlow::WaitUntil(Instant::now() + Duration::from_millis(16)));
    }
}

/// Opens the window and runs until it closes.
pub fn run(options: super::ViewOptions) -> anyhow::Result<()> {
    // winit's own message names its source files; say what is wrong in the user's terms.
    let event_loop = EventLoop::<Wake>::with_user_event().build().map_err(|_| {
        let display = std::env::var("DISPLAY").or_else(|_| std::env::var("WAYLAND_DISPLAY")).unwrap_or_default();
        anyhow::anyhow!(
            "cannot open the display {display:?}: no window system answers there (is an X server or Wayland \
             compositor running?); {}",
            super::HEADLESS_HINT
        )
    })?;
    // Raw keys too, for the tool keys where no window manager gives the window the keyboard
    // ([`App::device_event`]: only while the pointer is over a window never focused).
    event_loop.listen_device_events(winit::event_loop::DeviceEvents::Always);
    let mut app = App::new(event_loop.create_proxy(), options)?;
    let ran = event_loop.run_app(&mut app).context("event loop failed");
    // Closed, interrupted or failed: what was done is written first.
    let saved = app.state.settings.recording.is_some().then(|| app.save_recording());
    ran?;
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    if let Some(said) = saved {
        eprintln!("{}", said?);
    }
    if app.max_frames.is_some() {
        let p = &app.latest;
        let rate = if p.running_s > 0.0 { p.ticks_total as f64 / p.running_s } else { 0.0 };
        eprintln!(
            "viewer: {} frames; physics {} ticks and {} steps in {:.2} s ({rate:.0} ticks/s)",
            app.stats.frames, p.ticks_total, p.steps_total, p.running_s
        );
    }
    if let Some(path) = app.screenshot.clone() {
        if let Some((w, h, rgba)) = app.surface.as_mut().and_then(Surface::take_capture) {
            // The window as it was shown last, the panel included.
            crate::io::write_atomic(&path, &crate::render::offscreen::encode_png(w, h, &rgba)?)?;
            return Ok(());
        }
        // Where the window's surface allows no copy: the 3D view through the offscreen path.
        let headless = crate::render::offscreen::Headless::new()?;
        let (w, h) = (960, 540);
        let style = SurfaceStyle {
            colour_map: app.state.settings.colour != ColourMode::None
                || (app.state.settings.show_map && app.state.shown.face_map.as_ref().is_some_and(Result::is_ok)),
            ..Default::default()
        };
        let view_proj = app.camera.view_proj(w as f32 / h as f32);
        let rgba = headless.render((w, h), view_proj, style, &app.mesh, &app.overlay.lines)?;
        crate::io::write_atomic(&path, &crate::render::offscreen::encode_png(w, h, &rgba)?)?;
    }
    Ok(())
}
