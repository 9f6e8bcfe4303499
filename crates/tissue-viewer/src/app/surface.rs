//! The window and its wgpu surface: creation (adapter, device, format and present mode chosen
//! for the adapter), resize, frame acquisition with every surface error handled and logged, and
//! the one render pass that draws the cube in its viewport and egui over the window.

use std::sync::Arc;

use anyhow::Context as _;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

use crate::render::gpu::{CubeRenderer, LineVertex, SurfaceStyle, begin_cube_pass, depth_view};
use crate::render::mesh::SurfaceMesh;

/// The window, its surface and the renderers drawing into it.
pub struct Surface {
    /// The window.
    pub window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    /// The last frame was suboptimal: configure again after presenting.
    reconfigure: bool,
    device: wgpu::Device,
    queue: wgpu::Queue,
    config: wgpu::SurfaceConfiguration,
    depth: wgpu::TextureView,
    cube: CubeRenderer,
    egui_renderer: egui_wgpu::Renderer,
    /// egui's window integration.
    pub egui_state: egui_winit::State,
    /// The next frame drawn is read back ([`Surface::request_capture`]).
    capture: bool,
    /// The frame read back: width, height, RGBA8 rows as the window shows them.
    captured: Option<(u32, u32, Vec<u8>)>,
}

/// One frame of egui output to draw.
pub struct EguiFrame {
    /// Tessellated shapes.
    pub jobs: Vec<egui::ClippedPrimitive>,
    /// Texture changes.
    pub textures: egui::TexturesDelta,
    /// Points per pixel.
    pub pixels_per_point: f32,
}

/// The cube to draw: its viewport in egui points, camera and style.
pub struct CubeFrame<'a> {
    /// Where the 3D view is, egui points.
    pub rect: egui::Rect,
    /// View-projection for a viewport aspect (width / height).
    pub view_proj: &'a dyn Fn(f32) -> glam::Mat4,
    /// Colour map on or off.
    pub colour_map: bool,
    /// The surface mesh.
    pub mesh: &'a SurfaceMesh,
    /// Overlay lines, then `see_through` vertices of triangles drawn through the surface.
    pub lines: &'a [LineVertex],
    /// How many vertices at the end of `lines` are see-through triangles.
    pub see_through: usize,
}

impl Surface {
    /// Opens the window and sets up wgpu and egui for it.
    pub fn new(
        event_loop: &ActiveEventLoop,
        egui: &egui::Context,
        mesh: &SurfaceMesh,
        line_capacity: usize,
    ) -> anyhow::Result<Self> {
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
        let software = adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        let config = surface_config(&surface.get_capabilities(&adapter), software, window.inner_size());
        surface.configure(&device, &config);
        let depth = depth_view(&device, config.width, config.height);
        let cube = CubeRenderer::new(&device, config.format, mesh, line_capacity);
        // Dithering is a per-pixel cost a software rasteriser feels; it only hides banding.
        let options = egui_wgpu::RendererOptions {
            dithering: !software,
            depth_stencil_format: Some(crate::render::gpu::DEPTH_FORMAT),
            ..Default::default()
        };
        let egui_renderer = egui_wgpu::Renderer::new(&device, config.format, options);
        let egui_state = egui_winit::State::new(
            egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        let info = adapter.get_info();
        eprintln!("tissue-sim: rendering on {} ({:?}, {:?})", info.name, info.backend, info.device_type);
        if software {
            // Feathering (anti-aliased shape edges) adds thin triangles everywhere; text keeps its
            // anti-aliasing from the font atlas. About +15 % frame rate on lavapipe.
            egui.tessellation_options_mut(|o| o.feathering = false);
        }
        Ok(Self {
            window,
            surface,
            reconfigure: false,
            device,
            queue,
            config,
            depth,
            cube,
            egui_renderer,
            egui_state,
            capture: false,
            captured: None,
        })
    }

    /// Follows the window's new size.
    pub fn resize(&mut self, width: u32, height: u32) {
        self.config.width = width.max(1);
        self.config.height = height.max(1);
        self.surface.configure(&self.device, &self.config);
        self.depth = depth_view(&self.device, self.config.width, self.config.height);
    }

    /// The next frame's texture, or `None` (the frame is skipped) after handling whatever the
    /// surface reported: reconfigured when outdated or lost (and after presenting a suboptimal one), logged.
    fn acquire(&mut self) -> anyhow::Result<Option<wgpu::SurfaceTexture>> {
        match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) => Ok(Some(t)),
            wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
                // Draw this one; the surface is configured again once it is presented (never while
                // a frame is held).
                self.reconfigure = true;
                Ok(Some(t))
            }
            wgpu::CurrentSurfaceTexture::Timeout => {
                eprintln!("tissue-sim: surface timeout; frame skipped");
                Ok(None)
            }
            wgpu::CurrentSurfaceTexture::Occluded => Ok(None),
            wgpu::CurrentSurfaceTexture::Outdated => {
                eprintln!("tissue-sim: surface outdated; reconfigured");
                self.surface.configure(&self.device, &self.config);
                Ok(None)
            }
            wgpu::CurrentSurfaceTexture::Lost => {
                eprintln!("tissue-sim: surface lost; reconfigured");
                self.surface.configure(&self.device, &self.config);
                Ok(None)
            }
            other => {
                eprintln!("tissue-sim: cannot acquire a frame ({other:?}); frame skipped");
                Ok(None)
            }
        }
    }

    /// Reads the next frame drawn back, as the window shows it (the panel included), where the
    /// window's surface allows a copy from it ([`Surface::take_capture`]).
    pub fn request_capture(&mut self) {
        self.capture = true;
    }

    /// The frame read back since [`Surface::request_capture`]: width, height and RGBA8 rows;
    /// `None` where none was (the surface allows no copy, or no frame was drawn).
    pub fn take_capture(&mut self) -> Option<(u32, u32, Vec<u8>)> {
        self.captured.take()
    }

    /// Draws and presents one frame; `false` when it was skipped.
    pub fn draw(&mut self, cube: &CubeFrame<'_>, egui: EguiFrame) -> anyhow::Result<bool> {
        let Some(frame) = self.acquire()? else { return Ok(false) };
        let view = frame.texture.create_view(&Default::default());
        let ppp = egui.pixels_per_point;
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.config.width, self.config.height],
            pixels_per_point: ppp,
        };
        for (id, deltas) in &egui.textures.set {
            for delta in deltas {
                self.egui_renderer.update_texture(&self.device, &self.queue, *id, delta);
            }
        }
        let rect = cube.rect;
        let (vx, vy) = ((rect.left() * ppp).max(0.0), (rect.top() * ppp).max(0.0));
        let vw = (rect.width() * ppp).min(self.config.width as f32 - vx).max(1.0);
        let vh = (rect.height() * ppp).min(self.config.height as f32 - vy).max(1.0);
        let style = SurfaceStyle {
            colour_map: cube.colour_map,
            encode_srgb: !self.config.format.is_srgb(),
            ..Default::default()
        };
        self.cube.fit(&self.device, cube.mesh, cube.lines.len());
        self.cube.prepare(&self.queue, (cube.view_proj)(vw / vh), style, cube.mesh, cube.lines, cube.see_through);
        let mut encoder = self.device.create_command_encoder(&Default::default());
        self.egui_renderer.update_buffers(&self.device, &self.queue, &mut encoder, &egui.jobs, &screen);
        {
            // One pass for both: the cube in its viewport, then egui over the whole window (its
            // pipeline carries the same depth format and ignores depth).
            let mut pass = begin_cube_pass(&mut encoder, &view, &self.depth, crate::render::offscreen::BACKGROUND);
            pass.set_viewport(vx, vy, vw, vh, 0.0, 1.0);
            self.cube.draw(&mut pass);
            pass.set_viewport(0.0, 0.0, self.config.width as f32, self.config.height as f32, 0.0, 1.0);
            self.egui_renderer.render(&mut pass.forget_lifetime(), &egui.jobs, &screen);
        }
        if std::mem::take(&mut self.capture) && self.config.usage.contains(wgpu::TextureUsages::COPY_SRC) {
            let (w, h) = (self.config.width, self.config.height);
            let mut texels =
                crate::render::offscreen::read_back(&self.device, &self.queue, encoder, &frame.texture, w, h)?;
            let bgra =
                matches!(self.config.format, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb);
            for p in texels.chunks_exact_mut(4) {
                if bgra {
                    p.swap(0, 2);
                }
                // The window is opaque whatever the frame's alpha holds.
                p[3] = 255;
            }
            self.captured = Some((w, h, texels));
        } else {
            self.queue.submit([encoder.finish()]);
        }
        self.window.pre_present_notify();
        self.queue.present(frame);
        if std::mem::take(&mut self.reconfigure) {
            self.surface.configure(&self.device, &self.config);
        }
        for id in &egui.textures.free {
            self.egui_renderer.free_texture(id);
        }
        Ok(true)
    }
}

/// The surface configuration for an adapter: on a software adapter a non-sRGB target (sparing
/// egui a per-pixel gamma conversion, its largest cost there; the cube's shader then encodes
/// sRGB itself) and Immediate presentation (no display to tear); Mailbox where offered
/// otherwise, Fifo as the fallback.
fn surface_config(
    caps: &wgpu::SurfaceCapabilities,
    software: bool,
    size: winit::dpi::PhysicalSize<u32>,
) -> wgpu::SurfaceConfiguration {
    let format = caps.formats.iter().copied().find(|f| f.is_srgb() != software).unwrap_or(caps.formats[0]);
    let present_mode = if software && caps.present_modes.contains(&wgpu::PresentMode::Immediate) {
        wgpu::PresentMode::Immediate
    } else if caps.present_modes.contains(&wgpu::PresentMode::Mailbox) {
        wgpu::PresentMode::Mailbox
    } else {
        wgpu::PresentMode::Fifo
    };
    // A copy from the frame where the surface allows it: `view --screenshot` saves the window.
    let copy = caps.usages & wgpu::TextureUsages::COPY_SRC;
    wgpu::SurfaceConfiguration {
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | copy,
        format,
        width: size.width.max(1),
        height: size.height.max(1),
        present_mode,
        desired_maximum_frame_latency: 2,
        alpha_mode: caps.alpha_modes[0],
        view_formats: vec![],
        color_space: Default::default(),
    }
}
