//! Dynamics: the measured motion of whole models against the integrators' closed forms, the
//! converged FEM reference, damped releases settling to the static answer, and the viewer's
//! default step meeting its dynamic targets.

use tissue_core::mechanics::fem::dynamics::Formulation;
use tissue_core::mechanics::grid::Grid;
use tissue_core::mechanics::material::Material;
use tissue_core::mechanics::msm::Topology;
use tissue_core::response::single_mode::{self, Scheme};
use tissue_core::sim::{DEFAULT_DYNAMIC_BUDGET, Integrator, Model, Simulation, choose_step};
use tissue_studies::validate::dynamic::measure::{Configuration, References, measure, modal_model};
use tissue_studies::validate::dynamic::reference::{self as dynamic_reference, Transient, view_scene};

const ZETA: f64 = 0.2;

#[test]
fn measured_release_of_whole_models_matches_the_single_mode_closed_forms() {
    // Mass-proportional damping keeps every mode of a linear model a single damped oscillator, so
    // time stepping the whole FEM cube measures exactly the closed form at its fundamental.
    let material = Material::object_a();
    let refs = References::new(&material, ZETA).expect("reference");
    for (integrator, dt) in
        [(Integrator::Symplectic, 2e-4), (Integrator::Prefactored, 1e-3), (Integrator::Prefactored, 1.0 / 60.0)]
    {
        let config = Configuration { model: Model::Fem(Formulation::Linear), params: None, integrator, dt };
        let r = measure(&refs, config).expect("measure");
        let p = r.predicted.expect("stable");
        assert!((r.measured_period_s / p.period_s - 1.0).abs() < 1e-6, "{integrator:?} {dt}: {r:?}");
        assert!((r.measured_damping_ratio - p.damping_ratio).abs() < 1e-6, "{integrator:?} {dt}: {r:?}");
        assert!(r.fit_residual < 1e-6, "a pure mode: {r:?}");
        // The linear FEM is the reference's own model: its period error is the integrator's.
        assert!((r.modal_period_s - r.fem_period_s).abs() < 1e-12 * r.fem_period_s);
    }
    // Backward Euler at one 60 Hz frame swallows the motion: the 15 Hz fundamental then decays
    // at more than twice the damping set.
    let fem = modal_model(&material, Model::Fem(Formulation::Linear), None).expect("modal");
    let w = tissue_core::response::modal::scene_fundamental(&fem).expect("fundamental");
    let frame = single_mode::discrete(Scheme::BackwardEuler, w, 2.0 * ZETA * w, 1.0 / 60.0).expect("stable");
    assert!(frame.damping_ratio > 2.0 * ZETA, "{frame:?}");
}

#[test]
#[ignore = "slow: in the slow group, cargo test --release -- --ignored"]
fn reference_transients_converge_at_second_order() {
    let material = Material::object_b();
    let grid = Grid::paper();
    for case in [view_scene(&grid), dynamic_reference::paper_scene(&grid, "B", 1)] {
        for t in Transient::ALL {
            if t == Transient::ProbeTap && case.id != "view_top_shear_x" {
                continue; // the tap is the viewer scene's
            }
            let r = dynamic_reference::converged(&material, grid, &case, ZETA, t).expect("converges");
            let changes: Vec<f64> = r.history.iter().skip(1).map(|h| h.1).collect();
            let last = *changes.last().expect("halved at least once");
            assert!(last < dynamic_reference::CONVERGED, "{}: {:?}", case.id, r.history);
            assert!(changes[changes.len() - 2] < dynamic_reference::CONVERGED, "{}: {:?}", case.id, r.history);
            // Newmark is second order: each halving cuts the change about four times (the tap's
            // contact events make it first order and irregular: only overall decrease).
            if t == Transient::ProbeTap {
                assert!(changes[0] > 5.0 * last, "{}: {:?}", case.id, r.history);
            } else if changes.len() >= 2 {
                let ratio = changes[changes.len() - 2] / last;
                assert!((3.0..5.0).contains(&ratio), "{} {t:?}: {:?}", case.id, r.history);
            }
        }
    }
}

/// A tissue of `model` with `zeta`, loaded by the viewer scene's step load and stepped for `t` s.
fn settled(model: Model, zeta: f64, integrator: Integrator, dt: f64, t: f64) -> Vec<[f64; 3]> {
    let material = Material::object_a();
    let tissue = model.build(&material, None, zeta).expect("build");
    let scene = view_scene(&Grid::paper());
    let mut sim = Simulation::with_tissue(tissue, integrator, dt, Some(&scene));
    for _ in 0..(t / dt).round() as usize {
        sim.step().expect("steps");
    }
    sim.displacements()
}

fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter().zip(b).flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs())).fold(0.0, f64::max)
}

#[test]
fn damped_motion_settles_to_the_static_answer_whatever_the_damping() {
    let grid = Grid::paper();
    let scene = view_scene(&grid);
    let material = Material::object_a();
    // The linear FEM: its static answer is K^-1 f.
    let fem = modal_model(&material, Model::Fem(Formulation::Linear), None).expect("modal");
    let u = fem.static_shape(&scene).expect("static");
    let exact: Vec<[f64; 3]> = u.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let scale = exact.iter().flat_map(|p| p.iter()).fold(0.0f64, |a, b| a.max(b.abs()));
    for zeta in [0.2, 1.0] {
        let got = settled(Model::Fem(Formulation::Linear), zeta, Integrator::Prefactored, 1e-3, 3.0);
        assert!(max_diff(&got, &exact) < 1e-6 * scale, "zeta {zeta}: {:e}", max_diff(&got, &exact) / scale);
    }
    // The hex lattice (nonlinear springs): two damping ratios settle to one answer, its
    // equilibrium, which at 1 N is within 1 % of its small-displacement static shape.
    let hex = modal_model(&material, Model::Lattice(Topology::Hex), None).expect("modal");
    let linear: Vec<[f64; 3]> =
        hex.static_shape(&scene).expect("static").chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let lattice = Model::Lattice(Topology::Hex);
    let a = settled(lattice, 0.2, Integrator::Prefactored, 1e-3, 3.0);
    let b = settled(lattice, 1.0, Integrator::Prefactored, 1e-3, 3.0);
    assert!(max_diff(&a, &linear) < 1e-2 * scale, "{:e}", max_diff(&a, &linear) / scale);
    assert!(max_diff(&a, &b) < 1e-6 * scale, "damping changed the static answer: {:e}", max_diff(&a, &b) / scale);
}

#[test]
fn the_viewer_default_meets_its_dynamic_targets_and_the_automatic_step_follows_the_budget() {
    // The viewer's default: the hex tissue of object A, the automatic choice at 0.1 ms.
    let material = Material::object_a();
    let tissue = Model::Lattice(Topology::Hex).build(&material, None, ZETA).expect("build");
    let (integrator, dt, _) =
        choose_step(None, 1e-4, tissue.step_limit(), tissue.damping(), DEFAULT_DYNAMIC_BUDGET).expect("auto");
    let refs = References::new(&material, ZETA).expect("reference");
    let r = measure(&refs, Configuration { model: Model::Lattice(Topology::Hex), params: None, integrator, dt })
        .expect("measure");
    assert!(r.period_error < 0.02, "{r:?}");
    assert!(r.damping_error < 0.01, "{r:?}");
    // The fast tap with the viewer's contact (the material's compliance and slow modes) against
    // the material's converged tap (measured: 1.7 %).
    assert!(r.probe_tap_error < 0.10, "{r:?}");
    // One prefactored Newmark (trapezoidal) solve per 1 ms tick keeps the corotational FEM inside
    // the dynamic budget (measured: period 0.061 %, damping 0.028 % of critical).
    let newmark = Configuration {
        model: Model::Fem(Formulation::Corotational),
        params: None,
        integrator: Integrator::Newmark,
        dt: 1e-3,
    };
    let n = measure(&refs, newmark).expect("newmark");
    assert!(n.period_error < 0.02 && n.damping_error < 0.01, "{n:?}");
    // The FEM asked for 1 ms steps: backward Euler there damps 4 % of critical too much, so the
    // automatic choice takes substeps, and its prediction meets the budget.
    let fem = Model::Fem(Formulation::Corotational).build(&material, None, ZETA).expect("fem");
    let (i, h, note) = choose_step(None, 1e-3, fem.step_limit(), fem.damping(), DEFAULT_DYNAMIC_BUDGET).expect("auto");
    assert!(h < 1e-3 && note.is_some(), "{i:?} {h} {note:?}");
    let (p, d) = tissue_core::sim::predicted_error(i, h, fem.damping()).expect("stable");
    assert!(p <= DEFAULT_DYNAMIC_BUDGET.period && d <= DEFAULT_DYNAMIC_BUDGET.damping);
    let (_, d1) = tissue_core::sim::predicted_error(Integrator::Prefactored, 1e-3, fem.damping()).expect("stable");
    assert!(d1 > 0.03, "backward Euler at 1 ms: damping error {d1}");
    // The trapezoidal rule's closed form at the same 1 ms: well inside the budget.
    let (p, d) = tissue_core::sim::predicted_error(Integrator::Newmark, 1e-3, fem.damping()).expect("stable");
    assert!(p < 0.001 && d < 0.001, "newmark at 1 ms: {p} {d}");
}
