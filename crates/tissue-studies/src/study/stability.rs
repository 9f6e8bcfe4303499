//! Where explicit integration fails: the critical time step of symplectic Euler, measured by
//! bisection on `dt` over a fixed number of steps, against the analytic bound `2 / omega_max`
//! with `omega_max^2` the largest eigenvalue of `M^-1 K` (Lanczos on the rest stiffness).
//!
//! Undamped symplectic Euler on a mode of frequency `omega` is stable exactly when
//! `omega dt < 2`; above that the mode grows by a factor of about `1 + 2 sqrt(2 delta)` per
//! step at `omega dt = 2 (1 + delta)`. A run of [`STEPS`] steps from a random perturbation of
//! [`PERTURBATION_M`] counts as diverged once any node has moved [`GROWTH`] times that much, so
//! the bisection resolves `dt_crit` to about `1e-5` relative: far finer than the 5 % asked.

use rand::{RngExt, SeedableRng, rngs::Xoshiro256PlusPlus};

use crate::mechanics::cases::LoadCase;
use crate::mechanics::fem::FemModel;
use crate::mechanics::fem::dynamics::{FemDynamics, Formulation};
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::msm::{Dynamics, MsmModel, MsmParams};

/// Steps of one stability run.
pub const STEPS: usize = 2000;
/// Amplitude of the random initial displacement, metres (small: the run stays linear).
pub const PERTURBATION_M: f64 = 1e-9;
/// Growth of the largest displacement that counts as divergence.
pub const GROWTH: f64 = 1e6;
/// Lanczos steps of the study's `omega_max`, at most.
pub const STUDY_ITERATIONS: usize = 3000;
/// The study's `omega_max^2` is converged when the Ritz residual is within this of it.
pub const STUDY_TOLERANCE: f64 = 1e-8;

/// `omega_max` (rad/s) of a mass-spring model with `fixed` nodes held: the Lanczos Ritz value
/// ([`crate::response::stiffest_mode`]) after at most `iterations` steps, converged to a
/// residual of `1e-8` of it.
pub fn msm_omega_max(model: &MsmModel, fixed_nodes: &[bool], iterations: usize) -> f64 {
    crate::response::stiffest_mode::lattice(model, fixed_nodes, STUDY_TOLERANCE, iterations).ritz.sqrt()
}

/// `omega_max` (rad/s) of a FEM cube (linear stiffness, lumped masses) with its fixed dofs held,
/// as [`msm_omega_max`].
pub fn fem_omega_max(fem: &FemDynamics, iterations: usize) -> f64 {
    let free: Vec<bool> = fem.free.iter().map(|&f| f != 0.0).collect();
    crate::response::stiffest_mode::fem(&fem.model, &fem.mass, &free, STUDY_TOLERANCE, iterations).ritz.sqrt()
}

/// Whether `STEPS` undamped symplectic steps of `dt` from a fixed random perturbation stay bounded.
fn msm_stable(model: &MsmModel, case: &LoadCase, dt: f64) -> bool {
    let mut d = Dynamics::new(model);
    d.apply_case(case);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    let rest = d.x.clone();
    for c in 0..3 {
        for p in 0..d.free.len() {
            d.x[c][p] += d.free[p] * PERTURBATION_M * (2.0 * rng.random::<f64>() - 1.0);
        }
    }
    for _ in 0..STEPS {
        d.step_symplectic(model, dt);
    }
    let limit = GROWTH * PERTURBATION_M;
    (0..3).all(|c| d.x[c].iter().zip(&rest[c]).all(|(x, r)| (x - r).abs() < limit))
}

fn fem_stable(fem: &mut FemDynamics, dt: f64) -> bool {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    fem.v.fill(0.0);
    let rest = fem.rest().to_vec();
    for i in 0..fem.x.len() {
        fem.x[i] = rest[i] + fem.free[i] * PERTURBATION_M * (2.0 * rng.random::<f64>() - 1.0);
    }
    for _ in 0..STEPS {
        fem.step_symplectic(dt);
    }
    let ok = fem.x.iter().zip(&rest).all(|(x, r)| (x - r).abs() < GROWTH * PERTURBATION_M);
    fem.x.copy_from_slice(&rest);
    fem.v.fill(0.0);
    ok
}

/// Bisection for the largest stable `dt` near `guess`: brackets it first (halving or doubling
/// the guess), then 20 bisections.
pub fn bisect_dt(guess: f64, mut stable: impl FnMut(f64) -> bool) -> f64 {
    let (mut lo, mut hi) = (0.8 * guess, 1.25 * guess);
    for _ in 0..40 {
        if stable(lo) {
            break;
        }
        (hi, lo) = (lo, lo / 2.0);
    }
    for _ in 0..40 {
        if !stable(hi) {
            break;
        }
        (lo, hi) = (hi, hi * 2.0);
    }
    for _ in 0..20 {
        let mid = 0.5 * (lo + hi);
        if stable(mid) { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

/// One row of the stability study.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct StabilityPoint {
    /// The model (`msm-axis`, `msm-hex`, `fem-linear` in files).
    #[serde(serialize_with = "crate::study::names::serialize_model")]
    pub model: crate::sim::Model,
    /// Nodes per axis.
    pub n: usize,
    /// Factor on every stiffness (springs or material).
    pub stiffness_scale: f64,
    /// Largest angular frequency, rad/s (Lanczos).
    pub omega_max: f64,
    /// `2 / omega_max`, s.
    pub dt_analytic_s: f64,
    /// Largest stable `dt` found by bisection, s.
    pub dt_measured_s: f64,
    /// `dt_measured / dt_analytic`.
    pub ratio: f64,
}

/// Measured and analytic critical `dt` of an undamped MSM (one face clamped).
pub fn msm_point(model: &MsmModel, scale: f64) -> StabilityPoint {
    let case = LoadCase::clamped(&model.grid, "A", 1, 0.0);
    let omega = msm_omega_max(model, &case.fixed_nodes(), STUDY_ITERATIONS);
    let analytic = 2.0 / omega;
    let measured = bisect_dt(analytic, |dt| msm_stable(model, &case, dt));
    StabilityPoint {
        model: crate::sim::Model::Lattice(model.params.topology()),
        n: model.grid.n(),
        stiffness_scale: scale,
        omega_max: omega,
        dt_analytic_s: analytic,
        dt_measured_s: measured,
        ratio: measured / analytic,
    }
}

/// Measured and analytic critical `dt` of the undamped linear FEM cube (one face clamped).
pub fn fem_point(material: &Material, grid: Grid, scale: f64) -> StabilityPoint {
    let mut m = material.clone();
    m.stiffness *= scale;
    let model = FemModel::new(grid, &m);
    let mut fem = FemDynamics::new(model, material.density, Formulation::Linear, 0.0);
    fem.apply_case(&LoadCase::clamped(&grid, "A", 1, 0.0));
    let omega = fem_omega_max(&fem, STUDY_ITERATIONS);
    let analytic = 2.0 / omega;
    let measured = bisect_dt(analytic, |dt| fem_stable(&mut fem, dt));
    StabilityPoint {
        model: crate::sim::Model::Fem(Formulation::Linear),
        n: grid.n(),
        stiffness_scale: scale,
        omega_max: omega,
        dt_analytic_s: analytic,
        dt_measured_s: measured,
        ratio: measured / analytic,
    }
}

/// `params` with every stiffness scaled by `s` and no damping.
pub fn scaled_undamped(params: &MsmParams, s: f64) -> MsmParams {
    let sc = |v: Option<f64>| v.map(|v| v * s);
    MsmParams {
        k1: params.k1 * s,
        k2: params.k2 * s,
        k3: params.k3 * s,
        d: 0.0,
        c12: sc(params.c12),
        c13: sc(params.c13),
        c23: sc(params.c23),
        b: sc(params.b),
    }
}
