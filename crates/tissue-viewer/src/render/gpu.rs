//! The wgpu renderer of the cube: its shaded surface and line overlays, drawn into any render
//! pass (a window's surface or an offscreen texture). Buffers are sized once; a frame only writes
//! into them.

use glam::Mat4;
use wgpu::util::DeviceExt as _;

use super::mesh::{SurfaceMesh, SurfaceVertex};

/// Depth buffer format.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// A line-overlay vertex.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LineVertex {
    /// Position, metres.
    pub position: [f32; 3],
    /// RGBA colour.
    pub colour: [f32; 4],
}

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    light_dir: [f32; 4],
    mode: [f32; 4],
    base_colour: [f32; 4],
    ramp: [[f32; 4]; 4],
}

/// The colour map's stops, blue -> cyan -> yellow -> red at 0, 1/3, 2/3 and 1 (linear RGB): the
/// one home of the ramp the surface shader draws (through the globals) and the legends show.
pub const RAMP: [[f32; 3]; 4] = [[0.15, 0.20, 0.70], [0.10, 0.75, 0.85], [0.95, 0.90, 0.25], [0.85, 0.15, 0.10]];

/// The colour map at `t` in [0, 1] (clamped), linear RGB, as the surface shader mixes it.
pub fn ramp(t: f32) -> [f32; 3] {
    let s = t.clamp(0.0, 1.0) * 3.0;
    let i = (s.floor() as usize).min(2);
    let f = s - i as f32;
    std::array::from_fn(|k| RAMP[i][k] * (1.0 - f) + RAMP[i + 1][k] * f)
}

/// The colour map at `t` as 8-bit sRGB, as a lit face facing the light shows it.
pub fn ramp_srgb8(t: f32) -> [u8; 3] {
    ramp(t).map(|c| (255.0 * c.clamp(0.0, 1.0).powf(1.0 / 2.2)).round() as u8)
}

/// How the surface is coloured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceStyle {
    /// Use the per-vertex scalar through the colour map.
    pub colour_map: bool,
    /// Colour when the map is off (linear RGB).
    pub base_colour: [f32; 3],
    /// The target is not sRGB: encode colours to sRGB in the shader.
    pub encode_srgb: bool,
}

impl Default for SurfaceStyle {
    fn default() -> Self {
        Self { colour_map: false, base_colour: [0.85, 0.45, 0.42], encode_srgb: false }
    }
}

/// GPU resources of the cube view.
#[derive(Debug)]
pub struct CubeRenderer {
    surface_pipeline: wgpu::RenderPipeline,
    line_pipeline: wgpu::RenderPipeline,
    see_through_pipeline: wgpu::RenderPipeline,
    globals: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    lines: wgpu::Buffer,
    line_capacity: u64,
    line_count: u32,
    see_through_count: u32,
}

fn shader(device: &wgpu::Device, label: &str, source: &'static str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(std::borrow::Cow::Borrowed(source)),
    })
}

/// The WGSL sources, compiled into the binary: the shared uniforms, then each shader.
pub const SURFACE_WGSL: &str =
    concat!(include_str!("../../../../shaders/globals.wgsl"), include_str!("../../../../shaders/surface.wgsl"));
/// The WGSL sources, compiled into the binary: the shared uniforms, then each shader.
pub const LINES_WGSL: &str =
    concat!(include_str!("../../../../shaders/globals.wgsl"), include_str!("../../../../shaders/lines.wgsl"));

impl CubeRenderer {
    /// Creates pipelines for colour target `format` and buffers for `mesh` and up to
    /// `max_line_vertices` overlay vertices.
    #[allow(clippy::too_many_lines, reason = "wgpu descriptors: two pipelines and their buffers")]
    pub fn new(
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
        mesh: &SurfaceMesh,
        max_line_vertices: usize,
    ) -> Self {
        let surface_shader = shader(device, "surface.wgsl", SURFACE_WGSL);
        let line_shader = shader(device, "lines.wgsl", LINES_WGSL);
        let globals = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("globals"),
            size: std::mem::size_of::<Globals>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("globals"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("globals"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: globals.as_entire_binding() }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("cube"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let depth = |write: bool, compare: wgpu::CompareFunction| {
            Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(write),
                depth_compare: Some(compare),
                stencil: Default::default(),
                bias: Default::default(),
            })
        };
        // The surface is opaque (no blending: cheaper on software rasterisers); overlays blend.
        let opaque = [Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })];
        let target = [Some(wgpu::ColorTargetState {
            format,
            blend: Some(wgpu::BlendState::ALPHA_BLENDING),
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let surface_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32];
        let surface_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("surface"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &surface_shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<SurfaceVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &surface_attrs,
                })],
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: depth(true, wgpu::CompareFunction::LessEqual),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &surface_shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &opaque,
            }),
            multiview_mask: None,
            cache: None,
        });
        let line_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4];
        // The overlays: coloured vertices through the lines' shader, blended.
        let overlay = |label: &str, topology: wgpu::PrimitiveTopology, depth_stencil| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &line_shader,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<LineVertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &line_attrs,
                    })],
                },
                primitive: wgpu::PrimitiveState { topology, ..Default::default() },
                depth_stencil,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &line_shader,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &target,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let line_pipeline =
            overlay("lines", wgpu::PrimitiveTopology::LineList, depth(false, wgpu::CompareFunction::LessEqual));
        // Translucent triangles seen through the surface (a revealed lump): no depth test and no
        // depth written.
        let through = depth(false, wgpu::CompareFunction::Always);
        let see_through_pipeline = overlay("see-through", wgpu::PrimitiveTopology::TriangleList, through);
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("surface vertices"),
            contents: bytemuck::cast_slice(&mesh.vertices),
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        });
        let indices = index_buffer(device, mesh);
        let line_capacity = max_line_vertices.max(2) as u64;
        let lines = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("line vertices"),
            size: line_capacity * std::mem::size_of::<LineVertex>() as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            surface_pipeline,
            line_pipeline,
            see_through_pipeline,
            globals,
            bind_group,
            vertices,
            indices,
            index_count: 0,
            lines,
            line_capacity,
            line_count: 0,
            see_through_count: 0,
        }
    }

    /// Makes the surface and line buffers fit `mesh` (another grid) and `max_line_vertices`,
    /// creating them again where they do not.
    pub fn fit(&mut self, device: &wgpu::Device, mesh: &SurfaceMesh, max_line_vertices: usize) {
        let vertex_bytes = std::mem::size_of_val(mesh.vertices.as_slice()) as u64;
        let index_bytes = (mesh.index_capacity() * std::mem::size_of::<u32>()) as u64;
        if vertex_bytes != self.vertices.size() || index_bytes != self.indices.size() {
            self.vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("surface vertices"),
                contents: bytemuck::cast_slice(&mesh.vertices),
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            });
            self.indices = index_buffer(device, mesh);
        }
        if max_line_vertices as u64 > self.line_capacity {
            self.line_capacity = max_line_vertices as u64;
            self.lines = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("line vertices"),
                size: self.line_capacity * std::mem::size_of::<LineVertex>() as u64,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
        }
    }

    /// Uploads this frame's camera, surface and overlays (overlays beyond capacity are dropped);
    /// the last `see_through` vertices of `lines` are triangles drawn through the surface.
    pub fn prepare(
        &mut self,
        queue: &wgpu::Queue,
        view_proj: Mat4,
        style: SurfaceStyle,
        mesh: &SurfaceMesh,
        lines: &[LineVertex],
        see_through: usize,
    ) {
        let g = Globals {
            view_proj: view_proj.to_cols_array_2d(),
            light_dir: [0.4, -0.5, 0.8, 0.0],
            mode: [if style.colour_map { 1.0 } else { 0.0 }, 1.0, if style.encode_srgb { 1.0 } else { 0.0 }, 0.0],
            base_colour: [style.base_colour[0], style.base_colour[1], style.base_colour[2], 1.0],
            ramp: RAMP.map(|c| [c[0], c[1], c[2], 0.0]),
        };
        queue.write_buffer(&self.globals, 0, bytemuck::bytes_of(&g));
        queue.write_buffer(&self.vertices, 0, bytemuck::cast_slice(&mesh.vertices));
        // The triangles drawn this frame (a face's whole lattice only where the dent is).
        let drawn = mesh.indices.len().min(mesh.index_capacity());
        queue.write_buffer(&self.indices, 0, bytemuck::cast_slice(&mesh.indices[..drawn]));
        self.index_count = drawn as u32;
        let n = (lines.len() as u64).min(self.line_capacity) as usize;
        if n > 0 {
            queue.write_buffer(&self.lines, 0, bytemuck::cast_slice(&lines[..n]));
        }
        // The see-through triangles come last; where the buffer cut them, none are drawn.
        let see_through = if n == lines.len() { see_through.min(n) } else { 0 };
        self.line_count = (n - see_through) as u32;
        self.see_through_count = see_through as u32;
    }

    /// Records the draw calls into a pass that has a colour target of the pipeline's format and a
    /// [`DEPTH_FORMAT`] depth attachment.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_pipeline(&self.surface_pipeline);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
        if self.line_count > 0 {
            pass.set_pipeline(&self.line_pipeline);
            pass.set_vertex_buffer(0, self.lines.slice(..));
            pass.draw(0..self.line_count, 0..1);
        }
        if self.see_through_count > 0 {
            pass.set_pipeline(&self.see_through_pipeline);
            pass.set_vertex_buffer(0, self.lines.slice(..));
            pass.draw(self.line_count..self.line_count + self.see_through_count, 0..1);
        }
    }
}

/// An index buffer for the most triangles `mesh` draws in a frame, written each frame.
fn index_buffer(device: &wgpu::Device, mesh: &SurfaceMesh) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("surface indices"),
        size: (mesh.index_capacity().max(3) * std::mem::size_of::<u32>()) as u64,
        usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Begins the cube's render pass: clears `view` to `clear` and `depth` to the far plane.
pub fn begin_cube_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    view: &wgpu::TextureView,
    depth: &wgpu::TextureView,
    clear: wgpu::Color,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("cube"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: wgpu::LoadOp::Clear(clear), store: wgpu::StoreOp::Store },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// A depth texture view of a given size.
pub fn depth_view(device: &wgpu::Device, width: u32, height: u32) -> wgpu::TextureView {
    device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("depth"),
            size: wgpu::Extent3d { width: width.max(1), height: height.max(1), depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        })
        .create_view(&Default::default())
}
