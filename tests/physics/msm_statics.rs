//! The mass-spring model's static equilibrium: closed form, Newton and dynamic relaxation agree.

use tissue_core::mechanics::cases::{Bc, LoadCase, benchmark_cases};
use tissue_core::mechanics::grid::Grid;
use tissue_core::mechanics::material::TISSUE_DENSITY;
use tissue_core::mechanics::msm::statics::{NewtonOptions, closed_form_axis, solve_newton};
use tissue_core::mechanics::msm::{Dynamics, MsmModel, MsmParams};

fn paper() -> MsmParams {
    MsmParams::axis(968.2, 1010.0, 1137.7, 0.6)
}

fn shear() -> MsmParams {
    MsmParams { c12: Some(250.0), c13: Some(320.0), c23: Some(400.0), ..paper() }
}

fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter().flatten().zip(b.iter().flatten()).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

fn max_abs(v: &[[f64; 3]]) -> f64 {
    v.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()))
}

#[test]
fn chain_of_springs_closed_form() {
    // Each of the n^2 chains along the load carries F/n^2; its n-1 springs each stretch F/(n^2 k).
    let grid = Grid::paper();
    let model = MsmModel::new(grid, paper(), TISSUE_DENSITY).expect("model");
    let case = LoadCase::clamped(&grid, "A", 2, 10.0);
    let u = closed_form_axis(&model, &case).expect("closed form applies");
    let tip = u[grid.node(3, 7, 5)][1];
    assert!((tip - 7.0 * 10.0 / 64.0 / 1010.0).abs() < 1e-18);
    assert_eq!(u[grid.node(3, 0, 5)], [0.0; 3]);
    assert_eq!(u[grid.node(3, 7, 5)][0], 0.0);
}

#[test]
fn newton_matches_closed_form_on_the_paper_model() {
    let grid = Grid::paper();
    let model = MsmModel::new(grid, paper(), TISSUE_DENSITY).expect("model");
    for case in benchmark_cases(&grid, "A", Bc::Clamped) {
        let exact = closed_form_axis(&model, &case).expect("closed form");
        let (u, report) = solve_newton(&model, &case, NewtonOptions::default()).expect("Newton converges");
        assert!(report.rel_residual <= 1e-10, "{}: {report:?}", case.id);
        assert!(max_diff(&u, &exact) <= 1e-12 * max_abs(&exact), "{}", case.id);
    }
}

fn relax(model: &MsmModel, case: &LoadCase, steps: usize, dt: f64) -> Vec<[f64; 3]> {
    let mut dynamics = Dynamics::new(model);
    dynamics.apply_case(case);
    for _ in 0..steps {
        dynamics.step_symplectic(model, dt);
    }
    dynamics.displacements(model)
}

#[test]
fn newton_agrees_with_long_dynamic_relaxation() {
    let grid = Grid::paper();
    for params in [paper(), shear()] {
        let model = MsmModel::new(grid, params, TISSUE_DENSITY).expect("model");
        for (axis, f) in [(1, 10.0), (3, 5.0)] {
            let case = LoadCase::clamped(&grid, "A", axis, f);
            let (u, _) = solve_newton(&model, &case, NewtonOptions::default()).expect("Newton");
            let relaxed = relax(&model, &case, 30_000, 1e-4);
            let rel = max_diff(&u, &relaxed) / max_abs(&u);
            assert!(rel < 1e-8, "{:?} {}: relaxation differs by {rel:e}", params.topology(), case.id);
        }
    }
}

#[test]
fn shear_springs_change_the_answer_and_newton_converges() {
    let grid = Grid::paper();
    let model = MsmModel::new(grid, shear(), TISSUE_DENSITY).expect("model");
    assert_eq!(model.num_springs(), 3696);
    let case = LoadCase::clamped(&grid, "A", 1, 10.0);
    let (u, report) = solve_newton(&model, &case, NewtonOptions::default()).expect("Newton");
    assert!(report.rel_residual <= 1e-10 && report.iterations < 20, "{report:?}");
    let axis_only = closed_form_axis(&MsmModel::new(grid, paper(), TISSUE_DENSITY).expect("model"), &case).expect("cf");
    // Diagonals stiffen the cube: the loaded face moves less.
    let tip = grid.num_nodes() - 1;
    assert!(u[tip][0] < axis_only[tip][0]);
}

#[test]
fn implicit_euler_relaxes_to_the_same_equilibrium() {
    let grid = Grid::paper();
    let model = MsmModel::new(grid, shear(), TISSUE_DENSITY).expect("model");
    let case = LoadCase::clamped(&grid, "A", 2, 5.0);
    let (u, _) = solve_newton(&model, &case, NewtonOptions::default()).expect("Newton");
    let mut dynamics = Dynamics::new(&model);
    dynamics.apply_case(&case);
    for _ in 0..3000 {
        dynamics.step_implicit(&model, 1e-3).expect("implicit step");
    }
    let rel = max_diff(&u, &dynamics.displacements(&model)) / max_abs(&u);
    assert!(rel < 1e-8, "implicit relaxation differs by {rel:e}");
}

#[test]
fn prefactored_implicit_euler_relaxes_to_the_same_equilibrium() {
    // Only the Jacobian is frozen at rest: a state at rest under the step satisfies the full
    // nonlinear equilibrium, for the shear lattice and for the hex lattice.
    let grid = Grid::paper();
    let hex = MsmParams { b: Some(500.0), ..shear() };
    for params in [shear(), hex] {
        let model = MsmModel::new(grid, params, TISSUE_DENSITY).expect("model");
        let case = LoadCase::clamped(&grid, "A", 3, 10.0);
        let (u, _) = solve_newton(&model, &case, NewtonOptions::default()).expect("Newton");
        let mut dynamics = Dynamics::new(&model);
        dynamics.apply_case(&case);
        for _ in 0..3000 {
            dynamics.step_prefactored(&model, 1e-3).expect("prefactored step");
        }
        let rel = max_diff(&u, &dynamics.displacements(&model)) / max_abs(&u);
        assert!(rel < 1e-8, "{:?}: prefactored relaxation differs by {rel:e}", params.topology());
    }
}

#[test]
fn undamped_symplectic_euler_conserves_energy() {
    let grid = Grid::new(5).expect("grid");
    let model = MsmModel::new(grid, MsmParams { d: 0.0, ..shear() }, TISSUE_DENSITY).expect("model");
    let mut dynamics = Dynamics::new(&model);
    // Start from a stretched state, no load, one face clamped.
    let mut case = LoadCase::clamped(&grid, "A", 1, 0.0);
    case.load.fill(0.0);
    dynamics.apply_case(&case);
    for p in grid.face_nodes(0, true) {
        dynamics.x[0][p] += 1e-4;
    }
    let energy = |d: &Dynamics| d.kinetic_energy(&model) + model.elastic_energy(&d.x);
    let e0 = energy(&dynamics);
    let mut worst = 0.0f64;
    for _ in 0..20_000 {
        dynamics.step_symplectic(&model, 1e-5);
        worst = worst.max((energy(&dynamics) - e0).abs() / e0);
    }
    assert!(worst < 1e-2, "energy drift {worst:e}");
}
