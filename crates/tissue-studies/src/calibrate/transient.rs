//! The transient cost mode, in which damping matters and is identified.
//!
//! Each of the 9 clamped cases starts from rest with its load applied as a step at `t = 0`; the
//! MSM is integrated for [`TRANSIENT_TIME_S`] in [`TRANSIENT_STEPS`] backward-Euler steps and its
//! state then is compared, as in eq. 1, with the FEM's static answer. Too little damping leaves
//! the cube oscillating at that time, too much leaves it creeping towards equilibrium, so the cost
//! has a finite best `d`.
//!
//! Integration: linearly implicit Euler with the rest tangent `K0` (factorised once per axis and
//! parameter set) and the exact nonlinear spring forces on the right-hand side,
//! `(M + h d I + h^2 K0) dv = h (f(x) + f_ext - d v - h K0 v)`, unconditionally stable for the
//! linear part. Clamped cases stay mirror-symmetric, so the lattice is integrated on the symmetric
//! quarter (see `msm::reduction`). The axis-spring model needs no lattice at all: every layer
//! moves as one, the springs stay aligned with the load, and each case is exactly one chain of
//! `n - 1` masses, integrated with the same scheme (where it is exact: the chain is linear).

use crate::mechanics::cases::LoadCase;
use crate::mechanics::msm::forces::{ForceScratch, TangentAssembler, add_spring_forces};
use crate::mechanics::msm::{MsmModel, Topology};
use crate::mechanics::sparse::SparseError;

/// Simulated time after which the state is compared, seconds.
pub const TRANSIENT_TIME_S: f64 = 0.02;
/// Backward-Euler steps over that time.
pub const TRANSIENT_STEPS: usize = 40;

/// Displacements of every node after the transient of `case`. `tangent` holds the case's
/// symmetric reduction; it is assembled and factorised here unless `prepared` is true (the same
/// axis and parameters as the previous call).
pub fn transient_displacements(
    model: &MsmModel,
    case: &LoadCase,
    tangent: &mut TangentAssembler,
    prepared: bool,
) -> Result<Vec<[f64; 3]>, SparseError> {
    let h = TRANSIENT_TIME_S / TRANSIENT_STEPS as f64;
    let (m, d) = (model.node_mass, model.params.d);
    let grid = model.grid;
    let nn = grid.num_nodes();
    if model.params.topology() == Topology::Axis {
        let a = case.axis - 1;
        let n = grid.n();
        let k = [model.params.k1, model.params.k2, model.params.k3][a];
        let chain = chain_transient(k, m, d, n - 1, case.force_n / (n * n) as f64, h, TRANSIENT_STEPS);
        return Ok((0..nn)
            .map(|p| {
                let mut u = [0.0; 3];
                u[a] = chain[grid.ijk(p)[a]];
                u
            })
            .collect());
    }
    let rest: [Vec<f64>; 3] = std::array::from_fn(|c| (0..nn).map(|p| grid.position(p)[c]).collect());
    let r = tangent.dofs.n;
    let w = tangent.dofs.multiplicity.clone();
    let mut mass = vec![0.0; r];
    tangent.dofs.fold_masses(&model.masses, &mut mass);
    if !prepared {
        tangent.assemble(model, &rest, h * h, h * d, false, None);
        tangent.system.add_diagonal_scaled(1.0, &mass);
        tangent.system.factor()?;
    }
    let (mut cx, mut cv) = (vec![0.0; r], vec![0.0; r]);
    let (mut rhs, mut acv) = (vec![0.0; r], vec![0.0; r]);
    let mut x = rest.clone();
    let mut f: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; nn]);
    let mut scratch = ForceScratch::new(model);
    for _ in 0..TRANSIENT_STEPS {
        for c in 0..3 {
            for p in 0..nn {
                f[c][p] = case.load[3 * p + c];
            }
        }
        add_spring_forces(model, &x, &mut f, &mut scratch);
        tangent.dofs.fold(&f, &mut rhs);
        // h K0 v = (A v - (M + h d D) v) / h, from the stored A = M + h d D + h^2 K0.
        tangent.system.mul(&cv, &mut acv);
        for i in 0..r {
            let hk0v = (acv[i] - (mass[i] + h * d * w[i]) * cv[i]) / h;
            rhs[i] = h * (rhs[i] - d * w[i] * cv[i] - hk0v);
        }
        tangent.system.solve_in_place(&mut rhs)?;
        for i in 0..r {
            cv[i] += rhs[i];
            cx[i] += h * cv[i];
        }
        for c in 0..3 {
            x[c].copy_from_slice(&rest[c]);
        }
        tangent.dofs.expand_add(&cx, &mut x);
    }
    Ok((0..nn).map(|p| std::array::from_fn(|c| x[c][p] - rest[c][p])).collect())
}

/// Backward Euler on a chain of `moving` masses `m` (node 0 fixed, nodes 1..=moving free) joined
/// by springs `k`, nodal damping `d`, force `f_tip` on the last node, from rest. Returns the
/// displacement of nodes 0..=moving at the end.
pub fn chain_transient(k: f64, m: f64, d: f64, moving: usize, f_tip: f64, h: f64, steps: usize) -> Vec<f64> {
    let nm = moving;
    let (mut u, mut v) = (vec![0.0; nm + 1], vec![0.0; nm + 1]);
    // Tridiagonal A = (m + h d) I + h^2 K, K the chain stiffness (last node has one spring).
    let diag: Vec<f64> = (1..=nm).map(|i| m + h * d + h * h * k * if i == nm { 1.0 } else { 2.0 }).collect();
    let off = -h * h * k;
    let mut rhs = vec![0.0; nm];
    let (mut cp, mut dp) = (vec![0.0; nm], vec![0.0; nm]);
    for _ in 0..steps {
        for i in 1..=nm {
            let left = u[i] - u[i - 1];
            let right = if i < nm { u[i + 1] - u[i] } else { 0.0 };
            let force = k * (right - left) + if i == nm { f_tip } else { 0.0 };
            let kv = k * (2.0 * v[i] - v[i - 1] - if i < nm { v[i + 1] } else { v[i] });
            rhs[i - 1] = h * (force - d * v[i] - h * kv);
        }
        // Thomas algorithm.
        cp[0] = off / diag[0];
        dp[0] = rhs[0] / diag[0];
        for i in 1..nm {
            let den = diag[i] - off * cp[i - 1];
            cp[i] = off / den;
            dp[i] = (rhs[i] - off * dp[i - 1]) / den;
        }
        for i in (0..nm).rev() {
            let dv = if i + 1 < nm { dp[i] - cp[i] * rhs[i + 1] } else { dp[i] };
            rhs[i] = dv;
        }
        for i in 1..=nm {
            v[i] += rhs[i - 1];
            u[i] += h * v[i];
        }
    }
    u
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::cases::LoadCase;
    use crate::mechanics::grid::Grid;
    use crate::mechanics::msm::forces::TangentAssembler;
    use crate::mechanics::msm::reduction::DofMap;
    use crate::mechanics::msm::{MsmModel, MsmParams};

    #[test]
    fn chain_settles_to_the_static_stretch_with_damping() {
        let (k, m, d) = (2000.0, 0.002, 0.8);
        let u = chain_transient(k, m, d, 7, 10.0 / 64.0, 5e-4, 4000);
        let expect = 7.0 * 10.0 / 64.0 / k;
        assert!((u[7] - expect).abs() < 1e-9 * expect, "{} vs {expect}", u[7]);
    }

    #[test]
    fn lattice_scheme_equals_the_chain_for_the_axis_model() {
        // Force the lattice path on an axis model by giving it zero-stiffness diagonals.
        let grid = Grid::paper();
        let params =
            MsmParams { c12: Some(0.0), c13: Some(0.0), c23: Some(0.0), ..MsmParams::axis(900.0, 1000.0, 1100.0, 0.5) };
        let model = MsmModel::new(grid, params, 1040.0).unwrap();
        let case = LoadCase::clamped(&grid, "A", 2, 5.0);
        let mut t = TangentAssembler::new(&model, DofMap::clamped_symmetric(&grid, 1)).unwrap();
        let lattice = transient_displacements(&model, &case, &mut t, false).unwrap();
        let axis = MsmModel::new(grid, MsmParams::axis(900.0, 1000.0, 1100.0, 0.5), 1040.0).unwrap();
        let chain = transient_displacements(&axis, &case, &mut t, true).unwrap();
        let scale = chain.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
        for (a, b) in lattice.iter().flatten().zip(chain.iter().flatten()) {
            assert!((a - b).abs() < 1e-9 * scale, "{a} vs {b}");
        }
    }
}
