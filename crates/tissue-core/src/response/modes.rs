//! The lowest natural frequencies of a model on the touch scene: `K phi = omega^2 M phi` with
//! lumped (diagonal) masses, by subspace iteration on the factorised stiffness with a
//! Rayleigh-Ritz projection each step.

use crate::mechanics::sparse::SparseError;
use crate::response::linear::SceneSolver;

/// Iteration limit of the subspace iteration.
const MAX_ITERATIONS: usize = 500;
/// Converged when every wanted eigenvalue changes by less than this, relatively, in one step.
const TOLERANCE: f64 = 1e-12;

/// The lowest `count` natural frequencies, Hz, ascending; `mass` per dof (kg), zero on fixed dofs.
pub fn lowest_frequencies_hz(solver: &mut SceneSolver, mass: &[f64], count: usize) -> Result<Vec<f64>, SparseError> {
    let modes = lowest_modes(solver, mass, count)?;
    Ok(modes.iter().map(|m| m.omega / (2.0 * std::f64::consts::PI)).collect())
}

/// A natural mode: `K phi = omega^2 M phi`.
#[derive(Debug, Clone, PartialEq)]
pub struct Mode {
    /// Angular frequency, rad/s.
    pub omega: f64,
    /// Shape over all dofs, mass-normalised (`phi^T M phi = 1`), zero on fixed dofs.
    pub shape: Vec<f64>,
}

/// The lowest `count` modes, ascending; `mass` per dof (kg), zero on fixed dofs.
pub fn lowest_modes(solver: &mut SceneSolver, mass: &[f64], count: usize) -> Result<Vec<Mode>, SparseError> {
    let dofs = mass.len();
    let block = (2 * count).max(count + 8);
    // A deterministic, generic start: no eigenvector is orthogonal to all of these.
    let mut x: Vec<Vec<f64>> = (0..block)
        .map(|j| {
            (0..dofs)
                .map(|i| if mass[i] > 0.0 { ((i * (j + 1)) as f64 * 0.754_877).sin() + 0.1 } else { 0.0 })
                .collect()
        })
        .collect();
    let mut previous = vec![f64::INFINITY; count];
    let mut values = Vec::new();
    for _ in 0..MAX_ITERATIONS {
        // Y = K^-1 M X; then K Y = M X, so Y^T K Y = Y^T M X.
        let mx: Vec<Vec<f64>> = x.iter().map(|v| v.iter().zip(mass).map(|(a, m)| a * m).collect()).collect();
        let mut y = mx.clone();
        for v in &mut y {
            solver.solve(v)?;
        }
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(p, q)| p * q).sum::<f64>();
        let kr = nalgebra::DMatrix::from_fn(block, block, |i, j| 0.5 * (dot(&y[i], &mx[j]) + dot(&y[j], &mx[i])));
        let mr = nalgebra::DMatrix::from_fn(block, block, |i, j| {
            y[i].iter().zip(&y[j]).zip(mass).map(|((a, b), m)| a * b * m).sum::<f64>()
        });
        let l = mr.cholesky().ok_or(SparseError::NotPositiveDefinite)?.unpack();
        let l_inv = l.clone().try_inverse().ok_or(SparseError::NotPositiveDefinite)?;
        let a = &l_inv * kr * l_inv.transpose();
        let eig = nalgebra::SymmetricEigen::new(0.5 * (&a + a.transpose()));
        let mut order: Vec<usize> = (0..block).collect();
        order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
        let phi = l_inv.transpose() * &eig.eigenvectors;
        x = order
            .iter()
            .map(|&k| (0..dofs).map(|i| (0..block).map(|j| y[j][i] * phi[(j, k)]).sum()).collect())
            .collect();
        values = order.iter().take(count).map(|&k| eig.eigenvalues[k]).collect::<Vec<f64>>();
        let converged = values.iter().zip(&previous).all(|(v, p)| (v - p).abs() <= TOLERANCE * v.abs());
        previous.clone_from(&values);
        if converged {
            break;
        }
    }
    // The Ritz vectors are M-orthonormal (`Y^T M Y = L L^T`).
    Ok(values.iter().zip(x).map(|(w2, shape)| Mode { omega: w2.max(0.0).sqrt(), shape }).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::grid::Grid;
    use crate::mechanics::msm::{MsmModel, MsmParams};
    use crate::response::linear::GroupedStiffness;

    #[test]
    fn subspace_iteration_matches_a_dense_eigensolve() {
        let grid = Grid::new(3).unwrap();
        let params = MsmParams {
            c12: Some(40.0),
            c13: Some(50.0),
            c23: Some(60.0),
            ..MsmParams::axis(100.0, 200.0, 300.0, 0.0)
        };
        let model = MsmModel::new(grid, params, 1000.0).unwrap();
        let k = GroupedStiffness::lattice(grid, params.topology());
        let theta = crate::response::linear::group_values(&params);
        let mut solver = SceneSolver::new(&grid, &k).unwrap();
        solver.factor(&k, &theta).unwrap();
        let fixed = crate::response::linear::scene_fixed_dofs(&grid);
        let mass: Vec<f64> = fixed.iter().map(|&f| if f { 0.0 } else { model.node_mass }).collect();
        let hz = lowest_frequencies_hz(&mut solver, &mass, 6).unwrap();
        // Dense reference on the free dofs.
        let free: Vec<usize> = (0..mass.len()).filter(|&d| !fixed[d]).collect();
        let dofs = mass.len();
        let mut dense = nalgebra::DMatrix::zeros(free.len(), free.len());
        for (j, &dj) in free.iter().enumerate() {
            let mut e = vec![0.0; dofs];
            e[dj] = 1.0;
            let mut col = vec![0.0; dofs];
            k.mul(&theta, &e, &mut col);
            for (i, &di) in free.iter().enumerate() {
                dense[(i, j)] = col[di] / model.node_mass;
            }
        }
        let mut w: Vec<f64> = nalgebra::SymmetricEigen::new(dense).eigenvalues.iter().copied().collect();
        w.sort_by(f64::total_cmp);
        for (f, w2) in hz.iter().zip(&w) {
            let expected = w2.sqrt() / (2.0 * std::f64::consts::PI);
            assert!((f - expected).abs() <= 1e-9 * expected, "{f} vs {expected}");
        }
    }
}
