//! Opening a wgpu adapter that runs compute shaders (any backend, software Vulkan included).

/// What can go wrong on the GPU, each in one line.
#[derive(Debug, Clone, thiserror::Error)]
pub enum GpuError {
    /// No adapter, or none with compute shaders.
    #[error("no GPU adapter that computes ({0}); compute \"cpu\" runs everywhere")]
    NoAdapter(String),
    /// The device could not be created.
    #[error("cannot open the GPU device: {0}")]
    Device(String),
    /// The model has no GPU step, or the request does not fit the device.
    #[error("{0}")]
    Unsupported(String),
    /// Reading the state back failed.
    #[error("cannot read the GPU's state back: {0}")]
    Readback(String),
}

/// A device and queue that compute.
#[derive(Debug, Clone)]
pub struct ComputeDevice {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What it runs on.
    pub info: wgpu::AdapterInfo,
}

impl ComputeDevice {
    /// Opens the default adapter (backends from `WGPU_BACKEND`, else all), high performance
    /// first, with the largest and the most storage buffers it allows.
    pub fn open() -> Result<Self, GpuError> {
        let adapter = default_adapter().map_err(GpuError::NoAdapter)?;
        let info = adapter.get_info();
        if !adapter.get_downlevel_capabilities().flags.contains(wgpu::DownlevelFlags::COMPUTE_SHADERS) {
            return Err(GpuError::NoAdapter(format!("{} has no compute shaders", info.name)));
        }
        let supported = adapter.limits();
        let required_limits = wgpu::Limits {
            max_storage_buffer_binding_size: supported.max_storage_buffer_binding_size,
            max_buffer_size: supported.max_buffer_size,
            // The step binds `explicit::STORAGE_BUFFERS`.
            max_storage_buffers_per_shader_stage: supported.max_storage_buffers_per_shader_stage,
            ..wgpu::Limits::downlevel_defaults()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("tissue-sim compute"),
            required_limits,
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(one_line(&e.to_string())))?;
        // Errors outside an error scope are reported, not panicked on (wgpu's default).
        device.on_uncaptured_error(std::sync::Arc::new(|e: wgpu::Error| {
            eprintln!("GPU error: {}", one_line(&e.to_string()));
        }));
        Ok(Self { device, queue, info })
    }

    /// The adapter in words: name and backend.
    pub fn describe(&self) -> String {
        format!("{} ({:?}, {:?})", self.info.name, self.info.backend, self.info.device_type)
    }
}

/// The default adapter without a window (backends from `WGPU_BACKEND`, else all), high
/// performance first, or why there is none (one line): the compute step's and the offscreen
/// renderer's.
pub fn default_adapter() -> Result<wgpu::Adapter, String> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        ..Default::default()
    }))
    .map_err(|e| one_line(&e.to_string()))
}

/// `text` on one line (adapter errors may span several).
pub(crate) fn one_line(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}
