//! The explicit step's kernel: a model's [`ExplicitForm`] in GPU buffers, its state in and out,
//! steps recorded until something is written or read (then submitted together), and the guard's
//! figures of the last step (a few bytes a workgroup, read without the state).
//!
//! The state on the GPU is the displacement from rest and the velocity, in f32 (the displacement
//! rather than the position keeps f32's relative precision on what changes: a spring's length is
//! its rest vector plus a difference of displacements).

use super::device::{ComputeDevice, GpuError};
use crate::sim::explicit_form::{ExplicitForm, ForceForm};
use wgpu::util::DeviceExt as _;

/// The shader, as built into the program.
pub const EXPLICIT_STEP_WGSL: &str = include_str!("../../../shaders/explicit_step.wgsl");

/// Threads per workgroup (the shader's `@workgroup_size`).
const WORKGROUP: u32 = 64;
/// Spring families a lattice may have (the hex lattice has 13).
const MAX_FAMILIES: usize = 16;
/// Storage buffers the step binds: the state before and after it, the load, the coefficients
/// and the operator.
pub const STORAGE_BUFFERS: u32 = 5;
/// Workgroups one dispatch may have along x (WebGPU's minimum limit).
const MAX_GROUPS: u32 = 65_535;

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FamilyGpu {
    offset: u32,
    len: u32,
    start: u32,
    rest_length: f32,
    rest: [f32; 4],
}

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ParamsGpu {
    nn: u32,
    n: u32,
    families: u32,
    dt: f32,
    family: [FamilyGpu; MAX_FAMILIES],
    /// The dragging spring: target displacement (xyz) and stiffness over the node's mass (w).
    drag: [f32; 4],
    /// The held node (`NO_DRAG`: none).
    drag_node: u32,
    /// The spring's damping over the node's mass, 1/s.
    drag_damping: f32,
    pad: [u32; 2],
}

/// `drag_node` where nothing is dragged.
const NO_DRAG: u32 = u32::MAX;

/// The dragging spring's split step on the GPU: the held node, its target as a displacement
/// from rest, m, and the spring's stiffness and damping over the node's mass (1/s^2, 1/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpuDrag {
    /// The held node.
    pub node: usize,
    /// Where the spring pulls it, as a displacement from its rest position, m.
    pub target_displacement: [f64; 3],
    /// Stiffness over the node's mass, 1/s^2.
    pub stiffness_per_mass: f64,
    /// Damping over the node's mass, 1/s.
    pub damping_per_mass: f64,
}

/// A model's explicit step on the GPU.
#[derive(Debug)]
pub struct ExplicitKernel {
    gpu: ComputeDevice,
    nn: usize,
    params: ParamsGpu,
    params_buffer: wgpu::Buffer,
    /// The state before and after a step (then room for the guard's figures, two per
    /// workgroup, which [`ExplicitKernel::read_health`] writes after the state it does not
    /// hold); `state[current]` holds it between steps.
    state: [wgpu::Buffer; 2],
    current: usize,
    f_ext: wgpu::Buffer,
    coef: wgpu::Buffer,
    staging: wgpu::Buffer,
    health_staging: wgpu::Buffer,
    /// Group `i` steps `state[i]` into `state[1 - i]`.
    bind_groups: [wgpu::BindGroup; 2],
    step: wgpu::ComputePipeline,
    /// The guard's figures of a state (the shader's `guard_figures`).
    guard: wgpu::ComputePipeline,
    /// The dragging spring's split step (the shader's `drag_step`).
    drag: wgpu::ComputePipeline,
    /// Whether `params` changed since they were last written.
    params_stale: bool,
    /// Steps recorded and not yet submitted: they go with the next write or read (a write
    /// reaches the GPU before any command submitted after it, so the steps before it go first).
    pending: Option<wgpu::CommandEncoder>,
    /// Host copies: the state (`u` then `v`, component-major) and the load.
    host_state: Vec<f32>,
    host_load: Vec<f32>,
    host_health: Vec<f32>,
    /// Set by the readback's callback.
    mapped: std::sync::Arc<std::sync::atomic::AtomicU8>,
}

fn groups(threads: usize) -> u32 {
    (threads as u32).div_ceil(WORKGROUP)
}

fn storage(device: &wgpu::Device, label: &str, data: &[f32], extra: wgpu::BufferUsages) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(data),
        usage: wgpu::BufferUsages::STORAGE | extra,
    })
}

/// The coefficients buffer: `1 / m`, `c / m`, then free per component.
fn coefficients(form: &ExplicitForm) -> Vec<f32> {
    let mut coef: Vec<f32> = form.inv_mass.iter().chain(&form.damping_rate).map(|&v| v as f32).collect();
    for c in 0..3 {
        coef.extend(form.free[c].iter().map(|&v| v as f32));
    }
    coef
}

/// The parameters and the operator buffer of a form.
fn operator(form: &ExplicitForm) -> Result<(ParamsGpu, Vec<f32>), GpuError> {
    let nn = form.grid.num_nodes();
    let mut params = ParamsGpu {
        nn: nn as u32,
        n: form.grid.n() as u32,
        families: 0,
        dt: 0.0,
        family: [bytemuck::Zeroable::zeroed(); MAX_FAMILIES],
        drag: [0.0; 4],
        drag_node: NO_DRAG,
        drag_damping: 0.0,
        pad: [0; 2],
    };
    let mut op = Vec::new();
    match &form.force {
        ForceForm::Springs(families) => {
            if families.len() > MAX_FAMILIES {
                return Err(GpuError::Unsupported(format!(
                    "the GPU step takes at most {MAX_FAMILIES} spring families, this lattice has {}",
                    families.len()
                )));
            }
            params.families = families.len() as u32;
            for (slot, f) in params.family.iter_mut().zip(families) {
                *slot = FamilyGpu {
                    offset: f.offset as u32,
                    len: f.stiffness.len() as u32,
                    start: op.len() as u32,
                    rest_length: f.rest_length as f32,
                    rest: [f.rest[0] as f32, f.rest[1] as f32, f.rest[2] as f32, 0.0],
                };
                op.extend(f.stiffness.iter().map(|&k| k as f32));
            }
        }
        ForceForm::Stencil(blocks) => op.extend(blocks.iter().flatten().flatten().map(|&v| v as f32)),
    }
    Ok((params, op))
}

/// The bind group layout, and the pipelines of the step of a force form, the guard's figures and
/// the drag's step.
fn pipelines(device: &wgpu::Device, force: &ForceForm) -> (wgpu::BindGroupLayout, [wgpu::ComputePipeline; 3]) {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("explicit_step.wgsl"),
        source: wgpu::ShaderSource::Wgsl(std::borrow::Cow::Borrowed(EXPLICIT_STEP_WGSL)),
    });
    let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    };
    let read = wgpu::BufferBindingType::Storage { read_only: true };
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("explicit step"),
        entries: &[
            entry(0, wgpu::BufferBindingType::Uniform),
            entry(1, read),
            entry(2, read),
            entry(3, read),
            entry(4, read),
            entry(5, wgpu::BufferBindingType::Storage { read_only: false }),
        ],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("explicit step"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = |entry: &str| {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        })
    };
    let step = pipeline(match force {
        ForceForm::Springs(_) => "lattice_step",
        ForceForm::Stencil(_) => "stencil_step",
    });
    (layout, [step, pipeline("guard_figures"), pipeline("drag_step")])
}

impl ExplicitKernel {
    /// The step of `form` on `gpu`, at rest, unloaded; what the device refuses is an error.
    pub fn new(gpu: &ComputeDevice, form: &ExplicitForm) -> Result<Self, GpuError> {
        let scope = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let built = Self::build(gpu, form);
        match pollster::block_on(scope.pop()) {
            Some(e) => Err(GpuError::Device(super::device::one_line(&e.to_string()))),
            None => built,
        }
    }

    fn build(gpu: &ComputeDevice, form: &ExplicitForm) -> Result<Self, GpuError> {
        let nn = form.grid.num_nodes();
        if groups(nn) > MAX_GROUPS {
            return Err(GpuError::Unsupported(format!("{nn} nodes are more than one GPU dispatch covers")));
        }
        let device = &gpu.device;
        let bindable = device.limits().max_storage_buffers_per_shader_stage;
        if bindable < STORAGE_BUFFERS {
            return Err(GpuError::Unsupported(format!(
                "this GPU binds {bindable} storage buffers in a compute shader; the step needs {STORAGE_BUFFERS}"
            )));
        }
        let (params, op) = operator(form)?;
        let limit = device.limits().max_storage_buffer_binding_size as usize;
        // The guard's two figures a workgroup, then the held node's velocity change (and one
        // spare value).
        let health_len = 2 * groups(nn) as usize + 4;
        if 4 * op.len().max(6 * nn + health_len) > limit {
            return Err(GpuError::Unsupported(format!("{nn} nodes need more than this GPU's {limit}-byte buffers")));
        }
        let params_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("explicit params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let host_state = vec![0.0f32; 6 * nn];
        let host_load = vec![0.0f32; 3 * nn];
        let host_health = vec![0.0f32; health_len];
        let state = [0, 1].map(|_| {
            let zeros = vec![0.0f32; 6 * nn + health_len];
            storage(device, "state", &zeros, wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC)
        });
        let f_ext = storage(device, "f_ext", &host_load, wgpu::BufferUsages::COPY_DST);
        let coef = storage(device, "coefficients", &coefficients(form), wgpu::BufferUsages::COPY_DST);
        // A zero-length binding is not allowed: keep one element.
        let op = storage(device, "operator", if op.is_empty() { &[0.0] } else { &op }, wgpu::BufferUsages::empty());
        let readback = |label: &str, floats: usize| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (4 * floats) as u64,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let (staging, health_staging) = (readback("state readback", 6 * nn), readback("guard readback", health_len));
        let (layout, [step, guard, drag]) = pipelines(device, &form.force);
        let bind_groups = [0, 1].map(|i| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("explicit step"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: params_buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: state[i].as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 2, resource: f_ext.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 3, resource: coef.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 4, resource: op.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 5, resource: state[1 - i].as_entire_binding() },
                ],
            })
        });
        Ok(Self {
            gpu: gpu.clone(),
            nn,
            params,
            params_buffer,
            state,
            current: 0,
            f_ext,
            coef,
            staging,
            health_staging,
            bind_groups,
            step,
            guard,
            drag,
            params_stale: false,
            pending: None,
            host_state,
            host_load,
            host_health,
            mapped: Default::default(),
        })
    }

    /// Writes the state: positions `x` (displacements from `rest`) and velocities `v`.
    pub fn write_state(&mut self, rest: &[Vec<f64>; 3], x: &[Vec<f64>; 3], v: &[Vec<f64>; 3]) {
        let nn = self.nn;
        for c in 0..3 {
            for p in 0..nn {
                self.host_state[c * nn + p] = (x[c][p] - rest[c][p]) as f32;
                self.host_state[3 * nn + c * nn + p] = v[c][p] as f32;
            }
        }
        self.flush();
        self.gpu.queue.write_buffer(&self.state[self.current], 0, bytemuck::cast_slice(&self.host_state));
    }

    /// Writes the external forces, newtons.
    pub fn write_load(&mut self, f_ext: &[Vec<f64>; 3]) {
        self.write_load_nodes(f_ext, 0..self.nn);
    }

    /// Writes the external forces of the nodes `nodes` only (a tool's, a few rows of the top
    /// face: kilobytes where the whole load is megabytes), and nothing where they are what the
    /// GPU has (a load a tool sets again every substep and changes once a tick).
    pub fn write_load_nodes(&mut self, f_ext: &[Vec<f64>; 3], nodes: std::ops::Range<usize>) {
        let nn = self.nn;
        let nodes = nodes.start.min(nn)..nodes.end.min(nn);
        let mut changed = [false; 3];
        for (c, changed) in changed.iter_mut().enumerate() {
            let at = c * nn + nodes.start..c * nn + nodes.end;
            for (h, f) in self.host_load[at].iter_mut().zip(&f_ext[c][nodes.clone()]) {
                *changed |= *h != *f as f32;
                *h = *f as f32;
            }
        }
        if changed.contains(&true) {
            self.flush();
        }
        for c in (0..3).filter(|&c| changed[c]) {
            let at = c * nn + nodes.start..c * nn + nodes.end;
            let bytes = bytemuck::cast_slice(&self.host_load[at.clone()]);
            self.gpu.queue.write_buffer(&self.f_ext, (4 * at.start) as u64, bytes);
        }
    }

    /// Rewrites which components are free (a new load case).
    pub fn write_free(&mut self, form: &ExplicitForm) {
        self.flush();
        self.gpu.queue.write_buffer(&self.coef, 0, bytemuck::cast_slice(&coefficients(form)));
    }

    /// Holds a node by the dragging spring after each step from now (`None`: lets go).
    pub fn set_drag(&mut self, drag: Option<GpuDrag>) {
        let (node, target, k, c) = match drag {
            Some(d) => (d.node as u32, d.target_displacement, d.stiffness_per_mass, d.damping_per_mass),
            None => (NO_DRAG, [0.0; 3], 0.0, 0.0),
        };
        let drag = [target[0] as f32, target[1] as f32, target[2] as f32, k as f32];
        if (self.params.drag_node, self.params.drag, self.params.drag_damping) != (node, drag, c as f32) {
            (self.params.drag_node, self.params.drag, self.params.drag_damping) = (node, drag, c as f32);
            self.params_stale = true;
        }
    }

    /// Records `steps` steps of `dt`, each followed by the drag's split step where a node is
    /// held; they are submitted with the next write or read (or [`ExplicitKernel::finish`]), so
    /// the substeps of a tick under a held load go to the GPU together.
    pub fn run(&mut self, dt: f64, steps: usize) {
        if self.params.dt != dt as f32 || self.params_stale {
            self.flush();
            self.params.dt = dt as f32;
            self.params_stale = false;
            self.gpu.queue.write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&self.params));
        }
        let dragged = self.params.drag_node != NO_DRAG;
        {
            let mut pass = pending_pass(&mut self.pending, &self.gpu);
            for _ in 0..steps {
                pass.set_bind_group(0, &self.bind_groups[self.current], &[]);
                pass.set_pipeline(&self.step);
                pass.dispatch_workgroups(groups(self.nn), 1, 1);
                if dragged {
                    pass.set_pipeline(&self.drag);
                    pass.dispatch_workgroups(1, 1, 1);
                }
                self.current = 1 - self.current;
            }
        }
    }

    /// Submits the steps recorded.
    fn flush(&mut self) {
        if let Some(encoder) = self.pending.take() {
            self.gpu.queue.submit([encoder.finish()]);
        }
    }

    /// Waits for the steps submitted and reads the state back into positions `x` (rest plus
    /// displacement) and velocities `v`.
    pub fn read_state(
        &mut self,
        rest: &[Vec<f64>; 3],
        x: &mut [Vec<f64>; 3],
        v: &mut [Vec<f64>; 3],
    ) -> Result<(), GpuError> {
        self.flush();
        read_into(&self.gpu, &self.mapped, (&self.state[self.current], 0), &self.staging, &mut self.host_state)?;
        let nn = self.nn;
        for c in 0..3 {
            for p in 0..nn {
                x[c][p] = rest[c][p] + f64::from(self.host_state[c * nn + p]);
                v[c][p] = f64::from(self.host_state[3 * nn + c * nn + p]);
            }
        }
        Ok(())
    }

    /// Waits for the steps submitted and reads the guard's figures of the state they left: the
    /// kinetic energy, J (NaN where a velocity is), and the largest displacement component, m;
    /// and the held node's velocity change in the last step. One dispatch sums them per
    /// workgroup, and only those sums come back.
    pub fn read_health(&mut self) -> Result<crate::sim::tissue::StepHealth, GpuError> {
        {
            let mut pass = pending_pass(&mut self.pending, &self.gpu);
            pass.set_pipeline(&self.guard);
            pass.set_bind_group(0, &self.bind_groups[self.current], &[]);
            pass.dispatch_workgroups(groups(self.nn), 1, 1);
        }
        self.flush();
        let from = (&self.state[1 - self.current], (4 * 6 * self.nn) as u64);
        read_into(&self.gpu, &self.mapped, from, &self.health_staging, &mut self.host_health)?;
        let (figures, held) = self.host_health.split_at(self.host_health.len() - 4);
        let (mut energy, mut largest) = (0.0f64, 0.0f64);
        for pair in figures.chunks_exact(2) {
            energy += f64::from(pair[0]);
            // A NaN is kept (`max` would drop it).
            largest = if largest.is_nan() || pair[1].is_nan() { f64::NAN } else { largest.max(f64::from(pair[1])) };
        }
        let held_velocity_change_m_s =
            if self.params.drag_node == NO_DRAG { [0.0; 3] } else { std::array::from_fn(|c| f64::from(held[c])) };
        Ok(crate::sim::tissue::StepHealth {
            kinetic_energy_j: energy,
            largest_displacement_m: largest,
            held_velocity_change_m_s,
        })
    }

    /// Submits the steps recorded and waits until the GPU has finished everything.
    pub fn finish(&mut self) -> Result<(), GpuError> {
        self.flush();
        self.gpu
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Readback(e.to_string()))
    }
}

/// A compute pass recorded after what `pending` holds (a new encoder where it holds none).
fn pending_pass<'a>(pending: &'a mut Option<wgpu::CommandEncoder>, gpu: &ComputeDevice) -> wgpu::ComputePass<'a> {
    pending
        .get_or_insert_with(|| gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None }))
        .begin_compute_pass(&wgpu::ComputePassDescriptor { label: None, timestamp_writes: None })
}

/// Copies `out.len()` values of `from` (a buffer, a byte offset) through `staging` into `out`,
/// waiting for everything submitted.
fn read_into(
    gpu: &ComputeDevice,
    mapped: &std::sync::Arc<std::sync::atomic::AtomicU8>,
    (from, offset): (&wgpu::Buffer, u64),
    staging: &wgpu::Buffer,
    out: &mut [f32],
) -> Result<(), GpuError> {
    use std::sync::atomic::Ordering;
    let bytes = (4 * out.len()) as u64;
    let mut encoder = gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    encoder.copy_buffer_to_buffer(from, offset, staging, 0, bytes);
    gpu.queue.submit([encoder.finish()]);
    let slice = staging.slice(..bytes);
    mapped.store(0, Ordering::Release);
    let done = std::sync::Arc::clone(mapped);
    slice.map_async(wgpu::MapMode::Read, move |r| done.store(if r.is_ok() { 1 } else { 2 }, Ordering::Release));
    gpu.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| GpuError::Readback(e.to_string()))?;
    if mapped.load(Ordering::Acquire) != 1 {
        return Err(GpuError::Readback("the readback buffer did not map".into()));
    }
    {
        let data = slice.get_mapped_range().map_err(|e| GpuError::Readback(e.to_string()))?;
        out.copy_from_slice(bytemuck::cast_slice(&data));
    }
    staging.unmap();
    Ok(())
}
