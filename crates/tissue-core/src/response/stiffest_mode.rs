//! The stiffest mode of a model: the largest eigenvalue `omega_max^2` of `M^-1 K` (lumped
//! masses, the rest stiffness) by Lanczos on `M^-1/2 K M^-1/2`, with an upper estimate.
//!
//! After `j` Lanczos steps the largest Ritz value `theta` of the tridiagonal `T_j` lies below
//! `omega_max^2`, and some eigenvalue lies within the residual `r = beta_j |s_j|` of it (`s` the
//! Ritz vector in `T_j`'s basis). The extreme Ritz value converges first, so `theta + r` is an
//! upper estimate of `omega_max^2` that tightens as `r` falls: the explicit step limits take it
//! (capped by their rigorous bounds), the stability study the Ritz value itself. No
//! re-orthogonalisation: lost orthogonality only repeats converged Ritz values (Paige), and the
//! extreme one is all that is wanted.

use glam::DVec3;
use rand::{RngExt, SeedableRng, rngs::Xoshiro256PlusPlus};

use crate::mechanics::fem::FemModel;
use crate::mechanics::msm::MsmModel;

/// The explicit limits' tolerance on the residual, relative to the Ritz value: `theta + r` is
/// then at most 0.1 % above `omega_max^2`.
pub const LIMIT_TOLERANCE: f64 = 1e-3;
/// The explicit limits' iteration cap; a run that stops at it still gives `theta + r`, looser.
pub const LIMIT_ITERATIONS: usize = 400;
/// The Ritz values are extracted every this many steps (a dense eigen-solve of `T_j`).
const CHECK_EVERY: usize = 10;

/// A Lanczos estimate of `omega_max^2`, s^-2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StiffestMode {
    /// The largest Ritz value: at most `omega_max^2` (up to rounding).
    pub ritz: f64,
    /// Its residual norm: an eigenvalue lies within this of `ritz`.
    pub residual: f64,
    /// Lanczos steps taken.
    pub iterations: usize,
}

impl StiffestMode {
    /// `ritz + residual`: the upper estimate of `omega_max^2`.
    pub fn upper(&self) -> f64 {
        self.ritz + self.residual
    }
}

/// Lanczos on `M^-1/2 K M^-1/2` over the `free` dofs (`mass` per dof, kg), from a fixed
/// pseudo-random start, until the residual is within `tolerance` of the Ritz value or after
/// `max_iterations` steps. `apply` computes `K u` over all dofs (interleaved, as `mass`).
pub fn lanczos(
    mass: &[f64],
    free: &[bool],
    tolerance: f64,
    max_iterations: usize,
    mut apply: impl FnMut(&[f64], &mut [f64]),
) -> StiffestMode {
    let n = mass.len();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
    let mut q: Vec<f64> = (0..n).map(|i| if free[i] { rng.random::<f64>() - 0.5 } else { 0.0 }).collect();
    let norm = dot(&q, &q).sqrt();
    if norm == 0.0 {
        return StiffestMode { ritz: 0.0, residual: 0.0, iterations: 0 };
    }
    q.iter_mut().for_each(|v| *v /= norm);
    let inv_sqrt_mass: Vec<f64> = mass.iter().zip(free).map(|(&m, &f)| if f { 1.0 / m.sqrt() } else { 0.0 }).collect();
    let (mut previous, mut u, mut w) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let (mut alphas, mut betas) = (Vec::new(), Vec::<f64>::new());
    let mut estimate = StiffestMode { ritz: 0.0, residual: f64::INFINITY, iterations: 0 };
    for j in 1..=max_iterations {
        for i in 0..n {
            u[i] = q[i] * inv_sqrt_mass[i];
        }
        apply(&u, &mut w);
        let beta_previous = betas.last().copied().unwrap_or(0.0);
        for i in 0..n {
            w[i] *= inv_sqrt_mass[i];
        }
        let alpha = dot(&q, &w);
        for i in 0..n {
            w[i] -= alpha * q[i] + beta_previous * previous[i];
        }
        let beta = dot(&w, &w).sqrt();
        alphas.push(alpha);
        betas.push(beta);
        // An invariant subspace (beta = 0) makes the Ritz values exact.
        let exhausted = beta <= 1e-14 * alpha.abs();
        if exhausted || j % CHECK_EVERY == 0 || j == max_iterations {
            estimate = largest_ritz(&alphas, &betas);
            if exhausted || estimate.residual <= tolerance * estimate.ritz {
                break;
            }
        }
        for i in 0..n {
            previous[i] = q[i];
            q[i] = w[i] / beta;
        }
    }
    estimate
}

/// The largest Ritz value of the tridiagonal `T_j` (`alphas` on the diagonal, `betas[..j-1]`
/// beside it) and its residual `betas[j-1] |s_j|`.
fn largest_ritz(alphas: &[f64], betas: &[f64]) -> StiffestMode {
    let j = alphas.len();
    let t = nalgebra::DMatrix::from_fn(j, j, |r, c| {
        if r == c {
            alphas[r]
        } else if r + 1 == c || c + 1 == r {
            betas[r.min(c)]
        } else {
            0.0
        }
    });
    let eig = nalgebra::SymmetricEigen::new(t);
    let (top, ritz) = eig
        .eigenvalues
        .iter()
        .copied()
        .enumerate()
        .fold((0, f64::NEG_INFINITY), |best, (i, v)| if v > best.1 { (i, v) } else { best });
    let residual = betas[j - 1] * eig.eigenvectors[(j - 1, top)].abs();
    StiffestMode { ritz, residual, iterations: j }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// A lattice's stiffest mode with `fixed_nodes` held: its rest stiffness `sum k n n^T` over the
/// springs (`n` each spring's rest direction), its nodes' masses.
pub fn lattice(model: &MsmModel, fixed_nodes: &[bool], tolerance: f64, max_iterations: usize) -> StiffestMode {
    let springs: Vec<(usize, usize, [f64; 3], f64)> = model
        .springs()
        .into_iter()
        .map(|s| {
            let o = DVec3::from(model.families[s.family].family.offset.map(f64::from));
            (s.a, s.b, (o / o.length()).to_array(), s.k)
        })
        .collect();
    let dofs = 3 * model.grid.num_nodes();
    let free: Vec<bool> = (0..dofs).map(|d| !fixed_nodes[d / 3]).collect();
    let mass: Vec<f64> = (0..dofs).map(|d| model.masses[d / 3]).collect();
    lanczos(&mass, &free, tolerance, max_iterations, |u, out| {
        out.fill(0.0);
        for &(a, b, n, k) in &springs {
            let du = [u[3 * b] - u[3 * a], u[3 * b + 1] - u[3 * a + 1], u[3 * b + 2] - u[3 * a + 2]];
            let s = k * (n[0] * du[0] + n[1] * du[1] + n[2] * du[2]);
            for c in 0..3 {
                out[3 * a + c] -= s * n[c];
                out[3 * b + c] += s * n[c];
            }
        }
    })
}

/// A FEM cube's stiffest mode (its linear stiffness) over the `free` dofs, `mass` per dof.
pub fn fem(model: &FemModel, mass: &[f64], free: &[bool], tolerance: f64, max_iterations: usize) -> StiffestMode {
    lanczos(mass, free, tolerance, max_iterations, |u, out| model.apply(u, out))
}

/// The largest eigenvalue of `M^-1/2 K M^-1/2` on the `free` dofs by a dense eigen-solve (`mass`
/// per dof): the exact `omega_max^2` that the tests hold the estimates to.
#[cfg(test)]
pub(crate) fn dense_omega_max_sq(k: &nalgebra::DMatrix<f64>, mass: &[f64], free: &[bool]) -> f64 {
    let kept: Vec<usize> = (0..mass.len()).filter(|&d| free[d]).collect();
    let scaled = nalgebra::DMatrix::from_fn(kept.len(), kept.len(), |i, j| {
        k[(kept[i], kept[j])] / (mass[kept[i]] * mass[kept[j]]).sqrt()
    });
    scaled.symmetric_eigenvalues().max()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::grid::Grid;
    use crate::mechanics::material::Material;

    /// Against the dense eigen-solve at 4^3 (object B's FEM, free and with its bottom face held):
    /// the Ritz value is at most `omega_max^2` and the upper estimate at least it, within the
    /// tolerance.
    #[test]
    fn the_upper_estimate_brackets_the_stiffest_mode() {
        let material = Material::object_b();
        let grid = Grid::new(4).unwrap();
        let model = FemModel::new(grid, &material);
        let dofs = 3 * grid.num_nodes();
        let k = model.dense_stiffness();
        let node_mass = crate::mechanics::msm::model::lumped_masses(&grid, material.density);
        let mass: Vec<f64> = (0..dofs).map(|d| node_mass[d / 3]).collect();
        for clamped in [false, true] {
            let free: Vec<bool> = (0..dofs).map(|d| !clamped || grid.position(d / 3)[2] > 0.0).collect();
            let exact = dense_omega_max_sq(&k, &mass, &free);
            let e = fem(&model, &mass, &free, LIMIT_TOLERANCE, LIMIT_ITERATIONS);
            assert!(e.ritz <= exact * (1.0 + 1e-12), "Ritz value {} above omega_max^2 {exact}", e.ritz);
            assert!(e.upper() >= exact, "upper estimate {} below omega_max^2 {exact}", e.upper());
            assert!(e.upper() <= exact * (1.0 + LIMIT_TOLERANCE), "upper estimate {} vs {exact}", e.upper());
            eprintln!(
                "clamped {clamped}: omega_max^2 {exact:.6e}, Ritz {:.6e}, upper {:.6e}, {} steps",
                e.ritz,
                e.upper(),
                e.iterations
            );
        }
    }

    /// A diagonal `K` of known spectrum: the estimate finds its largest entry.
    #[test]
    fn a_diagonal_stiffness_gives_its_largest_entry() {
        let n = 300;
        let mass = vec![2.0; n];
        let free = vec![true; n];
        let e = lanczos(&mass, &free, 1e-6, 300, |u, out| {
            for i in 0..n {
                out[i] = (1.0 + i as f64) * u[i];
            }
        });
        let exact = n as f64 / 2.0;
        assert!(e.ritz <= exact * (1.0 + 1e-12) && e.upper() >= exact * (1.0 - 1e-12), "{e:?}");
        assert!((e.ritz - exact).abs() < 1e-3 * exact, "{e:?}");
    }
}
