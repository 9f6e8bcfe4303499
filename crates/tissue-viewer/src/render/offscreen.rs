//! Offscreen rendering through the same [`CubeRenderer`]: any wgpu adapter, software Vulkan
//! (Mesa lavapipe) included; no window or display needed.

use glam::Mat4;

use super::gpu::{CubeRenderer, LineVertex, SurfaceStyle, begin_cube_pass, depth_view};
use super::mesh::SurfaceMesh;

/// Colour format of offscreen images.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// Errors of offscreen rendering.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// No GPU adapter (not even a software one) is available.
    #[error("no wgpu adapter available ({0}); install Mesa's lavapipe (mesa-vulkan-drivers) for software Vulkan")]
    NoAdapter(String),
    /// The device could not be created.
    #[error("cannot create a wgpu device: {0}")]
    Device(String),
    /// Reading the image back failed.
    #[error("cannot read the rendered image back: {0}")]
    Readback(String),
    /// The requested size is not renderable.
    #[error("image size {0} x {1} is out of range (1..={2} on this adapter)")]
    Size(u32, u32, u32),
}

/// A headless device.
#[derive(Debug)]
pub struct Headless {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What it runs on.
    pub adapter_info: wgpu::AdapterInfo,
}

impl Headless {
    /// Opens the default adapter (backends from `WGPU_BACKEND`, else all).
    pub fn new() -> Result<Self, RenderError> {
        let adapter = crate::gpu::device::default_adapter().map_err(RenderError::NoAdapter)?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("tissue-sim offscreen"),
            required_limits: wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits()),
            ..Default::default()
        }))
        .map_err(|e| RenderError::Device(e.to_string()))?;
        Ok(Self { device, queue, adapter_info: adapter.get_info() })
    }

    /// Renders one frame of the cube and returns it as tightly packed RGBA8 (sRGB) rows.
    pub fn render(
        &self,
        size: (u32, u32),
        view_proj: Mat4,
        style: SurfaceStyle,
        mesh: &SurfaceMesh,
        lines: &[LineVertex],
    ) -> Result<Vec<u8>, RenderError> {
        let (width, height) = size;
        let max = self.device.limits().max_texture_dimension_2d.min(8192);
        if !(1..=max).contains(&width) || !(1..=max).contains(&height) {
            return Err(RenderError::Size(width, height, max));
        }
        let device = &self.device;
        let mut renderer = CubeRenderer::new(device, FORMAT, mesh, lines.len());
        renderer.prepare(&self.queue, view_proj, style, mesh, lines, 0);
        let target = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("offscreen"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = target.create_view(&Default::default());
        let depth = depth_view(device, width, height);
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = begin_cube_pass(&mut encoder, &view, &depth, BACKGROUND);
            renderer.draw(&mut pass);
        }
        read_back(device, &self.queue, encoder, &target, width, height)
    }
}

/// Submits `encoder` with a copy of `texture` (`width` x `height`, four bytes a texel, made with
/// `COPY_SRC`) after its commands, and returns the texels as tightly packed rows.
pub fn read_back(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    mut encoder: wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    width: u32,
    height: u32,
) -> Result<Vec<u8>, RenderError> {
    let row = (4 * width).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: u64::from(row) * u64::from(height),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(height) },
        },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
    queue.submit([encoder.finish()]);
    let slice = readback.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| RenderError::Readback(e.to_string()))?;
    rx.recv().map_err(|e| RenderError::Readback(e.to_string()))?.map_err(|e| RenderError::Readback(e.to_string()))?;
    let data = slice.get_mapped_range().map_err(|e| RenderError::Readback(e.to_string()))?;
    let mut pixels = Vec::with_capacity((4 * width * height) as usize);
    for r in 0..height as usize {
        let start = r * row as usize;
        pixels.extend_from_slice(&data[start..start + 4 * width as usize]);
    }
    drop(data);
    readback.unmap();
    Ok(pixels)
}

/// Background colour of the 3D view.
pub const BACKGROUND: wgpu::Color = wgpu::Color { r: 0.06, g: 0.07, b: 0.09, a: 1.0 };

/// Encodes RGBA8 rows as PNG bytes.
pub fn encode_png(width: u32, height: u32, rgba: &[u8]) -> Result<Vec<u8>, image::ImageError> {
    let mut out = std::io::Cursor::new(Vec::new());
    image::write_buffer_with_format(
        &mut out,
        rgba,
        width,
        height,
        image::ExtendedColorType::Rgba8,
        image::ImageFormat::Png,
    )?;
    Ok(out.into_inner())
}
