//! [`GpuTissue`]: a CPU tissue whose symplectic Euler steps run on the GPU. The CPU model keeps
//! the state between steps (tools, contact and the guard read and write it as always); a step
//! sends the load (and the state, where something changed it), runs the kernel and reads the
//! state back. Everything else (masses, forces for contact, parameters, implicit steps) is the
//! CPU model's.

use super::device::{ComputeDevice, GpuError};
use super::explicit::ExplicitKernel;
use crate::mechanics::cases::LoadCase;
use crate::mechanics::grid::Grid;
use crate::mechanics::msm::MsmParams;
use crate::response::damping::Damping;
use crate::sim::explicit_form::ExplicitForm;
use crate::sim::{Integrator, Tissue};

/// A tissue stepped on the GPU.
#[derive(Debug)]
pub struct GpuTissue {
    inner: Box<dyn Tissue>,
    gpu: ComputeDevice,
    kernel: ExplicitKernel,
    rest: [Vec<f64>; 3],
    /// Whether the CPU's state changed since the GPU last had it.
    stale: bool,
    /// Whether the load may have changed since the GPU last had it (it is sent only then:
    /// 3 MB at 64^3).
    load_stale: bool,
}

impl GpuTissue {
    /// `inner`'s steps on `gpu`; refused where the model has no GPU step.
    pub fn new(gpu: &ComputeDevice, inner: Box<dyn Tissue>) -> Result<Self, GpuError> {
        let form = inner.explicit_form().map_err(GpuError::Unsupported)?;
        let kernel = ExplicitKernel::new(gpu, &form)?;
        let grid = inner.grid();
        let rest = std::array::from_fn(|c| (0..grid.num_nodes()).map(|p| grid.position(p)[c]).collect());
        Ok(Self { inner, gpu: gpu.clone(), kernel, rest, stale: true, load_stale: true })
    }

    /// The adapter the steps run on, in words.
    pub fn adapter(&self) -> String {
        self.gpu.describe()
    }

    /// `steps` steps of `dt` with the load held, all in one submission and without reading the
    /// state back until the end: the GPU's own speed, for `bench`.
    pub fn run_unsynchronised(&mut self, dt: f64, steps: usize) -> Result<(), String> {
        self.sync_in();
        self.kernel.run(dt, steps);
        self.kernel.finish().map_err(|e| e.to_string())
    }

    /// Reads the GPU's state into the CPU model (after [`GpuTissue::run_unsynchronised`]).
    pub fn read_back(&mut self) -> Result<(), String> {
        let (x, v) = self.inner.x_v_mut();
        self.kernel.read_state(&self.rest, x, v).map_err(|e| e.to_string())
    }

    fn sync_in(&mut self) {
        if self.stale {
            self.kernel.write_state(&self.rest, self.inner.x(), self.inner.v());
            self.stale = false;
        }
        if self.load_stale {
            self.kernel.write_load(self.inner.f_ext_mut());
            self.load_stale = false;
        }
    }

    fn rebuild(&mut self) -> Result<(), String> {
        let form = self.inner.explicit_form()?;
        self.kernel = ExplicitKernel::new(&self.gpu, &form).map_err(|e| e.to_string())?;
        self.stale = true;
        self.load_stale = true;
        Ok(())
    }
}

impl Tissue for GpuTissue {
    fn grid(&self) -> Grid {
        self.inner.grid()
    }
    fn total_mass(&self) -> f64 {
        self.inner.total_mass()
    }
    fn node_mass(&self, p: usize) -> f64 {
        self.inner.node_mass(p)
    }
    fn x(&self) -> &[Vec<f64>; 3] {
        self.inner.x()
    }
    fn x_mut(&mut self) -> &mut [Vec<f64>; 3] {
        self.stale = true;
        self.inner.x_mut()
    }
    fn v(&self) -> &[Vec<f64>; 3] {
        self.inner.v()
    }
    fn v_mut(&mut self) -> &mut [Vec<f64>; 3] {
        self.stale = true;
        self.inner.v_mut()
    }
    fn x_v_mut(&mut self) -> (&mut [Vec<f64>; 3], &mut [Vec<f64>; 3]) {
        self.stale = true;
        self.inner.x_v_mut()
    }
    fn f_ext_mut(&mut self) -> &mut [Vec<f64>; 3] {
        self.load_stale = true;
        self.inner.f_ext_mut()
    }
    fn free(&self) -> &[f64] {
        self.inner.free()
    }
    fn forces(&mut self) -> &[Vec<f64>; 3] {
        self.inner.forces()
    }
    fn step(&mut self, integrator: Integrator, dt: f64) -> Result<(), String> {
        if integrator != Integrator::Symplectic {
            // The GPU has the explicit step only: an implicit one runs on the CPU's state.
            self.stale = true;
            return self.inner.step(integrator, dt);
        }
        self.sync_in();
        self.kernel.run(dt, 1);
        self.read_back()
    }
    fn kinetic_energy(&self) -> f64 {
        self.inner.kinetic_energy()
    }
    fn explicit_dt_limit(&self) -> f64 {
        self.inner.explicit_dt_limit()
    }
    fn apply_case(&mut self, case: &LoadCase) {
        self.inner.apply_case(case);
        if let Ok(form) = self.inner.explicit_form() {
            self.kernel.write_free(&form);
        }
        self.stale = true;
        self.load_stale = true;
    }
    fn params(&self) -> Option<MsmParams> {
        self.inner.params()
    }
    fn set_params(&mut self, params: MsmParams) -> Result<(), String> {
        self.inner.set_params(params)?;
        self.rebuild()
    }
    fn set_damping_ratio(&mut self, zeta: f64) -> Result<(), String> {
        self.inner.set_damping_ratio(zeta)?;
        self.rebuild()
    }
    fn damping(&self) -> Damping {
        self.inner.damping()
    }
    fn modal(&self) -> Result<crate::response::modal::ModalModel, String> {
        self.inner.modal()
    }
    fn explicit_form(&self) -> Result<ExplicitForm, String> {
        self.inner.explicit_form()
    }
    fn carries_contact_loads(&self) -> bool {
        self.inner.carries_contact_loads()
    }
    fn newton_solves(&self) -> Option<crate::mechanics::newton_krylov::NewtonSolves> {
        self.inner.newton_solves()
    }
    fn set_anchor(&mut self, anchor: Option<crate::mechanics::anchor::Anchor>) -> bool {
        // The implicit steps run on the CPU's model, which holds the drag in its solve.
        self.inner.set_anchor(anchor)
    }
    fn computed_on(&self) -> Option<String> {
        Some(format!("symplectic steps on the GPU: {}", self.adapter()))
    }
}
