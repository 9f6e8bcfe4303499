//! [`GpuTissue`]: a CPU tissue whose symplectic Euler steps run on the GPU, where the state stays
//! between steps. The CPU model keeps a copy that follows at [`Tissue::sync`] (to draw it, or for
//! a tool that reads nodes) and before anything writes it (node contact, the guard's restore, an
//! implicit step, new parameters); then the GPU takes the state again. The guard reads the
//! kernel's figures of the last step instead of the state. A load sends only the nodes a tool
//! changed, and the drag's split step runs on the GPU after each step. Everything else (masses, forces for contact, parameters, implicit steps) is the CPU
//! model's.

use super::device::{ComputeDevice, GpuError};
use super::explicit::{ExplicitKernel, GpuDrag};
use crate::mechanics::cases::LoadCase;
use crate::mechanics::grid::Grid;
use crate::mechanics::msm::MsmParams;
use crate::response::damping::Damping;
use crate::sim::explicit_form::ExplicitForm;
use crate::sim::tissue::StepHealth;
use crate::sim::{DRAG_DAMPING, DRAG_STIFFNESS, Integrator, Tissue};

/// A tissue stepped on the GPU.
#[derive(Debug)]
pub struct GpuTissue {
    inner: Box<dyn Tissue>,
    gpu: ComputeDevice,
    kernel: ExplicitKernel,
    rest: [Vec<f64>; 3],
    /// Whether the CPU's state changed since the GPU last had it.
    stale: bool,
    /// Whether the GPU's state is newer than the CPU's copy (it stepped since the last sync).
    behind: bool,
    /// Whether the whole load may have changed since the GPU last had it (sent only then: 3 MB
    /// at 64^3).
    load_stale: bool,
    /// The nodes whose load changed since the GPU last had it (sent alone otherwise).
    load_nodes: Option<std::ops::Range<usize>>,
    /// A readback that failed where no error could be returned: the next step's error.
    failed: Option<String>,
}

impl GpuTissue {
    /// `inner`'s steps on `gpu`; refused where the model has no GPU step.
    pub fn new(gpu: &ComputeDevice, inner: Box<dyn Tissue>) -> Result<Self, GpuError> {
        let form = inner.explicit_form().map_err(GpuError::Unsupported)?;
        let kernel = ExplicitKernel::new(gpu, &form)?;
        let grid = inner.grid();
        let rest = std::array::from_fn(|c| (0..grid.num_nodes()).map(|p| grid.position(p)[c]).collect());
        Ok(Self {
            inner,
            gpu: gpu.clone(),
            kernel,
            rest,
            stale: true,
            behind: false,
            load_stale: true,
            load_nodes: None,
            failed: None,
        })
    }

    /// The adapter the steps run on, in words.
    pub fn adapter(&self) -> String {
        self.gpu.describe()
    }

    /// `steps` steps of `dt` with the load held, all in one submission, waiting for them: the
    /// GPU's own speed, for `bench` (the state stays on the GPU).
    pub fn run_unsynchronised(&mut self, dt: f64, steps: usize) -> Result<(), String> {
        self.sync_in();
        self.kernel.run(dt, steps);
        self.behind = true;
        self.kernel.finish().map_err(|e| e.to_string())
    }

    /// Reads the GPU's state into the CPU model, whether or not it stepped since (`bench`'s
    /// figure of a readback).
    pub fn read_back(&mut self) -> Result<(), String> {
        let (x, v) = self.inner.x_v_mut();
        self.kernel.read_state(&self.rest, x, v).map_err(|e| e.to_string())?;
        self.behind = false;
        Ok(())
    }

    /// The state and the load to the GPU where the CPU changed them.
    fn sync_in(&mut self) {
        if self.stale {
            self.kernel.write_state(&self.rest, self.inner.x(), self.inner.v());
            self.stale = false;
        }
        if self.load_stale {
            self.kernel.write_load(self.inner.f_ext_mut());
            self.load_stale = false;
            self.load_nodes = None;
        } else if let Some(nodes) = self.load_nodes.take() {
            self.kernel.write_load_nodes(self.inner.f_ext_mut(), nodes);
        }
    }

    /// The state back from the GPU where it stepped since.
    fn sync_out(&mut self) -> Result<(), String> {
        if self.behind { self.read_back() } else { Ok(()) }
    }

    /// [`GpuTissue::sync_out`] before the CPU writes the state, which the GPU then takes again;
    /// a failed readback is the next step's error.
    fn before_write(&mut self) {
        if let Err(e) = self.sync_out() {
            self.failed.get_or_insert(e);
            self.behind = false;
        }
        self.stale = true;
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
        self.before_write();
        self.inner.x_mut()
    }
    fn v(&self) -> &[Vec<f64>; 3] {
        self.inner.v()
    }
    fn v_mut(&mut self) -> &mut [Vec<f64>; 3] {
        self.before_write();
        self.inner.v_mut()
    }
    fn x_v_mut(&mut self) -> (&mut [Vec<f64>; 3], &mut [Vec<f64>; 3]) {
        self.before_write();
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
        if let Err(e) = self.sync_out() {
            self.failed.get_or_insert(e);
        }
        self.inner.forces()
    }
    fn step(&mut self, integrator: Integrator, dt: f64) -> Result<(), String> {
        if let Some(e) = self.failed.take() {
            return Err(format!("the GPU's state could not be read back: {e}"));
        }
        if integrator != Integrator::Symplectic {
            // The GPU has the explicit step only: an implicit one runs on the CPU's state.
            self.sync_out()?;
            self.stale = true;
            return self.inner.step(integrator, dt);
        }
        self.sync_in();
        self.kernel.run(dt, 1);
        self.behind = true;
        Ok(())
    }
    fn kinetic_energy(&self) -> f64 {
        self.inner.kinetic_energy()
    }
    fn explicit_dt_limit(&self) -> f64 {
        self.inner.explicit_dt_limit()
    }
    fn step_limit(&self) -> crate::sim::StepLimit {
        self.inner.step_limit()
    }
    fn apply_case(&mut self, case: &LoadCase) {
        self.before_write();
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
        self.sync_out()?;
        self.inner.set_params(params)?;
        self.rebuild()
    }
    fn set_damping_ratio(&mut self, zeta: f64) -> Result<(), String> {
        self.sync_out()?;
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
    fn f_ext_mut_nodes(&mut self, nodes: std::ops::Range<usize>) -> &mut [Vec<f64>; 3] {
        self.load_nodes = Some(match self.load_nodes.take() {
            Some(had) => had.start.min(nodes.start)..had.end.max(nodes.end),
            None => nodes,
        });
        self.inner.f_ext_mut()
    }
    fn state_on_device(&self) -> bool {
        true
    }
    fn hold_by_drag(&mut self, drag: Option<(usize, [f64; 3])>) -> bool {
        let drag = drag.map(|(node, target)| {
            let m = self.inner.node_mass(node);
            GpuDrag {
                node,
                target_displacement: std::array::from_fn(|c| target[c] - self.rest[c][node]),
                stiffness_per_mass: DRAG_STIFFNESS / m,
                damping_per_mass: DRAG_DAMPING / m,
            }
        });
        self.kernel.set_drag(drag);
        true
    }
    fn sync(&mut self) -> Result<(), String> {
        self.sync_out()
    }
    fn discard_device_state(&mut self) {
        self.behind = false;
        self.stale = true;
        self.failed = None;
    }
    fn step_health(&mut self) -> Option<Result<StepHealth, String>> {
        // Where it did not step since the state came back, the CPU's copy is the state.
        self.behind.then(|| self.kernel.read_health().map_err(|e| e.to_string()))
    }
    fn computed_on(&self) -> Option<String> {
        Some(format!("symplectic steps on the GPU: {}", self.adapter()))
    }
}
