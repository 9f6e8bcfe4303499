//! The window: winit event loop, wgpu surface, the 3D view beside an egui side panel, mouse tools.

use std::sync::Arc;
use std::time::Instant;

use anyhow::Context as _;
use egui_plot::{Line, Plot, PlotPoints};
use glam::Vec3;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

use super::calibration::{Job, Progress};
use super::physics::{Command, PhysicsThread, Published};
use crate::calibrate::{GenerationStats, Method, Settings};
use crate::cases::{FORCES_N, LoadCase};
use crate::fem::FemModel;
use crate::grid::Grid;
use crate::material::Material;
use crate::msm::{MsmModel, MsmParams, Topology};
use crate::render::camera::OrbitCamera;
use crate::render::gpu::{CubeRenderer, LineVertex, SurfaceStyle, begin_cube_pass, depth_view};
use crate::render::mesh::SurfaceMesh;
use crate::render::{fixed_outline, lattice_edges, normalise, push_edges};
use crate::scene::{ColourMode, tissue_params};
use crate::sim::{Integrator, Simulation, Tool};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ToolKind {
    Orbit,
    Drag,
    Probe,
}

/// Everything the panel edits.
struct Ui {
    object: String,
    material_path: String,
    material: Material,
    topology: Topology,
    params: MsmParams,
    integrator: Integrator,
    dt: f64,
    /// Explicit stability limit of the current parameters, s (refreshed when they change).
    dt_limit: f64,
    tool: ToolKind,
    probe_radius_mm: f64,
    colour: ColourMode,
    show_springs: bool,
    show_nodes: bool,
    show_fixed: bool,
    case_axis: usize,
    case_force: f64,
    case_active: Option<LoadCase>,
    fem_answer: Option<Vec<[f64; 3]>>,
    fem_rx: Option<std::sync::mpsc::Receiver<Result<Vec<[f64; 3]>, String>>>,
    calib_method: Method,
    calib_seed: u64,
    calib_generations: usize,
    calib_population: usize,
    job: Option<Job>,
    history: Vec<GenerationStats>,
    result: Option<MsmParams>,
    note: Option<String>,
    force_depth: Vec<[f64; 2]>,
    study: super::study_panel::StudyPanel,
}

/// The mouse gesture in progress.
#[derive(Debug, Clone, Copy)]
enum Gesture {
    None,
    Orbit,
    Drag { node: usize, plane_point: Vec3 },
    Probe { contact: Vec3, dir: Vec3, start_y: f32 },
}

struct Gpu {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    device: wgpu::Device,
    queue: wgpu::Queue,
    config: wgpu::SurfaceConfiguration,
    depth: wgpu::TextureView,
    cube: CubeRenderer,
    egui_renderer: egui_wgpu::Renderer,
    egui_state: egui_winit::State,
}

struct App {
    gpu: Option<Gpu>,
    egui: egui::Context,
    physics: PhysicsThread,
    latest: Published,
    ui: Ui,
    camera: OrbitCamera,
    gesture: Gesture,
    mesh: SurfaceMesh,
    grid: Grid,
    /// The grid's edges, for the spring and fixed-face overlays.
    edges: Vec<(usize, usize)>,
    lines: Vec<LineVertex>,
    scalar: Vec<f32>,
    rest: Vec<[f32; 3]>,
    view_rect: egui::Rect,
    frames: u64,
    max_frames: Option<u64>,
    screenshot: Option<std::path::PathBuf>,
    fps: f64,
    frame_clock: (Instant, u64),
    error: Option<anyhow::Error>,
    /// Tool commands sent, and when each still unseen on screen was sent.
    tools_sent: u64,
    pending: std::collections::VecDeque<(u64, Instant)>,
    /// Input-to-photon latency of tool commands: (sum s, count, max s) since the last report.
    latency: (f64, u64, f64),
    latency_shown: (f64, f64),
}

fn build_sim(
    material: &Material,
    topology: Topology,
    params: MsmParams,
    integrator: Integrator,
    dt: f64,
    case: Option<&LoadCase>,
) -> anyhow::Result<Simulation> {
    let _ = topology;
    let model = MsmModel::new(Grid::paper(), params, material.density)?;
    Ok(Simulation::new(model, integrator, dt, case))
}

/// A resting cube held by its bottom face (z = 0), the viewer's default scene.
fn bottom_clamp(grid: &Grid) -> LoadCase {
    let mut c = LoadCase::clamped(grid, "view", 3, 0.0);
    c.load.fill(0.0);
    c
}

impl App {
    fn new(max_frames: Option<u64>, screenshot: Option<std::path::PathBuf>) -> anyhow::Result<Self> {
        let grid = Grid::paper();
        let material = Material::object_a();
        let params = tissue_params(&material, Topology::Shear)?;
        let dt = 1e-4;
        let model = MsmModel::new(grid, params, material.density)?;
        let integrator = Simulation::default_integrator(&model, dt);
        let case = bottom_clamp(&grid);
        let sim = build_sim(&material, Topology::Shear, params, integrator, dt, Some(&case))?;
        let physics = PhysicsThread::spawn(sim).context("cannot start the physics thread")?;
        let rest: Vec<[f32; 3]> = grid.positions().iter().map(|p| p.map(|c| c as f32)).collect();
        Ok(Self {
            gpu: None,
            egui: egui::Context::default(),
            physics,
            latest: Published::default(),
            ui: Ui {
                object: "A".into(),
                material_path: String::new(),
                material,
                topology: Topology::Shear,
                params,
                integrator,
                dt,
                dt_limit: Simulation::explicit_dt_limit(&model),
                tool: ToolKind::Drag,
                probe_radius_mm: 15.0,
                colour: ColourMode::Displacement,
                show_springs: false,
                show_nodes: false,
                show_fixed: true,
                case_axis: 1,
                case_force: 10.0,
                case_active: None,
                fem_answer: None,
                fem_rx: None,
                calib_method: Method::Hybrid,
                calib_seed: 1,
                calib_generations: 100,
                calib_population: 50,
                job: None,
                history: Vec::new(),
                result: None,
                note: None,
                force_depth: Vec::new(),
                study: Default::default(),
            },
            camera: OrbitCamera::default(),
            gesture: Gesture::None,
            mesh: SurfaceMesh::new(&grid),
            edges: lattice_edges(&grid),
            grid,
            lines: Vec::with_capacity(2 * 6000),
            scalar: vec![0.0; grid.num_nodes()],
            rest,
            view_rect: egui::Rect::NOTHING,
            frames: 0,
            max_frames,
            screenshot,
            fps: 0.0,
            frame_clock: (Instant::now(), 0),
            error: None,
            tools_sent: 0,
            pending: std::collections::VecDeque::new(),
            latency: (0.0, 0, 0.0),
            latency_shown: (0.0, 0.0),
        })
    }

    fn init_gpu(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let attrs = Window::default_attributes()
            .with_title("tissue-sim")
            .with_inner_size(winit::dpi::PhysicalSize::new(1280, 720));
        let window = Arc::new(event_loop.create_window(attrs).context("cannot create a window")?);
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(
            event_loop.owned_display_handle(),
        )));
        let surface = instance.create_surface(Arc::clone(&window)).context("cannot create a wgpu surface")?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .context("no GPU adapter for this window")?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("tissue-sim"),
            required_limits: wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits()),
            ..Default::default()
        }))
        .context("cannot create a GPU device")?;
        let caps = surface.get_capabilities(&adapter);
        // On a software adapter a non-sRGB target spares egui a per-pixel gamma conversion (its
        // largest cost there); the cube's shader then encodes sRGB itself.
        let software = adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        let format = caps.formats.iter().copied().find(|f| f.is_srgb() != software).unwrap_or(caps.formats[0]);
        // Mailbox where offered; on a software adapter (no real display to tear) Immediate, which
        // lets a CPU rasteriser run as fast as it can; Fifo otherwise.
        let present_mode = if software && caps.present_modes.contains(&wgpu::PresentMode::Immediate) {
            wgpu::PresentMode::Immediate
        } else if caps.present_modes.contains(&wgpu::PresentMode::Mailbox) {
            wgpu::PresentMode::Mailbox
        } else {
            wgpu::PresentMode::Fifo
        };
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: vec![],
            color_space: Default::default(),
        };
        surface.configure(&device, &config);
        let depth = depth_view(&device, config.width, config.height);
        let cube = CubeRenderer::new(&device, format, &self.mesh, self.lines.capacity());
        // Dithering is a per-pixel cost a software rasteriser feels; it only hides banding.
        let options = egui_wgpu::RendererOptions {
            dithering: !software,
            depth_stencil_format: Some(crate::render::gpu::DEPTH_FORMAT),
            ..Default::default()
        };
        let egui_renderer = egui_wgpu::Renderer::new(&device, format, options);
        let egui_state = egui_winit::State::new(
            self.egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        log_adapter(&adapter.get_info());
        if software {
            // Feathering (anti-aliased shape edges) adds thin triangles everywhere; text keeps its
            // anti-aliasing from the font atlas. About +15 % frame rate on lavapipe.
            self.egui.tessellation_options_mut(|o| o.feathering = false);
        }
        self.gpu = Some(Gpu { window, surface, device, queue, config, depth, cube, egui_renderer, egui_state });
        Ok(())
    }

    fn resize(&mut self, width: u32, height: u32) {
        if let Some(g) = &mut self.gpu {
            g.config.width = width.max(1);
            g.config.height = height.max(1);
            g.surface.configure(&g.device, &g.config);
            g.depth = depth_view(&g.device, g.config.width, g.config.height);
        }
    }

    /// Sends a tool command and remembers when, to time it to the screen.
    fn send_tool(&mut self, t: Tool) {
        self.physics.send(Command::SetTool(t));
        self.tools_sent += 1;
        if self.pending.len() < 256 {
            self.pending.push_back((self.tools_sent, Instant::now()));
        }
    }

    fn send_params(&mut self) {
        self.physics.send(Command::SetParams(self.ui.params));
        self.refresh_dt_limit();
    }

    fn refresh_dt_limit(&mut self) {
        if let Ok(model) = MsmModel::new(self.grid, self.ui.params, self.ui.material.density) {
            self.ui.dt_limit = Simulation::explicit_dt_limit(&model);
        }
    }

    fn rebuild(&mut self) {
        let case = self.ui.case_active.clone().unwrap_or_else(|| bottom_clamp(&self.grid));
        match build_sim(
            &self.ui.material,
            self.ui.topology,
            self.ui.params,
            self.ui.integrator,
            self.ui.dt,
            Some(&case),
        ) {
            Ok(sim) => self.physics.send(Command::Replace(Box::new(sim))),
            Err(e) => self.ui.note = Some(format!("cannot build the model: {e:#}")),
        }
    }

    fn load_object(&mut self) {
        let material = if self.ui.object == "file" {
            match Material::from_file(std::path::Path::new(self.ui.material_path.trim())) {
                Ok(m) => m,
                Err(e) => {
                    self.ui.note = Some(e.to_string());
                    return;
                }
            }
        } else {
            match Material::preset(&self.ui.object) {
                Some(m) => m,
                None => return,
            }
        };
        let params = match tissue_params(&material, self.ui.topology) {
            Ok(p) => p,
            Err(_) => {
                // No shipped calibration: start from the material-derived scale and suggest calibrating.
                let space = crate::calibrate::GeneSpace::new(&material, &self.grid, self.ui.topology);
                let mid: Vec<f64> = space.lo.iter().zip(&space.hi).map(|(l, h)| (l * h).sqrt()).collect();
                self.ui.note = Some(format!(
                    "{}: no calibrated tissue shipped; using the material's scale k* — press Calibrate",
                    material.name
                ));
                space.params(&mid)
            }
        };
        self.ui.material = material;
        self.ui.params = params;
        self.refresh_dt_limit();
        self.ui.case_active = None;
        self.ui.fem_answer = None;
        self.rebuild();
    }

    fn apply_case(&mut self) {
        let case = LoadCase::clamped(&self.grid, &self.ui.material.name, self.ui.case_axis, self.ui.case_force);
        self.ui.case_active = Some(case.clone());
        self.send_tool(Tool::None);
        self.physics.send(Command::Reset);
        self.physics.send(Command::ApplyCase(Some(case.clone())));
        // The FEM answer, solved off the UI thread.
        let (tx, rx) = std::sync::mpsc::channel();
        let material = self.ui.material.clone();
        let grid = self.grid;
        let ctx = self.egui.clone();
        let spawned = std::thread::Builder::new().name("fem".into()).spawn(move || {
            let r = FemModel::new(grid, &material)
                .solve_cases(std::slice::from_ref(&case))
                .map(|mut s| s.remove(0).displacements)
                .map_err(|e| e.to_string());
            let _ = tx.send(r);
            ctx.request_repaint();
        });
        if spawned.is_ok() {
            self.ui.fem_rx = Some(rx);
        }
        self.ui.fem_answer = None;
    }

    fn panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("tissue-sim");
        ui.label(format!(
            "{:.0} fps | physics {:.0} ticks/s ({:.0} steps/s, {:.1} us/step, x{:.2} real time)",
            self.fps, self.latest.ticks_per_s, self.latest.steps_per_s, self.latest.step_us, self.latest.realtime
        ));
        if self.latency_shown.0 > 0.0 {
            ui.label(format!(
                "tool input to screen: mean {:.0} ms, max {:.0} ms",
                self.latency_shown.0 * 1e3,
                self.latency_shown.1 * 1e3
            ));
        }
        if let Some(m) = &self.latest.message {
            ui.colored_label(egui::Color32::from_rgb(255, 120, 90), m);
        }
        if let Some(n) = &self.ui.note {
            ui.colored_label(egui::Color32::from_rgb(230, 200, 90), n);
        }
        ui.separator();
        egui::CollapsingHeader::new("Object and model").default_open(true).show(ui, |ui| {
            let mut reload = false;
            ui.horizontal(|ui| {
                for o in ["A", "B", "file"] {
                    reload |= ui.selectable_value(&mut self.ui.object, o.to_owned(), o).changed();
                }
            });
            if self.ui.object == "file" {
                ui.horizontal(|ui| {
                    ui.text_edit_singleline(&mut self.ui.material_path);
                    reload |= ui.button("Load").clicked();
                });
                reload &= !self.ui.material_path.trim().is_empty();
            }
            ui.horizontal_wrapped(|ui| {
                reload |= ui.selectable_value(&mut self.ui.topology, Topology::Shear, "shear springs (default)").changed();
                reload |= ui.selectable_value(&mut self.ui.topology, Topology::Hex, "hex lattice").changed();
                reload |= ui.selectable_value(&mut self.ui.topology, Topology::Axis, "paper: axis springs").changed();
            });
            if self.ui.topology == Topology::Axis {
                ui.colored_label(
                    egui::Color32::from_rgb(230, 200, 90),
                    "The paper's lattice has springs along the axes only: nothing resists shear. Drag a corner sideways to see it.",
                );
            }
            if reload {
                self.ui.note = None;
                self.load_object();
            }
            let mut changed = false;
            let p = &mut self.ui.params;
            let ti = self.ui.material.is_transversely_isotropic();
            egui::Grid::new("params").num_columns(2).show(ui, |ui| {
                let mut row = |ui: &mut egui::Ui, name: &str, v: &mut f64, unit: &str| {
                    ui.label(name);
                    changed |= ui.add(egui::DragValue::new(v).speed(5.0).range(0.0..=1e6).suffix(unit)).changed();
                    ui.end_row();
                };
                row(ui, "k1", &mut p.k1, " N/m");
                row(ui, "k2", &mut p.k2, " N/m");
                if !ti {
                    row(ui, "k3", &mut p.k3, " N/m");
                }
                for (name, c) in [("c12", &mut p.c12), ("c13", &mut p.c13), ("c23", &mut p.c23), ("b", &mut p.b)] {
                    if let Some(v) = c
                        && !(ti && name == "c13")
                    {
                        row(ui, name, v, " N/m");
                    }
                }
                ui.label("d");
                changed |= ui.add(egui::DragValue::new(&mut p.d).speed(0.01).range(0.0..=1e4).suffix(" N s/m")).changed();
                ui.end_row();
            });
            if ti {
                p.k3 = p.k2;
                if p.c12.is_some() {
                    p.c13 = p.c12;
                }
            }
            if changed {
                p.k1 = p.k1.max(1e-3);
                p.k2 = p.k2.max(1e-3);
                p.k3 = p.k3.max(1e-3);
                self.send_params();
            }
        });
        egui::CollapsingHeader::new("Integrator").default_open(true).show(ui, |ui| {
            let mut changed = false;
            ui.horizontal_wrapped(|ui| {
                changed |=
                    ui.selectable_value(&mut self.ui.integrator, Integrator::Symplectic, "symplectic Euler").changed();
                changed |=
                    ui.selectable_value(&mut self.ui.integrator, Integrator::Prefactored, "implicit, prefactored")
                        .on_hover_text("backward Euler with the rest tangent factorised once: one solve per step")
                        .changed();
                changed |= ui
                    .selectable_value(&mut self.ui.integrator, Integrator::Implicit, "implicit, full tangent")
                    .on_hover_text("backward Euler refactorising the current tangent every step")
                    .changed();
            });
            let mut dt_ms = self.ui.dt * 1e3;
            if ui.add(egui::Slider::new(&mut dt_ms, 0.01..=5.0).logarithmic(true).text("dt (ms)")).changed() {
                self.ui.dt = dt_ms * 1e-3;
                changed = true;
            }
            let limit = self.ui.dt_limit;
            ui.label(format!("explicit stability limit ~ {:.3} ms", limit * 1e3));
            if ui.button("auto (explicit when safe)").clicked() {
                self.ui.integrator = Simulation::integrator_for(self.ui.dt, limit);
                changed = true;
            }
            // Never leave the explicit integrator running where it would be unstable.
            if changed && self.ui.integrator == Integrator::Symplectic && self.ui.dt > 0.9 * limit {
                self.ui.integrator = Integrator::Prefactored;
                self.ui.note = Some(format!(
                    "dt = {:.3} ms is above 0.9 x the explicit limit ({:.3} ms): switched to prefactored implicit Euler",
                    self.ui.dt * 1e3,
                    limit * 1e3
                ));
            }
            if changed {
                self.physics.send(Command::SetIntegrator(self.ui.integrator, self.ui.dt));
            }
            if ui.button("Reset to rest").clicked() {
                self.physics.send(Command::Reset);
                self.ui.force_depth.clear();
            }
        });
        egui::CollapsingHeader::new("Tools").default_open(true).show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.selectable_value(&mut self.ui.tool, ToolKind::Drag, "drag");
                ui.selectable_value(&mut self.ui.tool, ToolKind::Probe, "probe");
                ui.selectable_value(&mut self.ui.tool, ToolKind::Orbit, "camera only");
            });
            ui.label("Left mouse: the tool; right mouse: rotate; wheel: zoom.");
            if self.ui.tool == ToolKind::Probe {
                ui.add(egui::Slider::new(&mut self.ui.probe_radius_mm, 2.0..=30.0).text("probe radius (mm)"));
            }
            let f = self.latest.tool_force;
            ui.label(format!("force on tool: |F| = {:.4} N  ({:.4}, {:.4}, {:.4})", norm(f), f[0], f[1], f[2]));
            if self.ui.tool == ToolKind::Probe {
                Plot::new("force_depth").height(130.0).x_axis_label("depth (mm)").y_axis_label("force (N)").show(
                    ui,
                    |p| {
                        p.line(Line::new("force vs depth", PlotPoints::from(self.ui.force_depth.clone())));
                    },
                );
            }
            ui.separator();
            ui.label("Paper's load case (clamped face, force on the opposite face):");
            ui.horizontal(|ui| {
                for a in 1..=3 {
                    ui.selectable_value(&mut self.ui.case_axis, a, format!("axis {a}"));
                }
            });
            ui.horizontal(|ui| {
                for f in FORCES_N {
                    ui.selectable_value(&mut self.ui.case_force, f, format!("{f} N"));
                }
            });
            ui.horizontal(|ui| {
                if ui.button("Apply case").clicked() {
                    self.apply_case();
                }
                if ui.button("Free cube").clicked() {
                    self.ui.case_active = None;
                    self.ui.fem_answer = None;
                    self.physics.send(Command::ApplyCase(Some(bottom_clamp(&self.grid))));
                }
            });
            if let (Some(case), Some(fem)) = (&self.ui.case_active, &self.ui.fem_answer) {
                let (avg, max) = error_vs_fem(&self.latest.positions, &self.rest, fem);
                let h = self.grid.h();
                ui.label(format!(
                    "{}: MSM vs FEM now: average {:.3} % of h, max {:.3} % of h",
                    case.id,
                    100.0 * avg / h,
                    100.0 * max / h
                ));
            }
        });
        egui::CollapsingHeader::new("View").default_open(true).show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.selectable_value(&mut self.ui.colour, ColourMode::None, "plain");
                ui.selectable_value(&mut self.ui.colour, ColourMode::Displacement, "displacement");
                ui.selectable_value(&mut self.ui.colour, ColourMode::Error, "error vs FEM");
            });
            ui.checkbox(&mut self.ui.show_springs, "springs");
            ui.checkbox(&mut self.ui.show_nodes, "nodes");
            ui.checkbox(&mut self.ui.show_fixed, "fixed nodes");
            if ui.button("Reset camera").clicked() {
                self.camera = OrbitCamera::default();
            }
        });
        egui::CollapsingHeader::new("Speed vs accuracy").default_open(false).show(ui, |ui| {
            let ctx = self.egui.clone();
            let object = if self.ui.object == "file" { self.ui.material.name.clone() } else { self.ui.object.clone() };
            self.ui.study.ui(ui, &object, move || ctx.request_repaint());
        });
        egui::CollapsingHeader::new("Calibration (GA+SA)").default_open(true).show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.selectable_value(&mut self.ui.calib_method, Method::Hybrid, "hybrid");
                ui.selectable_value(&mut self.ui.calib_method, Method::Ga, "GA");
                ui.selectable_value(&mut self.ui.calib_method, Method::Sa, "SA");
            });
            ui.horizontal(|ui| {
                ui.label("seed");
                ui.add(egui::DragValue::new(&mut self.ui.calib_seed));
                ui.label("population");
                ui.add(egui::DragValue::new(&mut self.ui.calib_population).range(2..=500));
                ui.label("generations");
                ui.add(egui::DragValue::new(&mut self.ui.calib_generations).range(1..=1000));
            });
            ui.horizontal(|ui| {
                if ui.button("Calibrate").clicked() {
                    if self.ui.job.is_some() {
                        self.ui.note = Some("a calibration is already running: cancel it first".into());
                    } else {
                        let settings = Settings {
                            method: self.ui.calib_method,
                            seed: self.ui.calib_seed,
                            population: self.ui.calib_population,
                            generations: self.ui.calib_generations,
                            ..Settings::default()
                        };
                        let ctx = self.egui.clone();
                        match Job::start(self.ui.material.clone(), self.ui.topology, settings, move || {
                            ctx.request_repaint()
                        }) {
                            Ok(j) => {
                                self.ui.job = Some(j);
                                self.ui.history.clear();
                                self.ui.result = None;
                                self.ui.note = None;
                            }
                            Err(e) => self.ui.note = Some(format!("cannot start the calibration: {e}")),
                        }
                    }
                }
                if ui.add_enabled(self.ui.job.is_some(), egui::Button::new("Cancel")).clicked()
                    && let Some(j) = &self.ui.job
                {
                    j.cancel();
                }
                if ui.add_enabled(self.ui.result.is_some(), egui::Button::new("Apply")).clicked()
                    && let Some(p) = self.ui.result
                {
                    self.ui.params = p;
                    self.send_params();
                }
            });
            if let Some(j) = &self.ui.job {
                let done = self.ui.history.last().map_or(0, |s| s.generation);
                ui.add(egui::ProgressBar::new(done as f32 / j.generations.max(1) as f32).show_percentage());
            }
            if let Some(p) = &self.ui.result {
                ui.label(format!("result: k = ({:.1}, {:.1}, {:.1}), d = {:.3}", p.k1, p.k2, p.k3, p.d));
            }
            if !self.ui.history.is_empty() {
                let pts = |f: &dyn Fn(&GenerationStats) -> f64| -> PlotPoints<'static> {
                    PlotPoints::from(self.ui.history.iter().map(|s| [s.generation as f64, f(s)]).collect::<Vec<_>>())
                };
                Plot::new("best").height(110.0).x_axis_label("generation").y_axis_label("best cost (m)").show(
                    ui,
                    |p| {
                        p.line(Line::new("best cost", pts(&|s| s.best_cost)));
                    },
                );
                Plot::new("fitness").height(110.0).x_axis_label("generation").y_axis_label("fitness (1/m)").show(
                    ui,
                    |p| {
                        p.line(Line::new("mean fitness", pts(&|s| s.mean_fitness)));
                        p.line(Line::new("std of fitness", pts(&|s| s.std_fitness)));
                    },
                );
            }
        });
    }

    fn poll_background(&mut self) {
        if let Some(job) = &self.ui.job {
            let mut ended = false;
            // Read before polling: a thread that had finished has its last message queued.
            let finished = job.finished();
            for msg in job.poll() {
                ended |= matches!(msg, Progress::Done(_));
                match msg {
                    Progress::Generation(s) => self.ui.history.push(s),
                    Progress::Done(Ok(r)) => {
                        self.ui.note = Some(format!(
                            "calibration {}: cost {:.4e} m in {:.1} s ({} evaluations){}",
                            if r.cancelled { "cancelled" } else { "done" },
                            r.cost,
                            r.wall_s,
                            r.evaluations,
                            if r.cancelled { "; best so far kept" } else { "" }
                        ));
                        self.ui.result = Some(r.params);
                    }
                    Progress::Done(Err(e)) => self.ui.note = Some(format!("calibration failed: {e}")),
                }
            }
            if !ended && finished {
                // The thread ended without a result (it panicked): free the slot and say so.
                self.ui.note = Some("the calibration stopped unexpectedly; no result".into());
                ended = true;
            }
            if ended {
                self.ui.job = None;
            }
        }
        if let Some(rx) = &self.ui.fem_rx
            && let Ok(r) = rx.try_recv()
        {
            match r {
                Ok(u) => self.ui.fem_answer = Some(u),
                Err(e) => self.ui.note = Some(format!("FEM solve failed: {e}")),
            }
            self.ui.fem_rx = None;
        }
    }

    /// Mouse on the 3D view: orbit, drag or probe.
    fn view_input(&mut self, response: &egui::Response, ctx: &egui::Context) {
        let rect = response.rect;
        let aspect = rect.width() / rect.height().max(1.0);
        let ndc = |p: egui::Pos2| {
            [2.0 * (p.x - rect.left()) / rect.width() - 1.0, 1.0 - 2.0 * (p.y - rect.top()) / rect.height()]
        };
        if response.hovered() {
            let scroll = ctx.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.camera.zoom(scroll / 50.0);
            }
        }
        if response.dragged_by(egui::PointerButton::Secondary)
            || (response.dragged_by(egui::PointerButton::Primary) && self.ui.tool == ToolKind::Orbit)
        {
            let d = response.drag_delta();
            self.camera.rotate(d.x, d.y);
            self.gesture = Gesture::Orbit;
        }
        if response.drag_started_by(egui::PointerButton::Primary)
            && self.ui.tool != ToolKind::Orbit
            && let Some(pos) = response.interact_pointer_pos()
        {
            let (o, d) = self.camera.ray(ndc(pos), aspect);
            if let Some((hit, node)) = self.mesh.pick(o.to_array(), d.to_array()) {
                self.gesture = match self.ui.tool {
                    ToolKind::Drag => Gesture::Drag { node, plane_point: Vec3::from(self.latest.positions[node]) },
                    ToolKind::Probe => {
                        self.ui.force_depth.clear();
                        Gesture::Probe { contact: Vec3::from(hit), dir: d, start_y: pos.y }
                    }
                    ToolKind::Orbit => Gesture::None,
                };
            }
        }
        if response.dragged_by(egui::PointerButton::Primary)
            && let Some(pos) = response.interact_pointer_pos()
        {
            match self.gesture {
                Gesture::Drag { node, plane_point } => {
                    let (o, d) = self.camera.ray(ndc(pos), aspect);
                    let n = (self.camera.eye() - self.camera.target).normalize();
                    let denom = d.dot(n);
                    if denom.abs() > 1e-6 {
                        let t = (plane_point - o).dot(n) / denom;
                        let target = o + t * d;
                        self.send_tool(Tool::Drag { node, target: target.as_dvec3().to_array() });
                    }
                }
                Gesture::Probe { contact, dir, start_y } => {
                    let r = (self.ui.probe_radius_mm * 1e-3) as f32;
                    // 0.1 mm of indentation per pixel dragged downwards.
                    let depth = ((pos.y - start_y) * 1e-4).max(0.0);
                    let centre = contact - r * dir + depth * dir;
                    self.send_tool(Tool::Probe { centre: centre.as_dvec3().to_array(), radius: f64::from(r) });
                    let f = self.latest.tool_force;
                    let along = -(f[0] * f64::from(dir.x) + f[1] * f64::from(dir.y) + f[2] * f64::from(dir.z));
                    if self.ui.force_depth.last().is_none_or(|l| (l[0] - f64::from(depth) * 1e3).abs() > 0.05) {
                        self.ui.force_depth.push([f64::from(depth) * 1e3, along.max(0.0)]);
                    }
                }
                _ => {}
            }
        }
        if response.drag_stopped() {
            if matches!(self.gesture, Gesture::Drag { .. } | Gesture::Probe { .. }) {
                self.send_tool(Tool::None);
            }
            self.gesture = Gesture::None;
        }
    }

    fn update_scene(&mut self) {
        let n = self.grid.num_nodes();
        if self.latest.positions.len() != n {
            self.latest.positions.clone_from(&self.rest);
        }
        if self.latest.fixed.len() != n {
            self.latest.fixed = vec![false; n];
        }
        let pos = &self.latest.positions;
        let mut max = None;
        match self.ui.colour {
            ColourMode::None => self.scalar.fill(0.0),
            ColourMode::Displacement => {
                for (s, (p, r)) in self.scalar.iter_mut().zip(pos.iter().zip(&self.rest)) {
                    *s = Vec3::from(*p).distance(Vec3::from(*r));
                }
                max = Some(0.002f32.max(self.scalar.iter().copied().fold(0.0, f32::max)));
            }
            ColourMode::Error => match &self.ui.fem_answer {
                Some(fem) => {
                    for (i, s) in self.scalar.iter_mut().enumerate() {
                        let target =
                            Vec3::from(self.rest[i]) + Vec3::new(fem[i][0] as f32, fem[i][1] as f32, fem[i][2] as f32);
                        *s = Vec3::from(pos[i]).distance(target);
                    }
                }
                None => self.scalar.fill(0.0),
            },
        }
        let scale = normalise(&mut self.scalar, max);
        let _ = scale;
        self.mesh.update(pos, Some(&self.scalar));
        self.lines.clear();
        if self.ui.show_fixed {
            fixed_outline(&self.edges, pos, &self.latest.fixed, [0.2, 0.9, 0.3, 1.0], &mut self.lines);
        }
        if self.ui.show_nodes {
            for p in pos {
                for axis in 0..3 {
                    if self.lines.len() + 2 > self.lines.capacity() {
                        break;
                    }
                    let (mut a, mut b) = (*p, *p);
                    a[axis] -= 0.0015;
                    b[axis] += 0.0015;
                    self.lines.push(LineVertex { position: a, colour: [1.0, 1.0, 0.6, 0.9] });
                    self.lines.push(LineVertex { position: b, colour: [1.0, 1.0, 0.6, 0.9] });
                }
            }
        }
        if self.ui.show_springs {
            push_edges(&self.edges, pos, [0.9, 0.9, 0.9, 0.35], |_, _| true, &mut self.lines);
        }
    }

    fn frame(&mut self) -> anyhow::Result<()> {
        self.physics.latest(&mut self.latest);
        self.poll_background();
        let Some(gpu) = self.gpu.as_mut() else { return Ok(()) };
        let raw = gpu.egui_state.take_egui_input(&gpu.window);
        let ctx = self.egui.clone();
        let mut view_response = None;
        let full = ctx.run_ui(raw, |ui| {
            egui::Panel::left("panel").exact_size(380.0).show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.panel(ui));
            });
            egui::CentralPanel::default().frame(egui::Frame::NONE).show(ui, |ui| {
                let rect = ui.max_rect();
                view_response = Some(ui.allocate_rect(rect, egui::Sense::click_and_drag()));
                if self.ui.colour != ColourMode::None {
                    legend(ui, rect, self.ui.colour, &self.scalar_range());
                }
            });
        });
        if let Some(r) = view_response {
            self.view_rect = r.rect;
            let sent = self.tools_sent;
            self.view_input(&r, &ctx);
            if self.tools_sent > sent {
                // Show this frame what the tool just did: wait (at most 3 ms, about 3 physics
                // ticks) for the physics thread to apply and step it, instead of a frame later.
                let deadline = Instant::now() + std::time::Duration::from_millis(3);
                while self.latest.tool_commands < self.tools_sent && Instant::now() < deadline {
                    std::thread::sleep(std::time::Duration::from_micros(200));
                    self.physics.latest(&mut self.latest);
                }
            }
        }
        self.update_scene();
        let Some(gpu) = self.gpu.as_mut() else { return Ok(()) };
        gpu.egui_state.handle_platform_output(&gpu.window, full.platform_output);
        let frame = match gpu.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                gpu.surface.configure(&gpu.device, &gpu.config);
                return Ok(());
            }
            _ => return Ok(()),
        };
        let view = frame.texture.create_view(&Default::default());
        let ppp = full.pixels_per_point;
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [gpu.config.width, gpu.config.height],
            pixels_per_point: ppp,
        };
        let jobs = ctx.tessellate(full.shapes, ppp);
        for (id, deltas) in &full.textures_delta.set {
            for delta in deltas {
                gpu.egui_renderer.update_texture(&gpu.device, &gpu.queue, *id, delta);
            }
        }
        let rect = self.view_rect;
        let (vx, vy) = ((rect.left() * ppp).max(0.0), (rect.top() * ppp).max(0.0));
        let vw = (rect.width() * ppp).min(gpu.config.width as f32 - vx).max(1.0);
        let vh = (rect.height() * ppp).min(gpu.config.height as f32 - vy).max(1.0);
        let style = SurfaceStyle {
            colour_map: self.ui.colour != ColourMode::None,
            encode_srgb: !gpu.config.format.is_srgb(),
            ..Default::default()
        };
        gpu.cube.prepare(&gpu.queue, self.camera.view_proj(vw / vh), style, &self.mesh, &self.lines);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        gpu.egui_renderer.update_buffers(&gpu.device, &gpu.queue, &mut encoder, &jobs, &screen);
        {
            // One pass for both: the cube in its viewport, then egui over the whole window (its
            // pipeline carries the same depth format and ignores depth).
            let mut pass = begin_cube_pass(&mut encoder, &view, &gpu.depth, crate::render::offscreen::BACKGROUND);
            pass.set_viewport(vx, vy, vw, vh, 0.0, 1.0);
            gpu.cube.draw(&mut pass);
            pass.set_viewport(0.0, 0.0, gpu.config.width as f32, gpu.config.height as f32, 0.0, 1.0);
            gpu.egui_renderer.render(&mut pass.forget_lifetime(), &jobs, &screen);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.window.pre_present_notify();
        gpu.queue.present(frame);
        // Tool commands whose effect this frame showed: their input-to-photon latency.
        let shown = self.latest.tool_commands;
        while let Some(&(seq, sent)) = self.pending.front() {
            if seq > shown {
                break;
            }
            let l = sent.elapsed().as_secs_f64();
            self.latency = (self.latency.0 + l, self.latency.1 + 1, self.latency.2.max(l));
            self.pending.pop_front();
        }
        for id in &full.textures_delta.free {
            gpu.egui_renderer.free_texture(id);
        }
        self.frames += 1;
        let (since, count) = self.frame_clock;
        if since.elapsed().as_secs_f64() >= 1.0 {
            self.fps = (self.frames - count) as f64 / since.elapsed().as_secs_f64();
            self.frame_clock = (Instant::now(), self.frames);
            if self.latency.1 > 0 {
                self.latency_shown = (self.latency.0 / self.latency.1 as f64, self.latency.2);
                self.latency = (0.0, 0, 0.0);
            }
            if self.max_frames.is_some() {
                eprintln!(
                    "fps {:.1}, physics {:.0} ticks/s, {:.1} us/step, tool latency mean {:.1} ms max {:.1} ms",
                    self.fps,
                    self.latest.ticks_per_s,
                    self.latest.step_us,
                    self.latency_shown.0 * 1e3,
                    self.latency_shown.1 * 1e3
                );
            }
        }
        Ok(())
    }

    fn scalar_range(&self) -> String {
        match self.ui.colour {
            ColourMode::None => String::new(),
            ColourMode::Displacement => {
                let m = self
                    .latest
                    .positions
                    .iter()
                    .zip(&self.rest)
                    .map(|(p, r)| Vec3::from(*p).distance(Vec3::from(*r)))
                    .fold(0.0f32, f32::max);
                format!("0 .. {:.2} mm", (m.max(0.002)) * 1e3)
            }
            ColourMode::Error if self.ui.fem_answer.is_none() => "apply a load case for the FEM answer".into(),
            ColourMode::Error => "0 .. max |x_msm - x_fem|".into(),
        }
    }
}

fn norm(f: [f64; 3]) -> f64 {
    (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt()
}

fn error_vs_fem(pos: &[[f32; 3]], rest: &[[f32; 3]], fem: &[[f64; 3]]) -> (f64, f64) {
    let mut sum = 0.0;
    let mut max = 0.0f64;
    for ((p, r), u) in pos.iter().zip(rest).zip(fem) {
        let d = (0..3).map(|c| (f64::from(p[c]) - f64::from(r[c]) - u[c]).powi(2)).sum::<f64>().sqrt();
        sum += d;
        max = max.max(d);
    }
    (sum / pos.len().max(1) as f64, max)
}

fn legend(ui: &mut egui::Ui, rect: egui::Rect, mode: ColourMode, range: &str) {
    let painter = ui.painter_at(rect);
    let x0 = rect.right() - 40.0;
    let (top, bottom) = (rect.top() + 40.0, rect.top() + 240.0);
    let steps = 32;
    for i in 0..steps {
        let t = i as f32 / steps as f32;
        let c = ramp(1.0 - t);
        let y = top + t * (bottom - top);
        painter.rect_filled(
            egui::Rect::from_min_max(egui::pos2(x0, y), egui::pos2(x0 + 16.0, y + (bottom - top) / steps as f32 + 1.0)),
            0.0,
            c,
        );
    }
    let title = match mode {
        ColourMode::Displacement => "displacement",
        ColourMode::Error => "MSM-FEM error",
        ColourMode::None => "",
    };
    let label = |pos: egui::Pos2, align: egui::Align2, text: &str, size: f32| {
        painter.text(pos, align, text, egui::FontId::proportional(size), egui::Color32::WHITE);
    };
    label(egui::pos2(x0 + 16.0, top - 22.0), egui::Align2::RIGHT_BOTTOM, title, 13.0);
    label(egui::pos2(x0 - 6.0, top), egui::Align2::RIGHT_TOP, "max", 12.0);
    label(egui::pos2(x0 - 6.0, bottom), egui::Align2::RIGHT_BOTTOM, "0", 12.0);
    label(egui::pos2(x0 + 16.0, bottom + 6.0), egui::Align2::RIGHT_TOP, range, 12.0);
}

/// The shader's colour ramp, for the legend (same stops as `surface.wgsl`).
fn ramp(t: f32) -> egui::Color32 {
    let stops = [[0.15, 0.20, 0.70], [0.10, 0.75, 0.85], [0.95, 0.90, 0.25], [0.85, 0.15, 0.10]];
    let s = t.clamp(0.0, 1.0) * 3.0;
    let i = (s.floor() as usize).min(2);
    let f = s - i as f32;
    let c: Vec<f32> = (0..3).map(|k| stops[i][k] * (1.0 - f) + stops[i + 1][k] * f).collect();
    egui::Color32::from_rgb((c[0] * 255.0) as u8, (c[1] * 255.0) as u8, (c[2] * 255.0) as u8)
}

fn log_adapter(info: &wgpu::AdapterInfo) {
    eprintln!("tissue-sim: rendering on {} ({:?}, {:?})", info.name, info.backend, info.device_type);
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gpu.is_none()
            && let Err(e) = self.init_gpu(event_loop)
        {
            self.error = Some(e);
            event_loop.exit();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        if let Some(g) = &mut self.gpu {
            let _ = g.egui_state.on_window_event(&g.window, &event);
        }
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => self.resize(size.width, size.height),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.frame() {
                    self.error = Some(e);
                    event_loop.exit();
                }
                if self.max_frames.is_some_and(|m| self.frames >= m) {
                    event_loop.exit();
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(g) = &self.gpu {
            g.window.request_redraw();
        }
    }
}

/// Opens the window and runs until it closes.
pub fn run(frames: Option<u64>, screenshot: Option<std::path::PathBuf>) -> anyhow::Result<()> {
    // winit's own message names its source files; say what is wrong in the user's terms.
    let event_loop = EventLoop::new().map_err(|_| {
        let display = std::env::var("DISPLAY").or_else(|_| std::env::var("WAYLAND_DISPLAY")).unwrap_or_default();
        anyhow::anyhow!(
            "cannot open the display {display:?}: no window system answers there (is an X server or Wayland \
             compositor running?); {}",
            super::HEADLESS_HINT
        )
    })?;
    let mut app = App::new(frames, screenshot)?;
    event_loop.run_app(&mut app).context("event loop failed")?;
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    if app.max_frames.is_some() {
        let p = &app.latest;
        let rate = if p.running_s > 0.0 { p.ticks_total as f64 / p.running_s } else { 0.0 };
        eprintln!(
            "viewer: {} frames; physics {} ticks and {} steps in {:.2} s ({rate:.0} ticks/s)",
            app.frames, p.ticks_total, p.steps_total, p.running_s
        );
    }
    if let Some(path) = app.screenshot.clone() {
        // The smoke test's screenshot: the same scene through the offscreen path.
        let headless = crate::render::offscreen::Headless::new()?;
        let (w, h) = (960, 540);
        let style = SurfaceStyle { colour_map: app.ui.colour != ColourMode::None, ..Default::default() };
        let rgba = headless.render((w, h), app.camera.view_proj(w as f32 / h as f32), style, &app.mesh, &app.lines)?;
        crate::io::write_atomic(&path, &crate::render::offscreen::encode_png(w, h, &rgba)?)?;
    }
    Ok(())
}
