//! Tests of the parent module.

use super::*;
use crate::mechanics::material::Material;

#[test]
fn the_stencil_is_the_element_loop() {
    let material = Material::object_a();
    for n in [2, 3, 5, 8] {
        let grid = Grid::new(n).unwrap();
        let fem = super::super::FemModel::new(grid, &material);
        let stencil = Stencil::new(&grid, &fem.ke);
        let u: Vec<f64> = (0..3 * grid.num_nodes()).map(|d| ((d * 7919) % 101) as f64 * 1e-5 - 5e-4).collect();
        let (mut a, mut b) = (vec![0.0; u.len()], vec![0.0; u.len()]);
        fem.apply_by_elements(&u, &mut a);
        stencil.apply(&u, &mut b);
        let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-12 * scale, "n = {n}: {x} vs {y}");
        }
    }
}

#[test]
fn component_wise_is_interleaved_bit_for_bit() {
    let material = Material::object_b();
    // Runs inside along x of 0, 1, 3, 4, 6, 8, 9, 11 and 14 nodes (the AVX2 path from 4, in
    // groups of eight from 8, the last four overlapping from 6), and 16^3 split over the pool.
    for n in [2, 3, 5, 6, 8, 10, 11, 13, 16] {
        let grid = Grid::new(n).unwrap();
        let fem = super::super::FemModel::new(grid, &material);
        let stencil = Stencil::new(&grid, &fem.ke);
        let nn = grid.num_nodes();
        let u: Vec<f64> = (0..3 * nn).map(|d| ((d * 7919) % 101) as f64 * 1e-5 - 5e-4).collect();
        let split: [Vec<f64>; 3] = std::array::from_fn(|c| (0..nn).map(|p| u[3 * p + c]).collect());
        let mut interleaved = vec![0.0; 3 * nn];
        stencil.apply_on(&u, &mut interleaved, false);
        for parallel in [false, true] {
            let mut out: [Vec<f64>; 3] = std::array::from_fn(|_| vec![f64::NAN; nn]);
            stencil.apply_components_on(&split, &mut out, parallel);
            for p in 0..nn {
                for c in 0..3 {
                    assert_eq!(out[c][p].to_bits(), interleaved[3 * p + c].to_bits(), "n = {n}, node {p}, {c}");
                }
            }
        }
    }
}

#[test]
fn the_f32_product_is_its_scalar_rows_and_near_the_f64_one() {
    let material = Material::object_b();
    // Runs inside along x of 3, 6, 8, 9, 14, 16, 17 and 22 nodes (the AVX2 path from 8, in
    // groups of sixteen from 16, the last eight overlapping), and 16^3 split over the pool.
    for n in [5, 8, 10, 11, 16, 18, 19, 24] {
        let grid = Grid::new(n).unwrap();
        let fem = super::super::FemModel::new(grid, &material);
        let stencil = Stencil::new(&grid, &fem.ke);
        let nn = grid.num_nodes();
        let u: [Vec<f64>; 3] =
            std::array::from_fn(|c| (0..nn).map(|p| (((3 * p + c) * 7919) % 101) as f64 * 1e-5 - 5e-4).collect());
        let u32: [Vec<f32>; 3] = std::array::from_fn(|c| u[c].iter().map(|&v| v as f32).collect());
        let mut exact: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; nn]);
        stencil.apply_components_on(&u, &mut exact, false);
        let scale = exact.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let load = |q: usize| [u32[0][q], u32[1][q], u32[2][q]];
        for parallel in [false, true] {
            let mut out: [Vec<f32>; 3] = std::array::from_fn(|_| vec![f32::NAN; nn]);
            stencil.apply_components_on(&u32, &mut out, parallel);
            for p in 0..nn {
                let (i, j, k) = (p % n, (p / n) % n, p / (n * n));
                let row = row_sum(&stencil.taps_f32[side(i, n) + 3 * side(j, n) + 9 * side(k, n)], p, load);
                for c in 0..3 {
                    assert_eq!(out[c][p].to_bits(), row[c].to_bits(), "n = {n}, node {p}, {c}");
                    let off = (f64::from(out[c][p]) - exact[c][p]).abs();
                    assert!(off <= 1e-5 * scale, "n = {n}, node {p}, {c}: {off:e} of {scale:e}");
                }
            }
        }
    }
}
