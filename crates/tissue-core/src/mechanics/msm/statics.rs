//! Static equilibrium of the mass-spring model under a load case (damping plays no part).
//!
//! Two solvers, checked against each other in the tests:
//!
//! * [`closed_form_axis`]: the paper's model (axis springs only) under a clamped case. Every
//!   spring chain along the loaded axis `a` carries exactly the nodal force `F / n^2` of its end
//!   node, so each of its springs stretches by `F / (n^2 k_a)`; every node of a layer moves by the
//!   same amount, so the springs across the axis keep their rest length and carry nothing. This
//!   satisfies the nonlinear equilibrium exactly, and the tangent there is positive definite
//!   (the chains' tension stiffens the lattice's shear modes), so it is the equilibrium reached
//!   from rest. Cost: one pass over the nodes.
//! * [`solve_newton`]: Newton's method on the nonlinear spring equations for any topology, with a
//!   sparse Cholesky factorisation of the tangent. With axis springs only, the small-displacement
//!   tangent is singular (nothing resists shear of the lattice), so a step may need a
//!   Levenberg-Marquardt shift `mu I`. The shift only changes the search direction, never the
//!   equations: convergence is declared on the unshifted residual, `|f_int + f_ext| <= tol |f_ext|`,
//!   and the final iterations are plain Newton steps. It never silently biases the answer.

use super::forces::{ForceScratch, TangentAssembler, add_spring_forces};
use super::model::{MsmModel, Topology};
use super::reduction::DofMap;
use crate::mechanics::cases::{Bc, CaseSolution, LoadCase};
use crate::mechanics::sparse::SparseError;

/// Errors of the static solve.
#[derive(Debug, thiserror::Error)]
pub enum StaticError {
    /// The linear algebra failed.
    #[error(transparent)]
    Sparse(#[from] SparseError),
    /// Newton did not converge.
    #[error(
        "static MSM solve of {case} did not converge: relative residual {residual:.3e} after {iterations} iterations"
    )]
    NotConverged {
        /// Case id.
        case: String,
        /// Final relative residual.
        residual: f64,
        /// Iterations done.
        iterations: usize,
    },
    /// The load's size is beyond what floating point represents (its norm overflows).
    #[error("the load is beyond what floating point represents (its norm is not finite)")]
    LoadNotFinite,
}

/// Newton solver settings.
#[derive(Debug, Clone, Copy)]
pub struct NewtonOptions {
    /// Convergence: `|residual| <= rel_tol |f_ext|` (Euclidean norms over free dofs), or the
    /// round-off floor of the spring forces at this size where that is larger.
    pub rel_tol: f64,
    /// Iteration limit.
    pub max_iterations: usize,
    /// Chord (modified Newton) iterations: keep the factorised tangent while the residual drops
    /// at least fourfold per step, and start from the tangent already factorised in the
    /// assembler if there is one (e.g. from the previous force of the same case family).
    pub chord: bool,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        Self { rel_tol: 1e-10, max_iterations: 100, chord: false }
    }
}

/// Convergence report of one Newton solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonReport {
    /// Newton iterations (accepted and rejected steps).
    pub iterations: usize,
    /// Final `|f_int + f_ext| / |f_ext|`.
    pub rel_residual: f64,
    /// Largest Levenberg-Marquardt shift used, relative to the mean tangent diagonal (0: none).
    pub max_shift: f64,
    /// Tangent factorisations done.
    pub factorisations: usize,
}

/// The exact equilibrium of the axis-spring model under a clamped case, or `None` when the fast
/// path does not apply (other topology or boundary conditions).
pub fn closed_form_axis(model: &MsmModel, case: &LoadCase) -> Option<Vec<[f64; 3]>> {
    if model.params.topology() != Topology::Axis || case.bc != Bc::Clamped || model.inclusions.is_some() {
        return None;
    }
    let a = case.axis - 1;
    let n = model.grid.n();
    let k = [model.params.k1, model.params.k2, model.params.k3][a];
    let stretch = case.force_n / (n * n) as f64 / k;
    let mut u = vec![[0.0; 3]; model.grid.num_nodes()];
    let stride = [1, n, n * n][a];
    for (p, row) in u.iter_mut().enumerate() {
        row[a] = ((p / stride) % n) as f64 * stretch;
    }
    Some(u)
}

/// The static equilibrium displacements of one case: the closed form where it applies, Newton
/// otherwise.
pub fn equilibrium(model: &MsmModel, case: &LoadCase) -> Result<Vec<[f64; 3]>, StaticError> {
    match closed_form_axis(model, case) {
        Some(u) => Ok(u),
        None => Ok(solve_newton(model, case, NewtonOptions::default())?.0),
    }
}

fn norm_free(v: &[Vec<f64>; 3], free: &[bool]) -> f64 {
    let mut s = 0.0;
    for (p, &f) in free.iter().enumerate() {
        if f {
            s += v[0][p] * v[0][p] + v[1][p] * v[1][p] + v[2][p] * v[2][p];
        }
    }
    s.sqrt()
}

/// The reduced unknowns a case of `model` is solved in: the mirror-symmetric quarter for a
/// clamped case of a lattice without inclusions, every free degree of freedom otherwise.
pub fn case_dofs(model: &MsmModel, case: &LoadCase) -> DofMap {
    match case.bc {
        Bc::Clamped if model.inclusions.is_none() => DofMap::clamped_symmetric(&model.grid, case.axis - 1),
        Bc::Clamped | Bc::Patch => DofMap::free(&case.fixed_nodes()),
    }
}

/// Newton-Raphson (with a Levenberg-Marquardt fallback) on the nonlinear spring equilibrium of a
/// case; returns node displacements and a convergence report.
pub fn solve_newton(
    model: &MsmModel,
    case: &LoadCase,
    opts: NewtonOptions,
) -> Result<(Vec<[f64; 3]>, NewtonReport), StaticError> {
    let mut tangent = TangentAssembler::new(model, case_dofs(model, case))?;
    solve_newton_with(model, case, opts, &mut tangent, None)
}

/// [`solve_newton`] with a prepared tangent pattern (reused across parameter sets of one topology)
/// and an optional starting displacement (a warm start; rest otherwise).
#[allow(clippy::too_many_lines, reason = "numeric kernel: the Newton / Levenberg-Marquardt iteration")]
pub fn solve_newton_with(
    model: &MsmModel,
    case: &LoadCase,
    opts: NewtonOptions,
    tangent: &mut TangentAssembler,
    start: Option<&[[f64; 3]]>,
) -> Result<(Vec<[f64; 3]>, NewtonReport), StaticError> {
    let grid = model.grid;
    let nn = grid.num_nodes();
    let free: Vec<bool> = case.fixed_nodes().iter().map(|f| !f).collect();
    let rest: [Vec<f64>; 3] = std::array::from_fn(|c| (0..nn).map(|p| grid.position(p)[c]).collect());
    let f_ext: [Vec<f64>; 3] = std::array::from_fn(|c| (0..nn).map(|p| case.load[3 * p + c]).collect());
    let f_norm = norm_free(&f_ext, &free);
    if !f_norm.is_finite() {
        return Err(StaticError::LoadNotFinite);
    }
    let mut x = rest.clone();
    if let Some(u) = start {
        for c in 0..3 {
            for p in 0..nn {
                if free[p] {
                    x[c][p] += u[p][c];
                }
            }
        }
    }
    let mut report = NewtonReport { iterations: 0, rel_residual: 0.0, max_shift: 0.0, factorisations: 0 };
    if f_norm == 0.0 && start.is_none() {
        return Ok((vec![[0.0; 3]; nn], report));
    }
    let f_norm = f_norm.max(f64::MIN_POSITIVE);
    let mut scratch = ForceScratch::new(model);
    let residual = |x: &[Vec<f64>; 3], g: &mut [Vec<f64>; 3], scratch: &mut ForceScratch| {
        for c in 0..3 {
            g[c].copy_from_slice(&f_ext[c]);
        }
        add_spring_forces(model, x, g, scratch);
        for (p, &f) in free.iter().enumerate() {
            if !f {
                for gc in g.iter_mut() {
                    gc[p] = 0.0;
                }
            }
        }
    };
    // Total potential energy: elastic minus work of the external loads.
    let energy = |x: &[Vec<f64>; 3]| {
        let mut w = 0.0;
        for c in 0..3 {
            for p in 0..nn {
                w += f_ext[c][p] * (x[c][p] - rest[c][p]);
            }
        }
        model.elastic_energy(x) - w
    };
    let mut g: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; nn]);
    residual(&x, &mut g, &mut scratch);
    let mut r_norm = norm_free(&g, &free);
    let mut e: Option<f64> = None; // energy of x, computed when a step must be judged by it
    let mut lambda = 0.0f64; // shift relative to the mean diagonal of the tangent
    let mean_diag = mean_diagonal(model);
    let mut rhs = vec![0.0; tangent.dofs.n];
    let mut trial = x.clone();
    let mut g_trial = g.clone();
    let mut refactor = !(opts.chord && tangent.system.is_factored());
    let tol = opts.rel_tol.max(roundoff_floor(model, &free) / f_norm) * f_norm;
    while r_norm > tol {
        if report.iterations >= opts.max_iterations {
            return Err(StaticError::NotConverged {
                case: case.id.clone(),
                residual: r_norm / f_norm,
                iterations: report.iterations,
            });
        }
        report.iterations += 1;
        let fresh = refactor;
        if refactor {
            tangent.assemble(model, &x, 1.0, lambda * mean_diag, false, None);
            if tangent.system.factor().is_err() {
                lambda = if lambda == 0.0 { 1e-10 } else { lambda * 10.0 };
                report.max_shift = report.max_shift.max(lambda);
                continue;
            }
            report.factorisations += 1;
            refactor = !opts.chord;
        }
        tangent.dofs.fold(&g, &mut rhs);
        tangent.system.solve_in_place(&mut rhs)?;
        for c in 0..3 {
            trial[c].copy_from_slice(&x[c]);
        }
        tangent.dofs.expand_add(&rhs, &mut trial);
        residual(&trial, &mut g_trial, &mut scratch);
        let r_trial = norm_free(&g_trial, &free);
        // A step is accepted when it lowers the residual, or else the total potential energy.
        let accept = r_trial < r_norm || {
            let e_x = *e.get_or_insert_with(|| energy(&x));
            let e_t = energy(&trial);
            e_t < e_x && {
                e = Some(e_t);
                true
            }
        };
        if accept {
            if r_trial >= r_norm || (opts.chord && r_trial > 0.25 * r_norm) {
                refactor = true; // a slow chord step: take a fresh tangent next time
            }
            if r_trial < r_norm {
                e = None;
            }
            std::mem::swap(&mut x, &mut trial);
            std::mem::swap(&mut g, &mut g_trial);
            r_norm = r_trial;
            lambda = if lambda <= 1e-10 { 0.0 } else { lambda / 10.0 };
        } else {
            refactor = true;
            if fresh {
                lambda = if lambda == 0.0 { 1e-10 } else { lambda * 10.0 };
                report.max_shift = report.max_shift.max(lambda);
            }
        }
    }
    report.rel_residual = r_norm / f_norm;
    let u = (0..nn).map(|p| std::array::from_fn(|c| x[c][p] - rest[c][p])).collect();
    Ok((u, report))
}

/// The smallest residual norm round-off lets the spring forces reach: each spring force is
/// `k (|x_b - x_a| - l0)` with positions of the cube's size, so it carries an error of about
/// `eps k L`; over the free degrees of freedom these add like `sqrt(dofs)` times a node's total
/// stiffness (the tangent's mean diagonal). At 8^3 this lies below the default tolerance; at
/// 24^3 and above it does not, and a fixed relative tolerance would never be met.
fn roundoff_floor(model: &MsmModel, free: &[bool]) -> f64 {
    let dofs = 3 * free.iter().filter(|f| **f).count();
    f64::EPSILON * mean_diagonal(model) * crate::mechanics::grid::CUBE_SIDE_M * (dofs as f64).sqrt()
}

/// Mean diagonal of the small-displacement tangent: sum over springs touching a node of `k`,
/// per dof, averaged — a scale for the Levenberg-Marquardt shift.
fn mean_diagonal(model: &MsmModel) -> f64 {
    let total: f64 = model.families.iter().map(|f| f.stiffness.iter().sum::<f64>()).sum();
    2.0 * total / (3 * model.grid.num_nodes()) as f64
}

/// Static equilibrium of each case: the closed form where it applies, Newton otherwise.
pub fn solve_cases(model: &MsmModel, cases: &[LoadCase]) -> Result<Vec<CaseSolution>, StaticError> {
    solve_cases_with_progress(model, cases, &mut |_, _| {})
}

/// [`solve_cases`], calling `progress(i, case id)` before case `i`.
pub fn solve_cases_with_progress(
    model: &MsmModel,
    cases: &[LoadCase],
    progress: &mut dyn FnMut(usize, &str),
) -> Result<Vec<CaseSolution>, StaticError> {
    cases
        .iter()
        .enumerate()
        .map(|(i, case)| {
            progress(i, &case.id);
            let displacements = equilibrium(model, case)?;
            Ok(CaseSolution {
                case_id: case.id.clone(),
                axis: case.axis,
                force_n: case.force_n,
                reaction_n: reaction(model, case, &displacements),
                displacements,
            })
        })
        .collect()
}

/// Sum of the support reactions: minus the spring forces acting on the fixed nodes.
fn reaction(model: &MsmModel, case: &LoadCase, u: &[[f64; 3]]) -> [f64; 3] {
    let nn = model.grid.num_nodes();
    let x: [Vec<f64>; 3] = std::array::from_fn(|c| (0..nn).map(|p| model.grid.position(p)[c] + u[p][c]).collect());
    let mut f: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; nn]);
    add_spring_forces(model, &x, &mut f, &mut ForceScratch::new(model));
    let mut r = [0.0; 3];
    for (p, &fixed) in case.fixed_nodes().iter().enumerate() {
        if fixed {
            for c in 0..3 {
                r[c] -= f[c][p];
            }
        }
    }
    r
}

/// Whether the static answer of a `topology` lattice at `n` nodes per axis is within reach: the
/// axis lattice's closed form always is (without inclusions); a Newton solve is bounded by its
/// sparse factor ([`crate::mechanics::sparse::DirectSolve::MsmNewton`]).
pub fn check_grid(topology: Topology, n: usize, inclusions: bool) -> Result<(), String> {
    match topology {
        Topology::Axis if !inclusions => Ok(()),
        _ => crate::mechanics::sparse::DirectSolve::MsmNewton.check_grid(n),
    }
}
