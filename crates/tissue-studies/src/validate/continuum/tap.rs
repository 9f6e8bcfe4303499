//! The material's answer to the fast probe tap
//! ([`crate::validate::transient::tap_centre`]: the 15 mm sphere 4 mm into the top face
//! and back in 20 ms along a `sin^2`): the linear hex8 FEM on graded meshes
//! ([`crate::mechanics::fem::graded`], fine around the tap and capped far from it so that the
//! cube's own motion is resolved too), lumped masses, mass-proportional damping of the ratio
//! asked for at the material's fundamental (a 16^3 FEM's), backward Euler, and frictionless
//! inelastic contact of the rigid sphere on the surface nodes with an active set at every step
//! (a node in contact is held on the sphere and so takes its motion). Backward Euler, not the
//! same-mesh reference's Newmark average acceleration: with nodes held on a moving sphere the
//! trapezoidal rule's contact forces chatter, and its force history changed more, not less, as
//! the step was halved below 0.1 ms (measured), while backward Euler converges (first order).
//! Converged in time first (the step halved on the coarsest mesh) and then in space (the meshes
//! of [`crate::validate::continuum::SPACING_RATIOS`]), each until the force's history changes by
//! less than [`TAP_TOLERANCE`] (relative L2 in time), and checked once more at half the step on
//! the finest mesh used. The answer is the force on the sphere: what the contact does to the
//! tissue, inertia and damping included (the contact multipliers).

use glam::DVec3;

use crate::mechanics::fem::graded::{GradedFem, GradedMesh};
use crate::mechanics::grid::{CUBE_SIDE_M, Grid};
use crate::mechanics::material::Material;
use crate::response::contact;
use crate::validate::continuum::{GROWTH, SPACING_RATIOS};
use crate::validate::touch::PROBE_RADIUS_M;
use crate::validate::transient::{DURATION_S, TAP_DEPTH_M, TAP_DURATION_S, TAP_POINT, Trajectory, tap_centre};

/// Converged when the force's history changes by less than this (relative L2 in time).
pub const TAP_TOLERANCE: f64 = 0.01;
/// The first step tried, s.
const FIRST_STEP_S: f64 = 1e-3;
/// At most this many halvings of the step.
const MAX_HALVINGS: usize = 7;
/// The far field's element side, in fine spacings.
const FAR_STEPS: f64 = 4.0;
/// Window nodes whose compliance is solved in one batch.
const BATCH_NODES: usize = 16;

/// The material's converged tap.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContinuumTap {
    /// The damping ratio at the fundamental.
    pub damping_ratio: f64,
    /// The fundamental used for the damping (a 16^3 FEM's), rad/s.
    pub omega_1: f64,
    /// The step of the answer, s.
    pub dt: f64,
    /// The fine spacing of the answer's mesh, m.
    pub spacing: f64,
    /// The force on the sphere at `k dt` for `k = 0..` until the tap ends, newtons (zero after).
    pub force_n: Vec<f64>,
    /// Each run: step (s), fine spacing (m), change from the run before (none for the first).
    pub history: Vec<(f64, f64, Option<f64>)>,
}

impl ContinuumTap {
    /// The force's magnitude as a trajectory over [`DURATION_S`] (zero once the tap has ended).
    pub fn trajectory(&self) -> Trajectory {
        let steps = (DURATION_S / self.dt).round() as usize;
        let mut samples: Vec<Vec<f64>> = self.force_n.iter().map(|&f| vec![f]).collect();
        samples.resize(steps + 1, vec![0.0]);
        Trajectory { dt: self.dt, samples }
    }
}

/// One mesh and step: the factor of `K + c M`, the masses and the surface window's compliance.
struct TapRun {
    fem: GradedFem,
    mass: Vec<f64>,
    /// Surface nodes the sphere can reach.
    window: Vec<usize>,
    /// Window-dof compliance of `K + c M`: `w3[(3 a + c) * 3 m + 3 b + d]`.
    w3: Vec<f64>,
}

impl TapRun {
    fn new(material: &Material, fine: f64, shift: f64) -> anyhow::Result<Self> {
        let reach = (2.0 * PROBE_RADIUS_M * TAP_DEPTH_M).sqrt();
        let mesh = GradedMesh::around_capped(TAP_POINT, fine, reach + 2.0 * fine, GROWTH, FAR_STEPS * fine);
        let mut fem = GradedFem::shifted(mesh, material, shift)?;
        let masses = fem.mesh.lumped_masses(material.density);
        let mass: Vec<f64> = (0..fem.fixed.len()).map(|d| if fem.fixed[d] { 0.0 } else { masses[d / 3] }).collect();
        let deepest = [TAP_POINT[0], TAP_POINT[1], CUBE_SIDE_M + PROBE_RADIUS_M - TAP_DEPTH_M];
        let window: Vec<usize> = (0..fem.mesh.num_nodes())
            .filter(|&p| fem.mesh.on_boundary(p) && !fem.fixed[3 * p])
            .filter(|&p| gap(deepest, fem.mesh.position(p)).1 > -2.0 * fine)
            .collect();
        let (n, m) = (fem.fixed.len(), window.len());
        let mut w3 = vec![0.0; 9 * m * m];
        for (chunk, batch) in window.chunks(BATCH_NODES).enumerate() {
            let cols = 3 * batch.len();
            let mut rhs = vec![0.0; n * cols];
            for (b, &p) in batch.iter().enumerate() {
                for c in 0..3 {
                    rhs[(3 * b + c) * n + 3 * p + c] = 1.0;
                }
            }
            fem.solve_columns(&mut rhs, cols)?;
            for col in 0..cols {
                let a = 3 * chunk * BATCH_NODES + col;
                for (q, &p) in window.iter().enumerate() {
                    for d in 0..3 {
                        w3[a * 3 * m + 3 * q + d] = rhs[col * n + 3 * p + d];
                    }
                }
            }
        }
        Ok(Self { fem, mass, window, w3 })
    }

    /// The contact of the unconstrained answer `u` for the sphere at `centre`
    /// ([`contact::solve`], warm-started from the last step's contact where it is within a
    /// radius): the window slots in contact and their forces along the normals, in `scratch`.
    fn contact(&self, centre: [f64; 3], u: &[f64], scratch: &mut contact::ContactScratch) -> anyhow::Result<()> {
        scratch.candidates.clear();
        scratch.candidates.extend(self.window.iter().map(|&p| {
            let (n, g) = gap(centre, self.fem.mesh.position(p));
            (n, g - (0..3).map(|c| n[c] * u[3 * p + c]).sum::<f64>())
        }));
        let candidates = &scratch.candidates;
        scratch.active.retain(|&q| candidates[q].1 > -PROBE_RADIUS_M);
        // With the candidates that came inside the sphere since.
        scratch.active.extend((0..candidates.len()).filter(|&q| candidates[q].1 > 0.0));
        contact::solve(&mut Window(self), scratch, 1e-12)?;
        Ok(())
    }

    /// The tap stepped at `h` with mass-proportional damping `alpha`: the force on the sphere at
    /// every step until the tap ends.
    fn run(&mut self, h: f64, alpha: f64) -> anyhow::Result<Vec<f64>> {
        let n = self.fixed_len();
        let (mut u, mut v) = (vec![0.0; n], vec![0.0; n]);
        let steps = (TAP_DURATION_S / h).round() as usize;
        let mut forces = vec![0.0];
        let mut rhs = vec![0.0; n];
        let mut base = vec![0.0; n];
        let mut scratch = contact::ContactScratch::default();
        let c_u = 1.0 / (h * h) + alpha / h;
        for k in 0..steps {
            let t = (k + 1) as f64 * h;
            for d in 0..n {
                base[d] = self.mass[d] * (c_u * u[d] + v[d] / h);
            }
            rhs.copy_from_slice(&base);
            self.fem.solve_columns(&mut rhs, 1)?;
            let centre = tap_centre(t).unwrap_or([TAP_POINT[0], TAP_POINT[1], 1.0]);
            self.contact(centre, &rhs, &mut scratch)?;
            if !scratch.active.is_empty() {
                rhs.copy_from_slice(&base);
                for (&q, &l) in scratch.active.iter().zip(&scratch.lambda) {
                    let (p, nrm) = (self.window[q], scratch.candidates[q].0);
                    for c in 0..3 {
                        rhs[3 * p + c] += l * nrm[c];
                    }
                }
                self.fem.solve_columns(&mut rhs, 1)?;
            }
            let force = DVec3::from(scratch.force());
            // Backward Euler: the nodes held on the sphere take its motion (inelastic contact).
            for d in 0..n {
                let un = if self.fem.fixed[d] { 0.0 } else { rhs[d] };
                v[d] = (un - u[d]) / h;
                u[d] = un;
            }
            forces.push(force.length());
        }
        Ok(forces)
    }

    fn fixed_len(&self) -> usize {
        self.fem.fixed.len()
    }
}

/// Outward normal from the sphere's centre to `x` and the depth of `x` inside the sphere.
fn gap(centre: [f64; 3], x: [f64; 3]) -> ([f64; 3], f64) {
    contact::sphere_gap(centre, PROBE_RADIUS_M, x, [0.0, 0.0, -1.0])
}

/// The tap's window as the contact sees it: the normal compliance between window slots.
struct Window<'a>(&'a TapRun);

impl contact::Compliance for Window<'_> {
    fn normal(&self, i: usize, ni: [f64; 3], j: usize, nj: [f64; 3]) -> f64 {
        let m3 = 3 * self.0.window.len();
        (0..3).map(|c| nj[c] * (0..3).map(|d| ni[d] * self.0.w3[(3 * j + c) * m3 + 3 * i + d]).sum::<f64>()).sum()
    }
}

/// Relative L2 in time between two force histories at steps `h` and `h_ref` (the first
/// interpolated onto the second's times).
fn change(a: &[f64], h: f64, b: &[f64], h_ref: f64) -> f64 {
    let ta = Trajectory { dt: h, samples: a.iter().map(|&f| vec![f]).collect() };
    let tb = Trajectory { dt: h_ref, samples: b.iter().map(|&f| vec![f]).collect() };
    tb.relative_error(&ta)
}

/// The material's converged tap, damped by `zeta` at the fundamental of a 16^3 FEM of it;
/// `progress(message)` says what is being run.
pub fn continuum_tap(material: &Material, zeta: f64, progress: &mut dyn FnMut(&str)) -> anyhow::Result<ContinuumTap> {
    let zeta = crate::response::damping::check_ratio(zeta).map_err(anyhow::Error::msg)?;
    // The damping's fundamental comes from a homogeneous FEM.
    material.require_homogeneous("the material's tap")?;
    let grid = Grid::new(16).map_err(anyhow::Error::msg)?;
    let fem = crate::mechanics::fem::FemModel::new(grid, material);
    let modal = crate::response::modal::ModalModel::fem(&fem, material.density);
    let omega_1 = crate::response::modal::scene_fundamental(&modal).map_err(anyhow::Error::msg)?;
    let alpha = crate::response::damping::mass_proportional_rate(zeta, omega_1);
    let hertz = (PROBE_RADIUS_M * TAP_DEPTH_M).sqrt();
    let mut history: Vec<(f64, f64, Option<f64>)> = Vec::new();
    let mut run = |fine: f64, h: f64, history: &mut Vec<(f64, f64, Option<f64>)>, last: Option<(&[f64], f64)>| {
        let last_change =
            history.last().and_then(|r| r.2).map_or(String::new(), |c| format!(", last change {:.2} %", 100.0 * c));
        progress(&format!("step {} ms, spacing {:.2} mm{last_change}", 1e3 * h, 1e3 * fine));
        let shift = 1.0 / (h * h) + alpha / h;
        let forces = TapRun::new(material, fine, shift)?.run(h, alpha)?;
        let c = last.map(|(prev, hp)| change(prev, hp, &forces, h));
        history.push((h, fine, c));
        anyhow::Ok((forces, c.unwrap_or(f64::INFINITY)))
    };
    // In time, on the coarsest mesh.
    let mut fine = SPACING_RATIOS[0] * hertz;
    let mut h = FIRST_STEP_S;
    let (mut best, _) = run(fine, h, &mut history, None)?;
    let mut converged = false;
    for _ in 0..MAX_HALVINGS {
        let (next, c) = run(fine, 0.5 * h, &mut history, Some((&best, h)))?;
        (best, h) = (next, 0.5 * h);
        if c < TAP_TOLERANCE {
            converged = true;
            break;
        }
    }
    anyhow::ensure!(converged, "the tap did not converge in time on the coarsest mesh: {history:?}");
    // In space, at that step.
    converged = false;
    for ratio in &SPACING_RATIOS[1..] {
        let (next, c) = run(ratio * hertz, h, &mut history, Some((&best, h)))?;
        (best, fine) = (next, ratio * hertz);
        if c < TAP_TOLERANCE {
            converged = true;
            break;
        }
    }
    anyhow::ensure!(converged, "the tap did not converge in space: {history:?}");
    // Half the step on the finest mesh used.
    let (next, c) = run(fine, 0.5 * h, &mut history, Some((&best, h)))?;
    anyhow::ensure!(c < TAP_TOLERANCE, "the tap's step is not converged on the finest mesh: {history:?}");
    Ok(ContinuumTap { damping_ratio: zeta, omega_1, dt: 0.5 * h, spacing: fine, force_n: next, history })
}
