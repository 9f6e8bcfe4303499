//! The dynamic reference: the linear hex8 FEM's transients on a scene, damped by the same ratio
//! (mass-proportional at its own fundamental), integrated by Newmark's average-acceleration
//! rule (trapezoidal, unconditionally stable, no numerical damping, second order) with the step
//! halved until the answer changes by less than [`CONVERGED`] (relative L2 in time).
//!
//! A scene is a clamp and a load ([`LoadCase`]): the viewer's (face z = 0 clamped, a uniform 1 N
//! shear of the top face along x, [`view_scene`]) or one of the paper's clamped cases (their
//! 10 N face loads, [`paper_scene`]). Two transients per scene ([`Transient`]): the load applied
//! as a step at `t = 0` from rest, and the load released at `t = 0` from its static shape. The
//! answer compared is the displacement of the loaded face's nodes over the first
//! [`DURATION_S`].

use super::damping::mass_proportional_rate;
use super::modal::ModalModel;
use crate::cases::LoadCase;
use crate::grid::Grid;
use crate::sparse::{SparseError, SpdSystem};

/// Length of a transient, s.
pub const DURATION_S: f64 = 0.2;
/// Converged when halving the step changes the answer by less than this (relative L2 in time).
pub const CONVERGED: f64 = 1e-3;
/// The first step tried, s.
const FIRST_STEP_S: f64 = 2e-3;
/// At most this many halvings.
const MAX_HALVINGS: usize = 9;
/// Total force of the viewer scene's top-face shear, N.
pub const VIEW_LOAD_N: f64 = 1.0;

/// Which transient.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Transient {
    /// The scene's load switched on at `t = 0`, from rest.
    StepLoad,
    /// The scene's load switched off at `t = 0`, from its static shape, at rest.
    Release,
}

impl Transient {
    /// Both.
    pub const ALL: [Transient; 2] = [Transient::StepLoad, Transient::Release];

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Transient::StepLoad => "step_load",
            Transient::Release => "release",
        }
    }
}

/// The viewer's scene: face z = 0 clamped, a uniform [`VIEW_LOAD_N`] shear of the top face along x.
pub fn view_scene(grid: &Grid) -> LoadCase {
    let mut case = LoadCase::bottom_clamp(grid, "view");
    case.load = crate::touch::top_traction(grid, 0, VIEW_LOAD_N);
    case.id = "view_top_shear_x".into();
    case
}

/// The paper's clamped case along `axis` (1-3), 10 N on the face opposite the clamp.
pub fn paper_scene(grid: &Grid, object: &str, axis: usize) -> LoadCase {
    LoadCase::clamped(grid, object, axis, 10.0)
}

/// The dofs whose displacement is compared: every dof of the nodes carrying the load.
pub fn loaded_dofs(case: &LoadCase) -> Vec<usize> {
    let nodes: Vec<usize> =
        (0..case.load.len() / 3).filter(|&p| case.load[3 * p..3 * p + 3].iter().any(|&f| f != 0.0)).collect();
    nodes.iter().flat_map(|&p| [3 * p, 3 * p + 1, 3 * p + 2]).collect()
}

/// A sampled trajectory: the compared dofs' displacements at `t = k dt`, `k = 0..=steps`.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    /// Sample spacing, s.
    pub dt: f64,
    /// One row per sample.
    pub samples: Vec<Vec<f64>>,
}

impl Trajectory {
    /// The samples linearly interpolated at `t`, into `out`.
    pub fn at(&self, t: f64, out: &mut [f64]) {
        let s = (t / self.dt).clamp(0.0, (self.samples.len() - 1) as f64);
        let k = (s.floor() as usize).min(self.samples.len().saturating_sub(2));
        let w = s - k as f64;
        let (a, b) = (&self.samples[k], &self.samples[(k + 1).min(self.samples.len() - 1)]);
        for ((o, x), y) in out.iter_mut().zip(a).zip(b) {
            *o = (1.0 - w) * x + w * y;
        }
    }

    /// Relative L2 in time of `self - reference` over `self`'s samples (trapezoidal weights),
    /// the reference interpolated at `self`'s times.
    pub fn relative_error(&self, reference: &Trajectory) -> f64 {
        let mut r = vec![0.0; reference.samples[0].len()];
        let (mut num, mut den) = (0.0, 0.0);
        let last = self.samples.len() - 1;
        for (k, s) in self.samples.iter().enumerate() {
            reference.at(k as f64 * self.dt, &mut r);
            let w = if k == 0 || k == last { 0.5 } else { 1.0 };
            num += w * s.iter().zip(&r).map(|(a, b)| (a - b) * (a - b)).sum::<f64>();
            den += w * r.iter().map(|b| b * b).sum::<f64>();
        }
        (num / den).sqrt()
    }
}

/// A converged reference transient and how it converged.
#[derive(Debug, Clone)]
pub struct ReferenceTransient {
    /// Which transient.
    pub transient: Transient,
    /// The answer at the finest step.
    pub trajectory: Trajectory,
    /// Each step tried and the change of the answer from the step twice its size (NaN for the
    /// first).
    pub history: Vec<(f64, f64)>,
}

/// Newmark average acceleration on `model` (`C = alpha M`) for `case`'s clamp: `transient` with
/// `case`'s load, sampled on the loaded dofs at step `h` over [`DURATION_S`].
pub fn newmark(
    model: &ModalModel,
    case: &LoadCase,
    alpha: f64,
    transient: Transient,
    h: f64,
) -> Result<Trajectory, SparseError> {
    let n = case.load.len();
    let mass = model.dof_masses(&case.fixed);
    let free: Vec<f64> = case.fixed.iter().map(|&f| if f { 0.0 } else { 1.0 }).collect();
    let (mut system, slots) = SpdSystem::new(n, &model.stiffness.entries)?;
    for ((&slot, &u), &g) in slots.iter().zip(&model.stiffness.unit).zip(&model.stiffness.group) {
        system.add(slot, u * model.theta[g as usize]);
    }
    let c_m = 4.0 / (h * h) + 2.0 * alpha / h;
    system.add_diagonal_scaled(c_m, &mass);
    system.decouple(&case.fixed, 1.0);
    system.factor()?;
    let (mut u, load) = match transient {
        Transient::StepLoad => (vec![0.0; n], case.load.clone()),
        Transient::Release => (model.static_shape(case)?, vec![0.0; n]),
    };
    let mut v = vec![0.0; n];
    let mut ku = vec![0.0; n];
    model.stiffness.mul(&model.theta, &u, &mut ku);
    let mut a: Vec<f64> =
        (0..n).map(|d| if mass[d] > 0.0 { (load[d] - ku[d]) / mass[d] * free[d] } else { 0.0 }).collect();
    let dofs = loaded_dofs(case);
    let steps = (DURATION_S / h).round() as usize;
    let mut samples = Vec::with_capacity(steps + 1);
    samples.push(dofs.iter().map(|&d| u[d]).collect());
    let mut rhs = vec![0.0; n];
    for _ in 0..steps {
        for d in 0..n {
            let m = mass[d];
            rhs[d] = free[d]
                * (load[d] + m * (4.0 / (h * h) * u[d] + 4.0 / h * v[d] + a[d]) + alpha * m * (2.0 / h * u[d] + v[d]));
        }
        system.solve_in_place(&mut rhs)?;
        for d in 0..n {
            let un = rhs[d] * free[d];
            let an = 4.0 / (h * h) * (un - u[d]) - 4.0 / h * v[d] - a[d];
            v[d] += 0.5 * h * (a[d] + an);
            a[d] = an;
            u[d] = un;
        }
        samples.push(dofs.iter().map(|&d| u[d]).collect());
    }
    Ok(Trajectory { dt: h, samples })
}

/// The converged FEM `transient` of `case` (on `grid`) for `material`, damped by `zeta` at the FEM's own
/// fundamental on the viewer's scene.
pub fn converged(
    material: &crate::material::Material,
    grid: Grid,
    case: &LoadCase,
    zeta: f64,
    transient: Transient,
) -> anyhow::Result<ReferenceTransient> {
    let fem = crate::fem::FemModel::new(grid, material);
    let model = ModalModel::fem(&fem, material.density);
    let omega_1 = super::modal::scene_fundamental(&model).map_err(|e| anyhow::anyhow!("{e}"))?;
    let alpha = mass_proportional_rate(zeta, omega_1);
    let mut h = FIRST_STEP_S;
    let mut previous = newmark(&model, case, alpha, transient, h)?;
    let mut history = vec![(h, f64::NAN)];
    for _ in 0..MAX_HALVINGS {
        h *= 0.5;
        let next = newmark(&model, case, alpha, transient, h)?;
        let change = previous.relative_error(&next);
        history.push((h, change));
        previous = next;
        if change < CONVERGED {
            return Ok(ReferenceTransient { transient, trajectory: previous, history });
        }
    }
    anyhow::bail!(
        "the FEM's {} transient of {} did not converge to {CONVERGED} in {MAX_HALVINGS} halvings (last change {:.2e})",
        transient.name(),
        case.id,
        history.last().map_or(f64::NAN, |h| h.1)
    )
}
