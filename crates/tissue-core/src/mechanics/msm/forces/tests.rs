//! Tests of the parent module.

use super::*;
use crate::mechanics::grid::Grid;
use crate::mechanics::msm::model::{MsmParams, Topology};

/// A hex lattice with every family's stiffness distinct.
fn hex_model(grid: Grid) -> MsmModel {
    let params = MsmParams {
        k1: 40.0,
        k2: 50.0,
        k3: 60.0,
        d: 0.0,
        c12: Some(10.0),
        c13: Some(11.0),
        c23: Some(12.0),
        b: Some(5.0),
    };
    MsmModel::new(grid, params, 1000.0).expect("model")
}

/// The explicit step's pair loop (reciprocal square root and Newton steps where AVX2 runs)
/// gives the exact loop's forces within 1e-12 of the largest, on a hex lattice at 9^3 (its
/// last pairs one by one) with every node moved off its rest position.
#[test]
fn the_fast_pair_loop_is_the_exact_one() {
    let grid = Grid::new(9).expect("grid");
    let model = hex_model(grid);
    let nn = grid.num_nodes();
    let x: [Vec<f64>; 3] =
        std::array::from_fn(|c| (0..nn).map(|p| grid.position(p)[c] + 1e-3 * ((p * (c + 3)) % 7) as f64).collect());
    let mut forces = [false, true].map(|fast| {
        let mut f: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; nn]);
        let mut scratch = ForceScratch::new(&model);
        if fast {
            accumulate_spring_forces::<true>(&model, &x, &mut f, &mut scratch);
        } else {
            accumulate_spring_forces::<false>(&model, &x, &mut f, &mut scratch);
        }
        f
    });
    let [exact, fast] = std::mem::take(&mut forces);
    let scale = exact.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(scale > 0.1, "{scale}");
    for (e, f) in exact.iter().flatten().zip(fast.iter().flatten()) {
        assert!((e - f).abs() <= 1e-12 * scale, "{e} vs {f}");
    }
}

/// The matrix-free tangent product is the assembled tangent's, with every spring stretched,
/// compressed and turned (hex lattice at 5^3, no node held).
#[test]
fn the_tangent_product_is_the_assembled_tangents() {
    let grid = Grid::new(5).expect("grid");
    let model = hex_model(grid);
    let nn = grid.num_nodes();
    let x: [Vec<f64>; 3] = std::array::from_fn(|c| {
        (0..nn).map(|p| 1.1 * grid.position(p)[c] + 4e-3 * ((p * (c + 3)) % 7) as f64 - 3e-3).collect()
    });
    let p: [Vec<f64>; 3] = std::array::from_fn(|c| (0..nn).map(|q| ((q * 3 + c) as f64 * 0.37).sin()).collect());
    let mut out: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; nn]);
    tangent_product(&model, &x, &p, &mut out, &mut ForceScratch::new(&model));
    let dofs = DofMap::free(&vec![false; nn]);
    let mut tangent = TangentAssembler::new(&model, dofs).expect("pattern");
    tangent.assemble(&model, &x, 1.0, 0.0, true, None);
    let flat: Vec<f64> = (0..3 * nn).map(|i| p[i % 3][i / 3]).collect();
    let mut want = vec![0.0; 3 * nn];
    tangent.system.mul(&flat, &mut want);
    let scale = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(scale > 1.0, "{scale}");
    for i in 0..3 * nn {
        assert!((out[i % 3][i / 3] - want[i]).abs() <= 1e-12 * scale, "dof {i}: {} vs {}", out[i % 3][i / 3], want[i]);
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
    /// The springs' forces on any lattice at any positions sum to zero (each spring pushes its two
    /// ends equally and oppositely), and so do their moments about the origin.
    #[test]
    fn spring_forces_sum_to_zero(
        n in 2usize..6,
        hex in proptest::bool::ANY,
        seed in proptest::collection::vec(-1.0f64..1.0, 3 * 216),
    ) {
        let grid = Grid::new(n).unwrap();
        let topology = if hex { Topology::Hex } else { Topology::Shear };
        let params = MsmParams { k1: 900.0, k2: 1100.0, k3: 1300.0, ..MsmParams::unit(topology) };
        let model = MsmModel::new(grid, params, 1040.0).unwrap();
        let nn = grid.num_nodes();
        let x: [Vec<f64>; 3] =
            std::array::from_fn(|c| (0..nn).map(|p| grid.position(p)[c] + 5e-3 * seed[3 * p + c]).collect());
        let mut f: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; nn]);
        add_spring_forces(&model, &x, &mut f, &mut ForceScratch::new(&model));
        let largest = f.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for c in 0..3 {
            let sum: f64 = f[c].iter().sum();
            proptest::prop_assert!(sum.abs() <= 1e-9 * largest.max(1.0), "sum {} of component {}", sum, c);
        }
        let moment: [f64; 3] = std::array::from_fn(|c| {
            let (a, b) = ((c + 1) % 3, (c + 2) % 3);
            (0..nn).map(|p| x[a][p] * f[b][p] - x[b][p] * f[a][p]).sum()
        });
        proptest::prop_assert!(moment.iter().all(|m| m.abs() <= 1e-9 * largest.max(1.0)), "moment {:?}", moment);
    }
}
