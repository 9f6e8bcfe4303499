//! Tests of the parent module.

use super::*;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::newton_krylov::{KRYLOV_TOLERANCE, NEWTON_TOLERANCE};

/// The rotation by `angle` about the unit axis `(1, 2, 2) / 3`, row-major.
fn rotation(angle: f64) -> [[f64; 3]; 3] {
    let k = [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
    let (s, c) = angle.sin_cos();
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let cross = match (i, j) {
                (0, 1) => -k[2],
                (0, 2) => k[1],
                (1, 0) => k[2],
                (1, 2) => -k[0],
                (2, 0) => -k[1],
                (2, 1) => k[0],
                _ => 0.0,
            };
            let delta = if i == j { 1.0 } else { 0.0 };
            c * delta + s * cross + (1.0 - c) * k[i] * k[j]
        })
    })
}

fn rotate(r: &[[f64; 3]; 3], v: &[f64], transpose: bool) -> Vec<f64> {
    v.chunks_exact(3)
        .flat_map(|v| {
            let row = |i: usize| (0..3).map(|j| if transpose { r[j][i] } else { r[i][j] } * v[j]).sum::<f64>();
            [row(0), row(1), row(2)]
        })
        .collect()
}

/// A corotational cube of object B (orthotropic) on 4^3, turned rigidly by `r` about its
/// centre, its rotations converged.
fn turned(r: &[[f64; 3]; 3]) -> FemDynamics {
    let m = Material::object_b();
    let grid = Grid::new(4).unwrap();
    let mut fem = FemDynamics::new(FemModel::new(grid, &m), m.density, Formulation::Corotational, 0.0);
    let centred: Vec<f64> = fem.rest.iter().map(|x| x - 0.05).collect();
    for (x, t) in fem.x.iter_mut().zip(rotate(r, &centred, false)) {
        *x = t + 0.05;
    }
    for _ in 0..20 {
        fem.forces();
    }
    fem
}

#[test]
fn the_warped_stiffness_of_a_rigidly_turned_cube_is_the_turned_rest_stiffness() {
    let r = rotation(0.7);
    let mut fem = turned(&r);
    let dofs = fem.x.len();
    let p: Vec<f64> = (0..dofs).map(|i| (0.37 * i as f64).sin()).collect();
    let mut warped = vec![0.0; dofs];
    fem.warped_system_product(&p, 0.0, 1.0, &mut warped);
    // R K R^T p, the rest stiffness in the turned frame.
    let mut k_local = vec![0.0; dofs];
    fem.model.apply(&rotate(&r, &p, true), &mut k_local);
    let want = rotate(&r, &k_local, false);
    let scale = want.iter().fold(0.0f64, |a, w| a.max(w.abs()));
    let worst = warped.iter().zip(&want).fold(0.0f64, |a, (w, v)| a.max((w - v).abs()));
    // The element rotations are the cube's to their tolerance (1e-8 rad).
    assert!(worst <= 1e-7 * scale, "warped product off by {worst} of {scale}");
}

#[test]
fn the_warped_solve_meets_its_tolerance_where_the_rest_factor_alone_does_not() {
    // A turned cube moving: the step's system is the warped one, far from the rest factor.
    let r = rotation(0.9);
    for trapezoidal in [true, false] {
        let mut fem = turned(&r);
        fem.newton_iterations = 0; // the linearised step
        for (i, v) in fem.v.iter_mut().enumerate() {
            *v = 0.05 * (0.7 * i as f64).cos();
        }
        let (v0, x0) = (fem.v.clone(), fem.x.clone());
        let dt = 1e-3;
        let step =
            |fem: &mut FemDynamics| if trapezoidal { fem.step_newmark(dt) } else { fem.step_prefactored(dt) }.unwrap();
        step(&mut fem);
        let solves = fem.newton_solves().unwrap();
        assert_eq!((solves.steps, solves.unconverged), (1, 0), "{solves:?}");
        assert!(solves.most >= 2, "{solves:?}");
        // The residual of the linearised system at the solution: the step's unknown is
        // dx (trapezoidal) or v' (backward Euler).
        let (c_scale, k_scale) = implicit_scales(dt, trapezoidal);
        let y: Vec<f64> =
            if trapezoidal { fem.x.iter().zip(&x0).map(|(x, x0)| x - x0).collect() } else { fem.v.clone() };
        // The rotations and forces of the step's start.
        let mut start = turned(&r);
        start.v.copy_from_slice(&v0);
        let f = start.forces().to_vec();
        let (v_scale, f_scale) = if trapezoidal { (dt, 0.5 * dt * dt) } else { (1.0, dt) };
        let b: Vec<f64> = (0..y.len()).map(|i| v_scale * start.mass[i] * v0[i] + f_scale * f[i]).collect();
        let mut ay = vec![0.0; y.len()];
        start.warped_system_product(&y, 1.0 + c_scale * start.alpha, k_scale, &mut ay);
        let norm = |v: &[f64]| v.iter().map(|v| v * v).sum::<f64>().sqrt();
        let residual: Vec<f64> = b.iter().zip(&ay).map(|(b, a)| b - a).collect();
        let relative = norm(&residual) / norm(&b);
        assert!(relative < 2.0 * KRYLOV_TOLERANCE, "trapezoidal {trapezoidal}: residual {relative} of |b|");
        // The rest factor's solve alone leaves a residual many orders larger.
        let mut frozen = turned(&r);
        frozen.v.copy_from_slice(&v0);
        frozen.newton_iterations = 0;
        frozen.krylov_iterations = 0;
        step(&mut frozen);
        let y0: Vec<f64> =
            if trapezoidal { frozen.x.iter().zip(&x0).map(|(x, x0)| x - x0).collect() } else { frozen.v.clone() };
        start.warped_system_product(&y0, 1.0 + c_scale * start.alpha, k_scale, &mut ay);
        let residual: Vec<f64> = b.iter().zip(&ay).map(|(b, a)| b - a).collect();
        let frozen_relative = norm(&residual) / norm(&b);
        assert!(frozen_relative > 1e3 * relative, "rest factor alone: {frozen_relative}, warped {relative}");
        eprintln!(
            "trapezoidal {trapezoidal}: {solves:?}, residual {relative:.2e}, rest factor alone {frozen_relative:.2e}"
        );
    }
}

/// The step's nonlinear residual `|v_s M v + w_n f(x) + w_e f(x + d(y)) - a M y| / |b|` of a
/// corotational implicit step from `start` (rotations converged) to `end`.
fn nonlinear_residual(start: &FemDynamics, end: &FemDynamics, dt: f64, trapezoidal: bool) -> f64 {
    let mut at_start = FemDynamics::new(start.model.clone(), 1040.0, Formulation::Corotational, 0.0);
    at_start.mass.copy_from_slice(&start.mass);
    at_start.x.copy_from_slice(&start.x);
    let mut at_end = FemDynamics::new(start.model.clone(), 1040.0, Formulation::Corotational, 0.0);
    at_end.x.copy_from_slice(&end.x);
    let (f0, f1) = (converged_forces(&mut at_start), converged_forces(&mut at_end));
    let a = 1.0 + implicit_scales(dt, trapezoidal).0 * start.alpha;
    let (v_s, w_n, w_e) = if trapezoidal { (dt, 0.25 * dt * dt, 0.25 * dt * dt) } else { (1.0, 0.0, dt) };
    let (mut r, mut b) = (0.0, 0.0);
    for i in 0..f0.len() {
        let y = if trapezoidal { end.x[i] - start.x[i] } else { end.v[i] };
        let m = start.mass[i];
        r += (v_s * m * start.v[i] + w_n * f0[i] + w_e * f1[i] - a * m * y).powi(2);
        b += (v_s * m * start.v[i] + (w_n + w_e) * f0[i]).powi(2);
    }
    (r / b).sqrt()
}

fn converged_forces(fem: &mut FemDynamics) -> Vec<f64> {
    for _ in 0..20 {
        fem.forces();
    }
    fem.forces().to_vec()
}

#[test]
fn newtons_corrections_solve_the_steps_equation_with_the_force_at_its_end() {
    let r = rotation(0.9);
    for trapezoidal in [true, false] {
        let mut residuals = Vec::new();
        for newton in [NEWTON_MAX_ITERATIONS, 0] {
            let mut fem = turned(&r);
            fem.newton_iterations = newton;
            // Spinning at 10 rad/s about z, and wobbling.
            for p in 0..fem.x.len() / 3 {
                let (x, y) = (fem.x[3 * p] - 0.05, fem.x[3 * p + 1] - 0.05);
                fem.v[3 * p] = -10.0 * y;
                fem.v[3 * p + 1] = 10.0 * x;
            }
            for (i, v) in fem.v.iter_mut().enumerate() {
                *v += 0.05 * (0.7 * i as f64).cos();
            }
            let start = FemDynamics { x: fem.x.clone(), v: fem.v.clone(), ..turned(&r) };
            if trapezoidal { fem.step_newmark(1e-3) } else { fem.step_prefactored(1e-3) }.unwrap();
            let solves = fem.newton_solves().unwrap();
            assert_eq!((solves.steps, solves.unconverged, solves.newton_unconverged), (1, 0, 0), "{solves:?}");
            assert!(newton == 0 || solves.newton >= 1, "{solves:?}");
            residuals.push(nonlinear_residual(&start, &fem, 1e-3, trapezoidal));
        }
        eprintln!(
            "trapezoidal {trapezoidal}: nonlinear residual {:.2e} (Newton), {:.2e} (linearised)",
            residuals[0], residuals[1]
        );
        assert!(
            residuals[0] <= 5.0 * NEWTON_TOLERANCE,
            "trapezoidal {trapezoidal}: residual {} with Newton",
            residuals[0]
        );
        assert!(residuals[1] > 10.0 * residuals[0], "trapezoidal {trapezoidal}: linearised {}", residuals[1]);
    }
}

/// The corotational FEM of a material with a lump: at small strain its force is the linear FEM's
/// (the lump's elements included), and a rigid turn of the whole cube costs no force.
#[test]
fn the_corotated_lump_is_the_linear_one_at_small_strain_and_free_under_a_rigid_turn() {
    let mut m = Material::object_b();
    m.inclusions.push(crate::mechanics::inclusion::Inclusion {
        centre: [0.05, 0.06, 0.07],
        radius: 0.02,
        stiffness: m.stiffness * 6.0,
    });
    let grid = Grid::new(5).unwrap();
    let model = FemModel::new(grid, &m);
    assert!(!model.patch().is_empty());
    let mut linear = FemDynamics::new(model.clone(), m.density, Formulation::Linear, 0.0);
    let mut corotated = FemDynamics::new(model, m.density, Formulation::Corotational, 0.0);
    for (d, (a, b)) in linear.x.iter_mut().zip(corotated.x.iter_mut()).enumerate() {
        let u = 1e-7 * (((d * 37) % 11) as f64 - 5.0);
        *a += u;
        *b += u;
    }
    let (fl, fc) = (linear.forces().to_vec(), corotated.forces().to_vec());
    let scale = fl.iter().fold(0.0f64, |a, f| a.max(f.abs()));
    let gap = fl.iter().zip(&fc).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
    assert!(gap < 1e-4 * scale, "{gap} of {scale}");
    // Turned rigidly by 0.6 rad about the cube's centre.
    let r = rotation(0.6);
    let centred: Vec<f64> = corotated.rest.iter().map(|x| x - 0.05).collect();
    for (x, t) in corotated.x.iter_mut().zip(rotate(&r, &centred, false)) {
        *x = t + 0.05;
    }
    for _ in 0..20 {
        corotated.forces();
    }
    let turned = corotated.forces().iter().fold(0.0f64, |a, f| a.max(f.abs()));
    let stiff = corotated.model.stiffest_element() * 0.05;
    assert!(turned < 1e-9 * stiff, "{turned} against {stiff}");
}
