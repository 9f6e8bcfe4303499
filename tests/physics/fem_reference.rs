//! The FEM reference against exact answers and its own invariants.

use tissue_core::mechanics::cases::{Bc, CaseSolution, LoadCase, benchmark_cases};
use tissue_core::mechanics::fem::{FemModel, StaticSolver};
use tissue_core::mechanics::grid::Grid;
use tissue_core::mechanics::material::Material;

fn max_abs(v: &[[f64; 3]]) -> f64 {
    v.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()))
}

fn solve(m: &Material, bc: Bc) -> (Grid, Vec<LoadCase>, Vec<CaseSolution>) {
    let grid = Grid::paper();
    let cases = benchmark_cases(&grid, &m.name, bc);
    let sols = FemModel::new(grid, m).solve_cases(&cases).expect("FEM solve");
    (grid, cases, sols)
}

#[test]
fn patch_tests_match_uniform_strain_to_1e10() {
    for m in [Material::object_a(), Material::object_b()] {
        let (grid, cases, sols) = solve(&m, Bc::Patch);
        for (c, s) in cases.iter().zip(&sols) {
            let exact = c.patch_exact(&grid, &m.compliance);
            let scale = max_abs(&exact);
            let err = s
                .displacements
                .iter()
                .zip(&exact)
                .flat_map(|(u, e)| (0..3).map(move |k| (u[k] - e[k]).abs()))
                .fold(0.0f64, f64::max);
            assert!(err <= 1e-10 * scale, "{}: relative error {:e}", c.id, err / scale);
            assert!(err <= 5e-12 * scale, "{}: relative error {:e} (round-off expected)", c.id, err / scale);
        }
    }
}

#[test]
fn reactions_balance_the_load() {
    for m in [Material::object_a(), Material::object_b()] {
        for bc in [Bc::Clamped, Bc::Patch] {
            let (_, cases, sols) = solve(&m, bc);
            for (c, s) in cases.iter().zip(&sols) {
                let mut expect = [0.0; 3];
                expect[c.axis - 1] = -c.force_n;
                for k in 0..3 {
                    assert!((s.reaction_n[k] - expect[k]).abs() < 1e-9 * c.force_n, "{}: {:?}", c.id, s.reaction_n);
                }
            }
        }
    }
}

#[test]
fn clamped_answers_are_linear_in_the_force() {
    let (_, cases, sols) = solve(&Material::object_a(), Bc::Clamped);
    for axis in 0..3 {
        let (u1, u5, u10) = (&sols[3 * axis], &sols[3 * axis + 1], &sols[3 * axis + 2]);
        assert_eq!((cases[3 * axis].force_n, cases[3 * axis + 2].force_n), (1.0, 10.0));
        let scale = max_abs(&u1.displacements);
        for ((a, b), c) in u1.displacements.iter().zip(&u5.displacements).zip(&u10.displacements) {
            for k in 0..3 {
                assert!((5.0 * a[k] - b[k]).abs() <= 1e-12 * 5.0 * scale);
                assert!((10.0 * a[k] - c[k]).abs() <= 1e-12 * 10.0 * scale);
            }
        }
    }
}

#[test]
fn object_b_axis3_mirrors_axis2() {
    let (grid, _, sols) = solve(&Material::object_b(), Bc::Clamped);
    for f in 0..3 {
        let (ax2, ax3) = (&sols[3 + f], &sols[6 + f]);
        let scale = max_abs(&ax2.displacements);
        for p in 0..grid.num_nodes() {
            let [i, j, k] = grid.ijk(p);
            let q = grid.node(i, k, j);
            let (a, b) = (ax2.displacements[p], ax3.displacements[q]);
            for (x, y) in [(a[0], b[0]), (a[1], b[2]), (a[2], b[1])] {
                assert!((x - y).abs() <= 1e-12 * scale, "node {p}: {a:?} vs {b:?}");
            }
        }
    }
}

#[test]
fn clamped_fast_path_matches_unreduced_solve_on_paper_grid() {
    let m = Material::object_a();
    let (_, cases, sols) = solve(&m, Bc::Clamped);
    let model = FemModel::new(Grid::paper(), &m);
    let mut full = StaticSolver::new(&model).expect("pattern");
    for (c, fast) in cases.iter().zip(&sols) {
        let s = full.solve_case(&model, c).expect("solve");
        let scale = max_abs(&s.displacements);
        for (x, y) in s.displacements.iter().flatten().zip(fast.displacements.iter().flatten()) {
            assert!((x - y).abs() <= 1e-13 * scale, "{}", c.id);
        }
    }
}

#[test]
fn clamped_solution_is_plausible() {
    // Loaded face moves along +axis; the clamped face stays; stiffer axes move less.
    let (grid, cases, sols) = solve(&Material::object_a(), Bc::Clamped);
    let tip: Vec<f64> = (0..3).map(|a| sols[3 * a + 2].displacements[grid.num_nodes() - 1][a]).collect();
    for (c, s) in cases.iter().zip(&sols) {
        let a = c.axis - 1;
        for p in grid.face_nodes(a, false) {
            assert_eq!(s.displacements[p], [0.0; 3]);
        }
        for p in grid.face_nodes(a, true) {
            assert!(s.displacements[p][a] > 0.0);
        }
    }
    // E1 < E2 < E3 for object A.
    assert!(tip[0] > tip[1] && tip[1] > tip[2], "{tip:?}");
}
