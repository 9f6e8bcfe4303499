//! Calibration: the paper's GA+SA against an independent exact optimum, reliability against the
//! pure GA, determinism on any thread count, cancellation.

use std::sync::atomic::{AtomicBool, Ordering};

use tissue_core::mechanics::grid::Grid;
use tissue_core::mechanics::material::Material;
use tissue_core::mechanics::msm::Topology;
use tissue_studies::calibrate::{GeneSpace, Method, Problem, Settings, calibrate};

fn problem(m: Material) -> (Problem, GeneSpace) {
    let space = GeneSpace::new(&m, &Grid::paper(), Topology::Axis);
    (Problem::new(m, Grid::paper(), Topology::Axis).expect("FEM references"), space)
}

fn run(p: &Problem, space: &GeneSpace, s: &Settings) -> tissue_studies::calibrate::CalibrationResult {
    calibrate(p, space, s, &AtomicBool::new(false), &mut |_| {}).expect("calibration runs")
}

#[test]
fn hybrid_reaches_the_exact_optimum_within_0_1_percent() {
    for m in [Material::object_a(), Material::object_b()] {
        let (p, space) = problem(m);
        let (k, optimum) = p.axis_optimum();
        // The exact optimum is a minimum: nudging any stiffness raises the cost.
        let mut ws = tissue_studies::calibrate::Workspace::default();
        for a in 0..3 {
            for f in [0.99, 1.01] {
                let mut kk = k;
                kk[a] *= f;
                if p.material.is_transversely_isotropic() && a > 0 {
                    kk[1] = kk[a];
                    kk[2] = kk[a];
                }
                let c = p
                    .cost(&tissue_core::mechanics::msm::MsmParams::axis(kk[0], kk[1], kk[2], 0.0), &mut ws)
                    .expect("cost");
                assert!(c > optimum, "{}: k{} x {f} gives {c} <= {optimum}", p.material.name, a + 1);
            }
        }
        let r = run(&p, &space, &Settings::default());
        assert!(r.cost <= optimum * 1.001, "{}: hybrid cost {} vs optimum {optimum}", p.material.name, r.cost);
        assert!(r.cost >= optimum * (1.0 - 1e-12), "below the exact optimum?");
        assert_eq!(r.history.len(), 101);
        assert!(!r.d_identified && r.params.d > 0.0);
    }
}

#[test]
fn hybrid_is_at_least_as_reliable_as_pure_ga() {
    let (p, space) = problem(Material::object_a());
    let (_, optimum) = p.axis_optimum();
    let hits = |method: Method| {
        (0..20u64)
            .filter(|&seed| run(&p, &space, &Settings { method, seed, ..Settings::default() }).cost <= optimum * 1.001)
            .count()
    };
    let (hybrid, ga) = (hits(Method::Hybrid), hits(Method::Ga));
    assert!(hybrid >= ga, "hybrid {hybrid}/20 vs GA {ga}/20 within 0.1 %");
    assert!(hybrid >= 18, "hybrid reached the optimum in only {hybrid}/20 seeds");
}

#[test]
fn same_seed_same_result_on_any_thread_count() {
    let (p, space) = problem(Material::object_b());
    let s = Settings { seed: 7, ..Settings::default() };
    let json = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
        let mut r = pool.install(|| run(&p, &space, &s));
        r.wall_s = 0.0; // the only key that may differ
        serde_json::to_string(&r).expect("json")
    };
    let one = json(1);
    assert_eq!(one, json(2));
    assert_eq!(one, json(2));
    for method in [Method::Ga, Method::Sa] {
        let a = run(&p, &space, &Settings { method, seed: 3, ..Settings::default() });
        let b = run(&p, &space, &Settings { method, seed: 3, ..Settings::default() });
        assert_eq!((a.params, a.cost, a.evaluations), (b.params, b.cost, b.evaluations));
    }
    let other = run(&p, &space, &Settings { seed: 8, ..Settings::default() });
    assert_ne!(other.params, run(&p, &space, &s).params, "another seed should search differently");
}

#[test]
fn cancel_takes_effect_within_one_generation() {
    let (p, space) = problem(Material::object_a());
    let cancel = AtomicBool::new(false);
    let mut seen = 0;
    let r = calibrate(&p, &space, &Settings::default(), &cancel, &mut |s| {
        seen = s.generation;
        if s.generation == 3 {
            cancel.store(true, Ordering::Relaxed);
        }
    })
    .expect("runs");
    assert!(r.cancelled);
    assert_eq!(seen, 3);
    assert_eq!(r.history.len(), 4);
    assert!(r.cost.is_finite());
}

#[test]
fn shear_model_calibration_beats_the_axis_optimum() {
    let m = Material::object_a();
    let space = GeneSpace::new(&m, &Grid::paper(), Topology::Shear);
    let p = Problem::new(m, Grid::paper(), Topology::Shear).expect("FEM");
    let (_, axis_optimum) = problem(Material::object_a()).0.axis_optimum();
    // A short run: the diagonals must already buy a clearly lower cost than the best axis model.
    let r = run(&p, &space, &Settings { population: 16, generations: 8, ..Settings::default() });
    assert!(r.params.c12.is_some() && r.params.c23.is_some());
    assert!(r.cost < 0.9 * axis_optimum, "shear {} vs axis optimum {axis_optimum}", r.cost);
}

#[test]
fn a_result_applies_to_a_running_model() {
    use tissue_core::mechanics::cases::LoadCase;
    use tissue_core::mechanics::msm::{Dynamics, MsmModel, MsmParams};
    let (p, space) = problem(Material::object_a());
    let r = run(&p, &space, &Settings { generations: 20, ..Settings::default() });
    let grid = Grid::paper();
    let before = MsmModel::new(grid, MsmParams::axis(900.0, 900.0, 900.0, r.params.d), 1040.0).expect("model");
    let mut dynamics = Dynamics::new(&before);
    dynamics.apply_case(&LoadCase::clamped(&grid, "A", 1, 5.0));
    for _ in 0..100 {
        dynamics.step_implicit(&before, 1e-3).expect("step");
    }
    let after = MsmModel::new(grid, r.params, 1040.0).expect("calibrated model");
    dynamics.set_model(&after);
    for _ in 0..3000 {
        dynamics.step_implicit(&after, 1e-3).expect("step");
    }
    // Relaxes to the calibrated model's own equilibrium.
    let tip = dynamics.displacements(&after)[grid.num_nodes() - 1][0];
    let expect = 7.0 * 5.0 / 64.0 / r.params.k1;
    assert!((tip - expect).abs() < 1e-6 * expect, "{tip} vs {expect}");
}

#[test]
#[ignore = "slow: in the slow group, cargo test --release -- --ignored"]
fn hex_lattice_meets_the_richer_model_targets_at_10_newtons() {
    // The target: at 10 N the richer calibrated MSM has at most 1/3 of the paper model's
    // average and 2/3 of its maximum nodal error, on both objects. The paper model here is the
    // axis lattice at the exact optimum of the same cost (the best it can do); the hex lattice is
    // calibrated on the same cases (the load-free stiffness fit, polished on the paper's cost).
    for m in [Material::object_a(), Material::object_b()] {
        let name = m.name.clone();
        let (axis_problem, _) = problem(m.clone());
        let (k, _) = axis_problem.axis_optimum();
        let hex_problem = Problem::new(m.clone(), Grid::paper(), Topology::Hex).expect("FEM references");
        let mut ws = tissue_studies::calibrate::Workspace::default();
        let fem = tissue_core::mechanics::fem::FemModel::new(Grid::paper(), &m);
        let (fit, _) =
            tissue_studies::calibrate::fit::stiffness_fit(&fem, Topology::Hex, m.is_transversely_isotropic());
        let mut objective = |p: &tissue_core::mechanics::msm::MsmParams| {
            hex_problem
                .paper_gradient(p, &mut tissue_studies::calibrate::Workspace::default())
                .map_err(|e| e.to_string())
        };
        let hex = tissue_studies::calibrate::polish::polish(&fit, m.is_transversely_isotropic(), &mut objective)
            .expect("polish")
            .params;
        let h = Grid::paper().h();
        let mut errors = |p: &Problem, params| {
            let s = p.static_solutions(&params, &mut ws).expect("static solve");
            tissue_studies::validate::accuracy::case_errors(h, &s, &p.fem)
        };
        let paper = errors(&axis_problem, tissue_core::mechanics::msm::MsmParams::axis(k[0], k[1], k[2], 0.0));
        let rich = errors(&hex_problem, hex);
        for (p, r) in paper.iter().zip(&rich).filter(|(p, _)| p.force_n == 10.0) {
            assert!(
                r.avg_pct <= p.avg_pct / 3.0,
                "{name} axis {}: avg {} vs paper model {}",
                p.axis,
                r.avg_pct,
                p.avg_pct
            );
            assert!(
                r.max_pct <= p.max_pct * 2.0 / 3.0,
                "{name} axis {}: max {} vs paper model {}",
                p.axis,
                r.max_pct,
                p.max_pct
            );
        }
    }
}
