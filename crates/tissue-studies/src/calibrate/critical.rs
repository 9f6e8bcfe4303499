//! The damping criterion used when the data cannot identify `d`: critical damping of the slowest
//! mode the benchmark excites.
//!
//! For each loaded axis the model is clamped on face `x_a = 0` and restricted to the
//! mirror-symmetric subspace of that case (the loads of the benchmark excite nothing else; it also
//! removes the zero-frequency shear modes of the axis-only lattice). The smallest eigenvalue of
//! `K c = omega^2 P^T M P c` (the model's node masses) comes from inverse iteration with the
//! rest tangent's sparse Cholesky factorisation; `d = 2 m omega_min` over the three axes, `m` the
//! mean node mass, makes that mode critically damped (nodal damping `-d v` damps a mode at rate
//! `d / 2m` where the masses are equal).

use crate::mechanics::msm::MsmModel;
use crate::mechanics::msm::forces::TangentAssembler;
use crate::mechanics::msm::reduction::DofMap;

use crate::calibrate::cost::CostError;

/// `(d, omega_min)`: the critical nodal damping (N s/m) of the slowest benchmark-symmetric mode
/// and its angular frequency (rad/s).
pub fn critical_damping(model: &MsmModel) -> Result<(f64, f64), CostError> {
    let grid = model.grid;
    let rest: [Vec<f64>; 3] = std::array::from_fn(|c| (0..grid.num_nodes()).map(|p| grid.position(p)[c]).collect());
    let mut omega_min = f64::INFINITY;
    for axis in 0..3 {
        let mut t = TangentAssembler::new(model, DofMap::clamped_symmetric(&grid, axis))?;
        t.assemble(model, &rest, 1.0, 0.0, false, None);
        t.system.factor()?;
        let n = t.dofs.n;
        // The mass of each unknown (D m for equal masses): c^T M c = 1 below.
        let mut w = vec![0.0; n];
        t.dofs.fold_masses(&model.masses, &mut w);
        let mut c: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64 * 0.1).collect();
        let mut kc = vec![0.0; n];
        let mut lambda = 0.0;
        for _ in 0..500 {
            let mut y: Vec<f64> = c.iter().zip(&w).map(|(ci, wi)| ci * wi).collect();
            t.system.solve_in_place(&mut y)?;
            let norm = y.iter().zip(&w).map(|(yi, wi)| yi * yi * wi).sum::<f64>().sqrt();
            c = y.into_iter().map(|v| v / norm).collect();
            t.system.mul(&c, &mut kc);
            let next = c.iter().zip(&kc).map(|(a, b)| a * b).sum::<f64>(); // c^T K c, with c^T D c = 1
            let done = (next - lambda).abs() <= 1e-13 * next;
            lambda = next;
            if done {
                break;
            }
        }
        omega_min = omega_min.min(lambda.sqrt());
    }
    Ok((2.0 * model.node_mass * omega_min, omega_min))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::grid::Grid;
    use crate::mechanics::msm::MsmParams;

    #[test]
    fn axis_model_matches_the_chain_formula() {
        // The slowest symmetric mode of the axis lattice is the axial mode of the softest chains:
        // omega_1 = 2 sqrt(k/m) sin(pi / (2 (2N + 1))), N = n - 1 moving masses.
        let grid = Grid::paper();
        let model = MsmModel::new(grid, MsmParams::axis(900.0, 1000.0, 1100.0, 0.0), 1040.0).unwrap();
        let (_, omega) = critical_damping(&model).unwrap();
        let m = model.node_mass;
        let expect = 2.0 * (900.0 / m).sqrt() * (std::f64::consts::PI / 30.0).sin();
        assert!((omega - expect).abs() < 1e-8 * expect, "{omega} vs {expect}");
    }
}
