//! Layer 3b, the GPU's step: the lattices' and the linear FEM's symplectic Euler step as wgpu
//! compute shaders (`shaders/explicit_step.wgsl`), in f32, behind the same seam as the CPU's
//! ([`crate::sim::Tissue`]). The state stays on the GPU between steps: the simulation asks for it
//! only where it reads nodes ([`crate::sim::Tissue::sync`]), its guard reads the kernel's
//! figures of a step, and the drag's split step runs there too.
//!
//! - [`device`]: an adapter that computes, or a one-line reason why there is none.
//! - [`explicit`]: the kernel: buffers, pipelines, steps, the drag's step, the guard's figures,
//!   state in and out.
//! - [`tissue`]: [`GpuTissue`], a CPU tissue whose symplectic steps run on the GPU.
//!
//! May use: `tissue-core` (its simulation, response, mechanics and io layers), wgpu.

// The core's layers, by the paths the code names them.
pub(crate) use tissue_core::{mechanics, response, sim};

pub mod device;
pub mod explicit;
pub mod tissue;

pub use device::{ComputeDevice, GpuError};
pub use tissue::GpuTissue;

/// Where a model's steps are computed: `cpu` (the default), `cpu-f32` or `gpu` (scripts, the
/// viewer).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Compute {
    /// The CPU, in f64.
    #[default]
    Cpu,
    /// The CPU, the symplectic step's internal force summed in f32 (the lattices and the linear FEM;
    /// [`crate::sim::Tissue::set_single_precision`]).
    #[serde(rename = "cpu-f32")]
    CpuF32,
    /// The GPU's compute shaders, in f32 (symplectic Euler only).
    Gpu,
}

impl Compute {
    /// `cpu` or `gpu`.
    pub fn name(self) -> &'static str {
        match self {
            Compute::Cpu => "cpu",
            Compute::CpuF32 => "cpu-f32",
            Compute::Gpu => "gpu",
        }
    }

    /// `tissue` as it runs here: itself on the CPU (its force in f32 for `cpu-f32`), or wrapped
    /// to step on the GPU (opening an adapter; a one-line error where none computes or the
    /// model has no such step).
    pub fn place(self, mut tissue: Box<dyn crate::sim::Tissue>) -> Result<Box<dyn crate::sim::Tissue>, GpuError> {
        match self {
            Compute::Cpu => Ok(tissue),
            Compute::CpuF32 => {
                tissue.set_single_precision(true).map_err(GpuError::Unsupported)?;
                Ok(tissue)
            }
            Compute::Gpu => Ok(Box::new(GpuTissue::new(&ComputeDevice::open()?, tissue)?)),
        }
    }
}

/// The tests' own cache folder (`tests/support/test_cache.rs`).
#[cfg(test)]
#[path = "../../../tests/support/test_cache.rs"]
mod test_cache;
