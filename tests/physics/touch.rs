//! The touch benchmark: shipped tissues carry their true validation scores, the default tissue is
//! the best of them, and calibration reaches the optimum of its cost (checked by an independent
//! derivative-free method).

use std::sync::atomic::AtomicBool;

use argmin::core::{CostFunction, Executor};
use argmin::solver::neldermead::NelderMead;
use tissue_core::mechanics::grid::Grid;
use tissue_core::mechanics::material::Material;
use tissue_core::mechanics::msm::{MsmParams, Topology};
use tissue_core::response::linear::{group_values, with_group_values};
use tissue_core::sim::Model;
use tissue_studies::calibrate::{CaseSet, GeneSpace, Problem, Settings, Workspace, calibrate};
use tissue_studies::validate::touch::score::{Reference, evaluate};

#[test]
fn shipped_tissues_record_their_validation_scores_and_the_default_is_the_best() {
    for m in [Material::object_a(), Material::object_b()] {
        let reference = Reference::new(&m, Grid::paper()).expect("reference");
        let mut best = (f64::INFINITY, Topology::Axis);
        for topology in [Topology::Shear, Topology::Hex] {
            let shipped = tissue_core::sim::shipped::shipped(&m, topology).expect("shipped");
            assert_eq!(shipped.cases, CaseSet::Touch, "{} {}", m.name, topology.name());
            let recorded = shipped.validation.expect("recorded scores");
            let r = evaluate(&reference, &m, Model::Lattice(shipped.params.topology()), Some(shipped.params))
                .expect("scores");
            for (a, b) in [
                (recorded.worst_force_error, r.worst_force_error),
                (recorded.median_force_error, r.median_force_error),
                (recorded.worst_frequency_error, r.worst_frequency_error),
            ] {
                assert!(
                    (a - b).abs() <= 1e-9 * b.max(1e-3),
                    "{} {}: recorded {a} vs measured {b}",
                    m.name,
                    topology.name()
                );
            }
            if r.worst_force_error < best.0 {
                best = (r.worst_force_error, topology);
            }
        }
        assert_eq!(best.1, tissue_core::sim::shipped::DEFAULT_TOPOLOGY, "object {}", m.name);
        // The default tissue's lowest six frequencies are within 5 % of the FEM's.
        let default =
            tissue_core::sim::shipped::shipped(&m, tissue_core::sim::shipped::DEFAULT_TOPOLOGY).expect("shipped");
        let f = default.validation.expect("scores").worst_frequency_error;
        assert!(f < 0.05, "object {}: worst frequency error {f}", m.name);
    }
}

/// The objective in `ln theta` of the free groups, for Nelder-Mead.
struct Independent<'a> {
    problem: &'a Problem,
    start: MsmParams,
    free: Vec<usize>,
}

impl CostFunction for Independent<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, s: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        let mut theta = group_values(&self.start);
        for (&g, v) in self.free.iter().zip(s) {
            theta[g] = v.exp();
        }
        let p = with_group_values(&self.start, &theta);
        Ok(self.problem.objective(&p, &mut Workspace::default()).unwrap_or(f64::INFINITY))
    }
}

#[test]
fn calibration_reaches_the_optimum_that_nelder_mead_finds() {
    // A small budget and a coarse grid: the search alone stops short, the polish finishes, and an
    // independent derivative-free search from the material's scale finds nothing better than 1 %.
    let grid = Grid::new(5).expect("grid");
    let m = Material::object_a();
    for (topology, cases) in [(Topology::Shear, CaseSet::Paper), (Topology::Hex, CaseSet::Touch)] {
        let problem = Problem::new(m.clone(), grid, topology).and_then(|p| p.with_cases(cases)).expect("problem");
        let space = GeneSpace::new(&m, &grid, topology);
        let settings = Settings { population: 10, generations: 10, ..Settings::default() };
        let r = calibrate(&problem, &space, &settings, &AtomicBool::new(false), &mut |_| {}).expect("calibrates");
        let mid: Vec<f64> = space.lo.iter().zip(&space.hi).map(|(l, h)| (l * h).sqrt()).collect();
        let start = space.params(&mid);
        let free: Vec<usize> = (0..6 + usize::from(topology == Topology::Hex)).collect();
        let s0: Vec<f64> = free.iter().map(|&g| group_values(&start)[g].ln()).collect();
        let simplex: Vec<Vec<f64>> = std::iter::once(s0.clone())
            .chain((0..s0.len()).map(|i| {
                let mut v = s0.clone();
                v[i] += 0.5;
                v
            }))
            .collect();
        let nm = NelderMead::new(simplex).with_sd_tolerance(1e-12).expect("simplex");
        let independent = Executor::new(Independent { problem: &problem, start, free }, nm)
            .configure(|s| s.max_iters(4000))
            .run()
            .expect("Nelder-Mead runs");
        let best = independent.state().best_cost;
        assert!(
            r.cost <= best * 1.01,
            "{} on {} cases: calibrated {} vs Nelder-Mead {best}",
            topology.name(),
            cases.name(),
            r.cost
        );
    }
}
