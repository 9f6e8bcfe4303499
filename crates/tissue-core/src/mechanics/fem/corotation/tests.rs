//! The corotated element force's tests.

use super::*;
use crate::mechanics::fem::FemModel;
use crate::mechanics::material::Material;

/// Positions of a grid stretched by `stretch` along x, moved by up to `wobble` metres (so that
/// no two elements deform alike), then turned by `angle` about z.
fn deformed(grid: &Grid, angle: f64, stretch: f64, wobble: f64) -> [Vec<f64>; 3] {
    let (s, c) = angle.sin_cos();
    let mut x: [Vec<f64>; 3] = std::array::from_fn(|_| Vec::new());
    for p in 0..grid.num_nodes() {
        let r = grid.position(p);
        let wobble = wobble * ((p * 7919) % 13) as f64 / 13.0;
        let (px, py) = (stretch * r[0] + wobble, r[1]);
        x[0].push(c * px - s * py);
        x[1].push(s * px + c * py);
        x[2].push(r[2] - wobble);
    }
    x
}

/// Two iterations of the rotations, to a tolerance none reaches.
const TWO: (usize, f64) = (2, 1e-12);

/// `f` on object A's elements at positions `x`, the rotations iterated `turn = (most
/// iterations, tolerance)` (the dense product where `dense`).
fn with_corotation<R>(
    grid: Grid,
    x: &[Vec<f64>; 3],
    (iterations, tolerance): (usize, f64),
    dense: bool,
    f: impl FnOnce(&Corotation<'_>, &FemModel) -> R,
) -> R {
    let fem = FemModel::new(grid, &Material::object_a());
    let parity = if dense { None } else { ParityBlocks::of(&fem.ke) };
    let at = Corotation {
        x: [&x[0], &x[1], &x[2]],
        rest_spacing: grid.h(),
        ke: &fem.ke,
        parity: parity.as_ref(),
        grid,
        iterations,
        tolerance,
    };
    f(&at, &fem)
}

/// Each element alone (one lane, scalar): its rotation from the identity and its force on
/// its nodes (element order).
fn element_forces(grid: Grid, x: &[Vec<f64>; 3], turn: (usize, f64), dense: bool) -> (Vec<[f64; 4]>, Vec<[f64; 24]>) {
    with_corotation(grid, x, turn, dense, |at, fem| {
        let mut out = (Vec::new(), Vec::new());
        for nodes in fem.elements() {
            let (mut next, mut forces) = ([[0.0; 4]], [[0.0; 4]; 24]);
            at.elements::<f64>(nodes[0], &[IDENTITY], &mut next, &mut forces, 0);
            out.0.push(next[0]);
            out.1.push(forces.map(|v| v[0]));
        }
        out
    })
}

/// The rotations from the identity and `-` the elements' forces summed on the nodes.
fn node_forces(
    grid: Grid,
    x: &[Vec<f64>; 3],
    turn: (usize, f64),
    parallel: bool,
    dense: bool,
) -> (Vec<[f64; 4]>, [Vec<f64>; 3]) {
    with_corotation(grid, x, turn, dense, |at, fem| {
        let elements = fem.elements().len();
        let (last, mut next) = (vec![IDENTITY; elements], vec![[0.0; 4]; elements]);
        let mut out: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; grid.num_nodes()]);
        at.all(&last, &mut next, &mut out, parallel);
        (next, out)
    })
}

#[test]
fn every_elements_force_is_summed_once_on_its_nodes() {
    // 1, 2, 4 (one group of four), 6 (one group and an overlapping one), 8 (two groups) and 9
    // elements a row.
    for n in [2, 3, 5, 7, 9, 10] {
        let grid = Grid::new(n).unwrap();
        let x = deformed(&grid, 0.2, 1.05, 1e-3);
        let (q, f) = element_forces(grid, &x, TWO, false);
        let fem = FemModel::new(grid, &Material::object_a());
        let mut expected: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; grid.num_nodes()]);
        for (nodes, fe) in fem.elements().iter().zip(&f) {
            for (a, &p) in nodes.iter().enumerate() {
                for c in 0..3 {
                    expected[c][p] -= fe[3 * a + c];
                }
            }
        }
        let (qn, got) = node_forces(grid, &x, TWO, false, false);
        assert_eq!(q, qn, "n = {n}: the rotations in lanes and alone");
        let scale = expected.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 0.0);
        for (e, g) in expected.iter().flatten().zip(got.iter().flatten()) {
            assert!((e - g).abs() <= 1e-13 * scale, "n = {n}: {e} vs {g}");
        }
    }
}

#[test]
fn a_rigid_turn_gives_no_force_once_the_rotation_has_converged() {
    for n in [3, 6, 12] {
        let grid = Grid::new(n).unwrap();
        let x = deformed(&grid, 0.3, 1.0, 0.0);
        let (q, _) = node_forces(grid, &x, (0, 1e-12), false, false);
        let (q1, f) = node_forces(grid, &x, (60, 1e-12), false, false);
        assert!(q.iter().all(|q| *q == IDENTITY));
        let worst = f.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(worst < 1e-9, "n = {n}: force {worst} N on a rigid turn");
        // The turn found is 0.3 rad about z: q = (cos 0.15, 0, 0, sin 0.15).
        for q in &q1 {
            assert!((q[0] - 0.15f64.cos()).abs() < 1e-10 && (q[3] - 0.15f64.sin()).abs() < 1e-10, "{q:?}");
        }
    }
}

/// A lane that stops after a small Newton step ([`SETTLED`]) without measuring again is still
/// within the tolerance: each element starts 2.6e-5 rad (just under the threshold) from its
/// converged rotation, stretched up to 20 % or compressed up to 40 %, and ends within the
/// step's 1e-8 rad of it.
#[test]
fn a_settled_rotation_is_within_the_tolerance() {
    let grid = Grid::new(7).unwrap();
    for (angle, stretch, wobble) in [(0.2, 1.05, 1e-3), (1.0, 1.2, 3e-3), (0.0, 0.9, 2e-3), (0.5, 0.6, 4e-3)] {
        let x = deformed(&grid, angle, stretch, wobble);
        let (exact, _) = node_forces(grid, &x, (60, 1e-15), false, false);
        let h = [1e-5, -0.7e-5, 0.5e-5]; // half of a 2.6e-5 rad turn
        let start: Vec<[f64; 4]> = exact
            .iter()
            .map(|&[w, vx, vy, vz]| {
                let v = [vx, vy, vz];
                let hv = [h[1] * v[2] - h[2] * v[1], h[2] * v[0] - h[0] * v[2], h[0] * v[1] - h[1] * v[0]];
                let nw = w - (h[0] * v[0] + h[1] * v[1] + h[2] * v[2]);
                let nv: [f64; 3] = std::array::from_fn(|c| v[c] + w * h[c] + hv[c]);
                let norm = (nw * nw + nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]).sqrt();
                [nw / norm, nv[0] / norm, nv[1] / norm, nv[2] / norm]
            })
            .collect();
        let settled =
            with_corotation(grid, &x, (super::ROTATION_ITERATIONS, 1e-8), false, |at, _| {
                let mut next = vec![[0.0; 4]; start.len()];
                let mut out: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; grid.num_nodes()]);
                at.all(&start, &mut next, &mut out, false);
                next
            });
        for (q, e) in settled.iter().zip(&exact) {
            // The angle between them: twice the vector part of e^-1 q, to first order.
            let w = e[0] * q[0] + e[1] * q[1] + e[2] * q[2] + e[3] * q[3];
            let v: [f64; 3] = [
                e[0] * q[1] - e[1] * q[0] - (e[2] * q[3] - e[3] * q[2]),
                e[0] * q[2] - e[2] * q[0] - (e[3] * q[1] - e[1] * q[3]),
                e[0] * q[3] - e[3] * q[0] - (e[1] * q[2] - e[2] * q[1]),
            ];
            let turn = 2.0 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt() / w.abs();
            assert!(turn <= 1e-8, "stretch {stretch}, angle {angle}: {turn:e} rad from the converged rotation");
        }
    }
}

#[test]
fn every_element_has_the_same_bits_in_any_lane_and_on_any_split() {
    // 13 elements a row: three groups of four and one overlapping; 6: one and one overlapping.
    // Two iterations for all; then to the step's tolerance from the identity, where the
    // elements of a group stop after different numbers of iterations.
    let to_tolerance = (super::ROTATION_ITERATIONS, 1e-8);
    for (n, turn) in [(7, TWO), (14, TWO), (7, to_tolerance), (14, to_tolerance)] {
        let grid = Grid::new(n).unwrap();
        let x = deformed(&grid, 0.2, 1.05, 1e-3);
        let (q, f) = node_forces(grid, &x, turn, false, false);
        let (qp, fp) = node_forces(grid, &x, turn, true, false);
        assert_eq!(q, qp);
        assert_eq!(f, fp);
        // Each element alone against its lane in the loop's groups.
        let (alone_q, _) = element_forces(grid, &x, turn, false);
        assert_eq!(q, alone_q, "n = {n}, {turn:?}");
        // Four elements in AVX2 lanes against each alone.
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            #[target_feature(enable = "avx2")]
            fn group_avx2(at: &Corotation<'_>, node: usize, next: &mut [[f64; 4]], out: &mut GroupForces) {
                at.elements::<lanes::F64x4>(node, &[IDENTITY; 4], next, out, 0);
            }
            let (alone_q, alone_f) = element_forces(grid, &x, turn, false);
            with_corotation(grid, &x, turn, false, |at, fem| {
                let m = grid.n() - 1;
                for (e, nodes) in fem.elements().iter().enumerate().filter(|(e, _)| e % m + 4 <= m) {
                    let (mut next, mut out) = ([[0.0; 4]; 4], [[0.0; 4]; 24]);
                    // SAFETY: the CPU has AVX2, checked above.
                    unsafe { group_avx2(at, nodes[0], &mut next, &mut out) };
                    for l in 0..4 {
                        assert_eq!(next[l], alone_q[e + l], "element {}", e + l);
                        assert_eq!(out.map(|v| v[l]), alone_f[e + l], "element {}", e + l);
                    }
                }
            });
        }
    }
}

#[test]
fn the_parity_blocks_are_the_element_matrix() {
    for material in [Material::object_a(), Material::object_b()] {
        let ke = FemModel::new(Grid::new(5).unwrap(), &material).ke;
        let parity = ParityBlocks::of(&ke).expect("an orthotropic cube has the parity form");
        let local: [V3<f64>; 8] =
            std::array::from_fn(|a| std::array::from_fn(|c| ((3 * a + c) * 7919 % 23) as f64 * 1e-4 - 1e-3));
        let (dense, blocks) = (dense_product(&ke, &local), parity.apply(&local));
        let scale = dense.as_flattened().iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (d, b) in dense.as_flattened().iter().zip(blocks.as_flattened()) {
            assert!((d - b).abs() <= 1e-12 * scale, "{d} vs {b}");
        }
        // Coupling the x displacement of node 0 with the y of node 1 alone breaks the
        // reflections: no parity form, the dense product instead.
        let mut skew = ke;
        skew[(0, 4)] += 1e-3 * scale;
        skew[(4, 0)] += 1e-3 * scale;
        assert!(ParityBlocks::of(&skew).is_none());
    }
}

#[test]
fn the_dense_and_the_parity_products_turn_alike() {
    let grid = Grid::new(9).unwrap();
    let x = deformed(&grid, 0.4, 1.1, 2e-3);
    let (q, f) = node_forces(grid, &x, TWO, false, false);
    let (qd, fd) = node_forces(grid, &x, TWO, false, true);
    assert_eq!(q, qd, "the rotations do not depend on the product");
    let scale = fd.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for (a, b) in f.iter().flatten().zip(fd.iter().flatten()) {
        assert!((a - b).abs() <= 1e-12 * scale, "{a} vs {b}");
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(32))]
    /// Any rigid turn about z of any small grid gives no corotated force once the rotations have
    /// converged.
    #[test]
    fn a_rigid_turn_gives_no_corotated_force(angle in -3.1f64..3.1, n in 2usize..6) {
        let grid = Grid::new(n).unwrap();
        let x = deformed(&grid, angle, 1.0, 0.0);
        let (_, f) = node_forces(grid, &x, (60, 1e-13), false, false);
        let worst = f.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        proptest::prop_assert!(worst < 1e-8, "force {} N on a rigid turn of {} rad", worst, angle);
    }
}
