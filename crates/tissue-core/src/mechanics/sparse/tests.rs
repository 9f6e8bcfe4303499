//! Tests of the parent module.

use super::*;

#[test]
fn solves_a_tridiagonal_system() {
    let n = 50;
    let mut entries = vec![];
    for i in 0..n {
        entries.push((i, i));
        if i > 0 {
            entries.push((i, i - 1));
        }
    }
    let (mut sys, slots) = SpdSystem::new(n, &entries).unwrap();
    for (e, &(r, c)) in entries.iter().enumerate() {
        sys.add(slots[e], if r == c { 2.0 } else { -1.0 });
    }
    sys.add_diagonal(0.5);
    sys.factor().unwrap();
    let x: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
    let mut b = vec![0.0; n];
    sys.mul(&x, &mut b);
    sys.solve_in_place(&mut b).unwrap();
    for i in 0..n {
        assert!((b[i] - x[i]).abs() < 1e-13);
    }
}

/// A 27-neighbour pattern on `n^3` nodes, three unknowns a node, and an SPD matrix on it
/// (a graph Laplacian per component plus a shift, with a small coupling of the components).
fn grid_system(n: usize) -> (Vec<(usize, usize)>, Vec<f64>) {
    let grid = crate::mechanics::grid::Grid::new(n).unwrap();
    let (mut entries, mut values) = (Vec::new(), Vec::new());
    for p in 0..grid.num_nodes() {
        let [i, j, k] = grid.ijk(p);
        for q in 0..grid.num_nodes() {
            let [a, b, c] = grid.ijk(q);
            if q >= p || i.abs_diff(a) > 1 || j.abs_diff(b) > 1 || k.abs_diff(c) > 1 {
                continue;
            }
            for (r, cc) in [(0, 0), (1, 1), (2, 2), (0, 1)] {
                entries.push((3 * p + r, 3 * q + cc));
                values.push(if r == cc { -1.0 } else { 0.01 });
            }
        }
    }
    (entries, values)
}

#[test]
fn nested_dissection_orders_every_unknown_once_and_solves_as_minimum_degree() {
    let n = 9;
    let grid = crate::mechanics::grid::Grid::new(n).unwrap();
    let order = nested_dissection(&grid.dof_nodes());
    let mut seen = vec![false; 3 * grid.num_nodes()];
    for &u in &order {
        assert!(!std::mem::replace(&mut seen[u as usize], true), "unknown {u} twice");
    }
    assert!(seen.iter().all(|&s| s));
    let (entries, values) = grid_system(n);
    let dofs = 3 * grid.num_nodes();
    let x: Vec<f64> = (0..dofs).map(|i| (i as f64 * 0.37).sin()).collect();
    let mut solved = Vec::new();
    for dissected in [false, true] {
        let (mut sys, slots) = if dissected {
            SpdSystem::on_grid(dofs, &entries, &grid.dof_nodes()).unwrap()
        } else {
            SpdSystem::new(dofs, &entries).unwrap()
        };
        for (&slot, &v) in slots.iter().zip(&values) {
            sys.add(slot, v);
        }
        // Diagonally dominant: 27 neighbours of -1 each at most.
        sys.add_diagonal(30.0);
        sys.factor().unwrap();
        let mut b = vec![0.0; dofs];
        sys.mul(&x, &mut b);
        sys.solve_in_place(&mut b).unwrap();
        solved.push((b, sys.factor_nonzeros()));
    }
    for (a, b) in solved[0].0.iter().zip(&solved[1].0) {
        assert!((a - b).abs() < 1e-12, "{a} against {b}");
    }
    assert!(solved[1].1 < solved[0].1, "dissection fill {} against minimum degree {}", solved[1].1, solved[0].1);
    let wrong = SpdSystem::on_grid(dofs, &entries, &grid.dof_nodes()[1..]);
    assert!(matches!(wrong, Err(SparseError::Pattern(_))));
}

#[test]
fn reports_indefinite() {
    let (mut sys, slots) = SpdSystem::new(2, &[(0, 0), (1, 1), (1, 0)]).unwrap();
    sys.add(slots[0], 1.0);
    sys.add(slots[1], 1.0);
    sys.add(slots[2], 2.0);
    assert!(matches!(sys.factor(), Err(SparseError::NotPositiveDefinite)));
    let mut b = [1.0, 1.0];
    assert!(matches!(sys.solve_in_place(&mut b), Err(SparseError::NotFactored)));
}
