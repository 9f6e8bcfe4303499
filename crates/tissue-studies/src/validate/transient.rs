//! The dynamic reference: the linear hex8 FEM's transients on a scene, damped by the same ratio
//! (mass-proportional at its own fundamental), integrated by Newmark's average-acceleration
//! rule (trapezoidal, unconditionally stable, no numerical damping, second order) with the step
//! halved until the answer changes by less than [`CONVERGED`] (relative L2 in time) in two
//! halvings in a row.
//!
//! A scene is a clamp and a load ([`LoadCase`]): the viewer's (face z = 0 clamped, a uniform 1 N
//! shear of the top face along x, [`view_scene`]) or one of the paper's clamped cases (their
//! 10 N face loads, [`paper_scene`]). The transients ([`Transient`]): the load applied as a step
//! at `t = 0` from rest, the load released at `t = 0` from its static shape (the answer compared:
//! the displacement of the loaded face's nodes over the first [`DURATION_S`]), and on the viewer's
//! scene a [`TAP_DURATION_S`] probe tap: the viewer's 15 mm sphere pressed into the top face above
//! a node to [`TAP_DEPTH_M`] and back along a half sine, with frictionless, inelastic,
//! linearised node contact solved at every step (an active set on the Schur complement of the
//! contact nodes, so that no contact pulls and no free node ends inside the sphere; a node in
//! contact moves with the sphere along its normal); the answer compared: the magnitude of the
//! contact nodes' elastic push on the probe, what the viewer reads.

use crate::mechanics::cases::LoadCase;
use crate::mechanics::grid::{CUBE_SIDE_M, Grid};
use crate::mechanics::sparse::{SparseError, SpdSystem};
use crate::response::damping::mass_proportional_rate;
use crate::response::modal::ModalModel;
use glam::DVec3;

/// Length of a transient, s.
pub const DURATION_S: f64 = 0.2;
/// Converged when halving the step twice in a row changes the answer by less than this each time
/// (relative L2 in time).
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
    /// The probe tap on the top face (the scene's clamp, no load).
    ProbeTap,
}

impl Transient {
    /// All three.
    pub const ALL: [Transient; 3] = [Transient::StepLoad, Transient::Release, Transient::ProbeTap];

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Transient::StepLoad => "step_load",
            Transient::Release => "release",
            Transient::ProbeTap => "probe_tap",
        }
    }
}

/// Length of the probe tap, s.
pub const TAP_DURATION_S: f64 = 0.02;
/// Deepest press of the probe tap, m.
pub const TAP_DEPTH_M: f64 = 0.004;

/// The probe's velocity at `t` during the tap, m/s.
pub fn tap_velocity(t: f64) -> Option<[f64; 3]> {
    use std::f64::consts::PI;
    (0.0..=TAP_DURATION_S)
        .contains(&t)
        .then(|| [0.0, 0.0, -TAP_DEPTH_M * PI / TAP_DURATION_S * (2.0 * PI * t / TAP_DURATION_S).sin()])
}

/// Where the tap touches the top face: above the top-face node (3, 3) of the 8^3 grid, m.
pub const TAP_POINT: [f64; 3] = [3.0 / 7.0 * CUBE_SIDE_M, 3.0 / 7.0 * CUBE_SIDE_M, CUBE_SIDE_M];

/// The probe's centre at `t` during the tap (`None` once it has let go): above [`TAP_POINT`],
/// pressed `TAP_DEPTH_M sin^2(pi t / TAP_DURATION_S)` below the surface.
pub fn tap_centre(t: f64) -> Option<[f64; 3]> {
    if !(0.0..=TAP_DURATION_S).contains(&t) {
        return None;
    }
    let top = TAP_POINT;
    Some([top[0], top[1], top[2] + crate::validate::touch::PROBE_RADIUS_M - tap_depth(t)])
}

/// How deep the tap has pressed at `t` (within the tap), m.
pub fn tap_depth(t: f64) -> f64 {
    TAP_DEPTH_M * (std::f64::consts::PI * t / TAP_DURATION_S).sin().powi(2)
}

/// The viewer's scene: face z = 0 clamped, a uniform [`VIEW_LOAD_N`] shear of the top face along x.
pub fn view_scene(grid: &Grid) -> LoadCase {
    let mut case = LoadCase::bottom_clamp(grid, "view");
    case.load = crate::validate::touch::top_traction(grid, 0, VIEW_LOAD_N);
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
    let (mut system, slots) = SpdSystem::on_grid(n, &model.stiffness().entries, &model.grid.dof_nodes())?;
    for ((&slot, &u), &g) in slots.iter().zip(&model.stiffness().unit).zip(&model.stiffness().group) {
        system.add(slot, u * model.theta()[g as usize]);
    }
    let c_m = 4.0 / (h * h) + 2.0 * alpha / h;
    system.add_diagonal_scaled(c_m, &mass);
    system.decouple(&case.fixed, 1.0);
    system.factor()?;
    let (mut u, load) = match transient {
        Transient::StepLoad => (vec![0.0; n], case.load.clone()),
        Transient::Release => (model.static_shape(case)?, vec![0.0; n]),
        Transient::ProbeTap => (vec![0.0; n], vec![0.0; n]),
    };
    let mut v = vec![0.0; n];
    let mut ku = vec![0.0; n];
    model.stiffness().mul(model.theta(), &u, &mut ku);
    let mut a: Vec<f64> =
        (0..n).map(|d| if mass[d] > 0.0 { (load[d] - ku[d]) / mass[d] * free[d] } else { 0.0 }).collect();
    let dofs = loaded_dofs(case);
    let steps = (DURATION_S / h).round() as usize;
    let mut samples = Vec::with_capacity(steps + 1);
    let tap = transient == Transient::ProbeTap;
    // Once the probe has let go nothing pushes on it: the tap's force is zero from then on.
    let stepped = if tap { ((TAP_DURATION_S / h).round() as usize + 1).min(steps) } else { steps };
    samples.push(if tap { vec![0.0] } else { dofs.iter().map(|&d| u[d]).collect() });
    let mut rhs = vec![0.0; n];
    for k in 0..stepped {
        for d in 0..n {
            let m = mass[d];
            rhs[d] = free[d]
                * (load[d] + m * (4.0 / (h * h) * u[d] + 4.0 / h * v[d] + a[d]) + alpha * m * (2.0 / h * u[d] + v[d]));
        }
        system.solve_in_place(&mut rhs)?;
        let contacts = match tap_centre((k + 1) as f64 * h) {
            Some(centre) if tap => contact(&mut system, &model.grid, &case.fixed, centre, &mut rhs)?,
            _ => Vec::new(),
        };
        for d in 0..n {
            let un = rhs[d] * free[d];
            let an = 4.0 / (h * h) * (un - u[d]) - 4.0 / h * v[d] - a[d];
            v[d] += 0.5 * h * (a[d] + an);
            a[d] = an;
            u[d] = un;
        }
        // Inelastic contact: a node in contact loses the part of its velocity that moves it
        // into the sphere (no bounce), as the viewer's contact does.
        if let Some(sphere_v) = tap_velocity((k + 1) as f64 * h) {
            for (p, nrm) in &contacts {
                let rel = (0..3).map(|c| (v[3 * p + c] - sphere_v[c]) * nrm[c]).sum::<f64>();
                if rel >= 0.0 {
                    continue; // separating: let go
                }
                for c in 0..3 {
                    let d = 3 * p + c;
                    let dv = -rel * nrm[c];
                    v[d] += dv;
                }
            }
        }
        if tap {
            // What the viewer reads: the contact nodes' elastic push on the sphere.
            model.stiffness().mul(model.theta(), &u, &mut ku);
            let mut force = [0.0; 3];
            for (p, n) in &contacts {
                let f_n = -(0..3).map(|c| ku[3 * p + c] * n[c]).sum::<f64>();
                if f_n < 0.0 {
                    for c in 0..3 {
                        force[c] += f_n * n[c];
                    }
                }
            }
            samples.push(vec![DVec3::from(force).length()]);
        } else {
            samples.push(dofs.iter().map(|&d| u[d]).collect());
        }
    }
    samples.resize(steps + 1, vec![0.0]);
    Ok(Trajectory { dt: h, samples })
}

/// Corrects the unconstrained answer `u` of one step (`system u = f`) for the sphere at `centre`
/// (radius [`crate::validate::touch::PROBE_RADIUS_M`]): frictionless linearised node contact, every free
/// node's normal displacement `n_p . u_p >= g_p` (its depth inside the sphere at rest), with
/// non-negative contact forces along `n_p` and an active set; returns the nodes in contact and
/// their normals.
fn contact(
    system: &mut SpdSystem,
    grid: &Grid,
    fixed: &[bool],
    centre: [f64; 3],
    u: &mut [f64],
) -> Result<Vec<(usize, [f64; 3])>, SparseError> {
    use crate::response::linear::{contact_active_set, sphere_geometry};
    let radius = crate::validate::touch::PROBE_RADIUS_M;
    let geometry = sphere_geometry(grid, centre, radius);
    let free: Vec<bool> = (0..grid.num_nodes()).map(|p| !fixed[3 * p]).collect();
    let solved = contact_active_set(&mut |w| system.solve_in_place(w), u, &geometry, &free, radius)?;
    u.copy_from_slice(&solved.u);
    Ok(solved.solved.iter().zip(&solved.lambda).filter(|(_, l)| **l > 0.0).map(|(&p, _)| (p, geometry[p].0)).collect())
}

/// The converged FEM `transient` of `case` (on `grid`) for `material`, damped by `zeta` at the FEM's own
/// fundamental on the viewer's scene.
pub fn converged(
    material: &crate::mechanics::material::Material,
    grid: Grid,
    case: &LoadCase,
    zeta: f64,
    transient: Transient,
) -> anyhow::Result<ReferenceTransient> {
    let fem = crate::mechanics::fem::FemModel::new(grid, material);
    let model = ModalModel::fem(&fem, material.density);
    let omega_1 = crate::response::modal::scene_fundamental(&model).map_err(|e| anyhow::anyhow!("{e}"))?;
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
        // Two changes in a row below the bound: the tap's contact events make its convergence
        // first order and not monotone, so one small change can be chance.
        let last_two = history.iter().rev().take(2).filter(|h| h.1 < CONVERGED).count();
        if last_two == 2 {
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
