//! Fitting a spring lattice to the touch benchmark's training cases, and the load-free
//! stiffness fit.
//!
//! The touch cost is the mean over the training cases of `(r - 1)^2 + e^2` for point and shear
//! loads (`r` the compliance ratio at the load, `e` the field error) and `(r - 1)^2` for the
//! probe (`r` the force ratio). The lattice's rest stiffness is linear in its parameters,
//! `K = sum_g theta_g K_g`, so the gradient is exact and cheap: `dr/dtheta_g = -u^T K_g u / (u_fem . f)`
//! with no extra solve, the field error's takes one adjoint solve per case, and the probe
//! force's one small dense solve ([`crate::response::linear::ProbeAnswer::sensitivity`]).
//! The polish minimises it by L-BFGS (argmin) in `ln theta`.
//!
//! [`stiffness_fit`] is the load-free baseline (Lloyd, Szekely and Harders 2007; Natsupakpong
//! and Cavusoglu 2010): the non-negative least-squares fit of the lattice's stiffness matrix to
//! the FEM's in the Frobenius norm, solved exactly over the few parameters.

use crate::mechanics::fem::FemModel;
use crate::mechanics::grid::Grid;
use crate::mechanics::msm::{MsmParams, Topology};
use crate::response::linear::{GroupedStiffness, with_group_values};
use crate::validate::touch::Set;
use crate::validate::touch::score::{Reference, Responder};

/// Which stiffness groups are free, and which copy another (a transversely isotropic material,
/// axis 1 distinct: `k3 = k2`, `c13 = c12`).
#[derive(Debug, Clone)]
pub struct Groups {
    /// Free group indices (into [`crate::response::linear::GROUP_NAMES`]).
    pub free: Vec<usize>,
    /// `(copy, source)` pairs.
    pub tied: Vec<(usize, usize)>,
}

impl Groups {
    /// The groups of `topology`.
    pub fn new(topology: Topology, transversely_isotropic: bool) -> Self {
        let mut present: Vec<usize> = vec![0, 1, 2];
        if topology != Topology::Axis {
            present.extend([3, 4, 5]);
        }
        if topology == Topology::Hex {
            present.push(6);
        }
        let tied: Vec<(usize, usize)> = if transversely_isotropic { vec![(2, 1), (4, 3)] } else { Vec::new() }
            .into_iter()
            .filter(|(c, _)| present.contains(c))
            .collect();
        let free = present.into_iter().filter(|g| !tied.iter().any(|(c, _)| c == g)).collect();
        Self { free, tied }
    }

    /// All seven groups from the free values.
    pub fn expand(&self, values: &[f64]) -> [f64; 7] {
        let mut theta = [0.0; 7];
        for (&g, &v) in self.free.iter().zip(values) {
            theta[g] = v;
        }
        for &(c, s) in &self.tied {
            theta[c] = theta[s];
        }
        theta
    }

    /// The gradient over the free values from one over all seven groups.
    pub fn reduce(&self, gradient: &[f64; 7]) -> Vec<f64> {
        let mut g = *gradient;
        for &(c, s) in &self.tied {
            g[s] += g[c];
        }
        self.free.iter().map(|&i| g[i]).collect()
    }
}

/// Adds `(r - 1)^2`, `r = value / reference`, to `cost` and its gradient to `grad`, given the
/// adjoint forms `w^T K_g u` of each group (`dr/dtheta_g = -forms_g / reference`).
fn add_ratio_term(value: f64, reference: f64, forms: &[f64], cost: &mut f64, grad: &mut [f64]) {
    let ratio = value / reference;
    *cost += (ratio - 1.0).powi(2);
    for (g, f) in grad.iter_mut().zip(forms) {
        *g -= 2.0 * (ratio - 1.0) * f / reference;
    }
}

/// The touch cost of a lattice over `set` of `reference` at `theta` (one value per group of the
/// responder's stiffness), and its gradient by each group; `responder` is the lattice's (any
/// parameters: it is refactorised here).
pub fn touch_cost(
    reference: &Reference,
    set: Set,
    responder: &mut Responder,
    theta: &[f64],
) -> Result<(f64, Vec<f64>), crate::mechanics::sparse::SparseError> {
    let r = responder;
    r.set_theta(theta)?;
    let groups = r.stiffness.groups;
    let (mut cost, mut grad, mut count) = (0.0, vec![0.0; groups], 0usize);
    let mut forms = vec![0.0; groups];
    for (case, fem) in reference.cases.iter().zip(&reference.answers) {
        if case.set != set {
            continue;
        }
        count += 1;
        let (answer, sensitivity) = r.answer(case)?;
        // dr/dtheta_g = -w^T K_g u / feel_fem: w = u for a force load, the probe's adjoint field.
        let w = sensitivity.as_ref().unwrap_or(&answer.u);
        r.stiffness.group_forms(w, &answer.u, &mut forms);
        add_ratio_term(answer.feel, fem.feel, &forms, &mut cost, &mut grad);
        if sensitivity.is_none() {
            // The field error, by one adjoint solve.
            let ref2: f64 = fem.u.iter().map(|v| v * v).sum();
            let mut adjoint: Vec<f64> = answer.u.iter().zip(&fem.u).map(|(a, b)| a - b).collect();
            cost += adjoint.iter().map(|v| v * v).sum::<f64>() / ref2;
            r.solver.solve(&mut adjoint)?;
            r.stiffness.group_forms(&adjoint, &answer.u, &mut forms);
            for g in 0..groups {
                grad[g] -= 2.0 * forms[g] / ref2;
            }
        }
    }
    let n = count.max(1) as f64;
    Ok((cost / n, grad.into_iter().map(|g| g / n).collect()))
}

/// The press cost of a lattice at `theta`: the mean of `(F / F_material - 1)^2` over `presses`
/// (each with the material's force, newtons), `F` the magnitude of the lattice's force with node
/// contact on `grid`, and its gradient by each group (the probe's adjoint, the contact set held).
pub fn press_cost(
    presses: &[(crate::validate::continuum::Press, f64)],
    grid: Grid,
    responder: &mut Responder,
    theta: &[f64],
) -> Result<(f64, Vec<f64>), crate::mechanics::sparse::SparseError> {
    let r = responder;
    r.set_theta(theta)?;
    let groups = r.stiffness.groups;
    let (mut cost, mut grad) = (0.0, vec![0.0; groups]);
    let mut forms = vec![0.0; groups];
    for (press, material) in presses {
        let answer = r.solver.probe(&grid, press.centre(), press.radius)?;
        r.stiffness.group_forms(&answer.sensitivity, &answer.u, &mut forms);
        add_ratio_term(answer.force_n(), *material, &forms, &mut cost, &mut grad);
    }
    let n = presses.len().max(1) as f64;
    Ok((cost / n, grad.into_iter().map(|g| g / n).collect()))
}

/// A lattice's responder for the touch cost (factorised at unit parameters).
pub fn lattice_responder(
    reference: &Reference,
    topology: Topology,
) -> Result<Responder, crate::mechanics::sparse::SparseError> {
    Responder::new(reference.grid, GroupedStiffness::lattice(reference.grid, topology), &[1.0; 7])
}

/// The non-negative least-squares fit of the lattice's stiffness matrix to the FEM's of the same
/// material and grid, over all degrees of freedom (Frobenius norm), with the material's ties.
/// Returns the parameters (damping `d` zero) and the relative residual `|K - K_fem| / |K_fem|`.
pub fn stiffness_fit(fem: &FemModel, topology: Topology, transversely_isotropic: bool) -> (MsmParams, f64) {
    let grid = fem.grid;
    let lattice = GroupedStiffness::lattice(grid, topology);
    let groups = Groups::new(topology, transversely_isotropic);
    let m = groups.free.len();
    // Each free unknown's matrix (tied groups folded in) and the FEM's, entry by entry.
    let column = |g: usize| {
        groups.free.iter().position(|&f| f == g).or_else(|| {
            groups.tied.iter().find(|(c, _)| *c == g).and_then(|(_, s)| groups.free.iter().position(|f| f == s))
        })
    };
    let mut entries: std::collections::HashMap<(usize, usize), Vec<f64>> = std::collections::HashMap::new();
    for ((&rc, &v), &g) in lattice.entries.iter().zip(&lattice.unit).zip(&lattice.group) {
        if let Some(j) = column(g as usize) {
            entries.entry(rc).or_insert_with(|| vec![0.0; m + 1])[j] += v;
        }
    }
    let (fem_entries, fem_values) = fem.stiffness_entries();
    for (&rc, &v) in fem_entries.iter().zip(&fem_values) {
        entries.entry(rc).or_insert_with(|| vec![0.0; m + 1])[m] += v;
    }
    let mut gram = nalgebra::DMatrix::<f64>::zeros(m + 1, m + 1);
    for ((r, c), v) in &entries {
        let w = if r == c { 1.0 } else { 2.0 };
        for i in 0..=m {
            for j in 0..=m {
                gram[(i, j)] += w * v[i] * v[j];
            }
        }
    }
    // Exact NNLS over the few unknowns: the best least-squares solution on every support.
    let mut best = (f64::INFINITY, vec![0.0; m]);
    for mask in 1u32..(1 << m) {
        let support: Vec<usize> = (0..m).filter(|i| mask & (1 << i) != 0).collect();
        let a = nalgebra::DMatrix::from_fn(support.len(), support.len(), |i, j| gram[(support[i], support[j])]);
        let b = nalgebra::DVector::from_fn(support.len(), |i, _| gram[(support[i], m)]);
        let Some(x) = a.cholesky().map(|c| c.solve(&b)) else { continue };
        if x.iter().any(|v| *v < 0.0) {
            continue;
        }
        let mut full = vec![0.0; m];
        for (i, &s) in support.iter().enumerate() {
            full[s] = x[i];
        }
        // |K - K_fem|^2 = x^T G x - 2 x^T b + |K_fem|^2.
        let mut residual = gram[(m, m)];
        for i in 0..m {
            residual -= 2.0 * full[i] * gram[(i, m)];
            for j in 0..m {
                residual += full[i] * full[j] * gram[(i, j)];
            }
        }
        if residual < best.0 {
            best = (residual, full);
        }
    }
    let (min, _) = crate::mechanics::msm::model::STIFFNESS_RANGE;
    let mut theta = groups.expand(&best.1);
    for t in &mut theta[..3] {
        *t = t.max(min); // an axis spring needs a stiffness
    }
    let template = MsmParams::unit(topology);
    (with_group_values(&template, &theta), (best.0.max(0.0) / gram[(m, m)]).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::material::Material;

    #[test]
    fn touch_gradient_matches_finite_differences() {
        let grid = Grid::new(5).unwrap();
        let m = Material::object_a();
        let reference = Reference::new(&m, grid).unwrap();
        let mut responder = lattice_responder(&reference, Topology::Hex).unwrap();
        let mut cost = |t: &[f64; 7]| touch_cost(&reference, Set::Training, &mut responder, t).unwrap();
        let theta = [300.0, 250.0, 200.0, 60.0, 50.0, 40.0, 30.0];
        let (_, g) = cost(&theta);
        for i in 0..7 {
            let h = 1e-6 * theta[i];
            let (mut up, mut down) = (theta, theta);
            up[i] += h;
            down[i] -= h;
            let fd = (cost(&up).0 - cost(&down).0) / (2.0 * h);
            assert!(
                (fd - g[i]).abs() <= 1e-5 * g[i].abs().max(1e-6 * g.iter().fold(0.0f64, |a, v| a.max(v.abs()))),
                "{i}: {fd} vs {}",
                g[i]
            );
        }
    }

    #[test]
    fn press_gradient_matches_finite_differences() {
        // The material's training presses (shipped for A), node contact on a 10^3 hex lattice.
        let grid = Grid::new(10).unwrap();
        let m = Material::object_a();
        let presses = crate::validate::probe::score::training_forces(&m).unwrap();
        assert_eq!(presses.len(), 24);
        let stiffness = GroupedStiffness::lattice(grid, Topology::Hex);
        let mut responder = Responder::new(grid, stiffness, &[1.0; 7]).unwrap();
        let mut cost = |t: &[f64; 7]| press_cost(&presses, grid, &mut responder, t).unwrap();
        let theta = [600.0, 500.0, 450.0, 90.0, 80.0, 70.0, 50.0];
        let (c, g) = cost(&theta);
        assert!(c > 0.0 && c.is_finite());
        for i in 0..7 {
            let h = 1e-6 * theta[i];
            let (mut up, mut down) = (theta, theta);
            up[i] += h;
            down[i] -= h;
            let fd = (cost(&up).0 - cost(&down).0) / (2.0 * h);
            let scale = g.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            assert!((fd - g[i]).abs() <= 1e-4 * scale, "{i}: {fd} vs {}", g[i]);
        }
    }

    #[test]
    fn stiffness_fit_gives_a_valid_lattice_and_its_residual() {
        let grid = Grid::new(4).unwrap();
        let m = Material::object_a();
        let fem = FemModel::new(grid, &m);
        let (p, residual) = stiffness_fit(&fem, Topology::Hex, false);
        assert!(residual > 0.0 && residual < 1.0, "{residual}");
        assert!(p.validate().is_ok(), "{p:?}");
    }
}
