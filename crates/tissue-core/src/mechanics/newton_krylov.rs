//! The implicit steps of the nonlinear models (the corotational FEM, the spring lattices): Newton's
//! method on the step's equation, each linear solve by conjugate gradients preconditioned with
//! the rest factor. One rule, one home: the models say only what their equation, tangent and
//! factor are ([`StepEquation`]).
//!
//! A step solves its scheme's equation with the force at the step's end,
//! `a M y = v_s M v + w_n f(x) + w_e f(x + d(y))` (`y = dx` for the trapezoidal rule, `v'` for
//! backward Euler). The first iterate is the linearised step: `(a M + k K_t) y = b` with the
//! tangent `K_t` of the step's start. Newton's corrections then solve with the tangent of each
//! iterate, until the residual is [`NEWTON_TOLERANCE`] of the equation's terms' size (which does
//! not vanish at rest, where `b` does) or [`NewtonKrylov::newton_max`] corrections are spent; a
//! correction that does not lower the residual is undone. Each linear solve runs conjugate
//! gradients preconditioned with the rest factor `a M + k K_0` (factorised once per step size),
//! from that factor's solve, until its residual is [`KRYLOV_TOLERANCE`] of `|b|` or of the
//! equation's terms' size, whichever is larger. For the
//! corotational FEM the tangent is the stiffness warped by the elements' rotations, `K_w = sum_e
//! R_e K_e R_e^T` (Mueller et al. 2002: the change of the rotations left out); for a lattice, the
//! springs' tangent with each geometric part clamped at zero. Either is positive semi-definite
//! and at most `omega_max^2` of the element or spring bound times `M`, so the preconditioned
//! eigenvalues lie in `[1 / (1 + s), 1 + s]`, `s = k omega_max^2 / a`: the iterations are bounded
//! whatever the deformation.

use super::sparse::SparseError;

/// The residual `|b - A y|`, relative to `|b|` or the equation's terms' size (the larger), where a
/// linear solve stops.
pub const KRYLOV_TOLERANCE: f64 = 1e-6;
/// The most conjugate-gradient iterations of one linear solve ([`NewtonKrylov::krylov_max`]'s
/// default).
pub const KRYLOV_MAX_ITERATIONS: usize = 100;
/// Where the Newton corrections stop: the nonlinear residual relative to its terms' size. A
/// free 8^3 corotational cube spinning at 10 rad/s takes one correction a 1 ms Newmark step and
/// keeps its energy within 0.075 % over 0.5 s (linearised, 5.2 % gained); a held press (`bench`'s
/// scene) leaves 3e-6 to 6e-5 after the linearised step and takes a correction in under a tenth
/// of its steps.
pub const NEWTON_TOLERANCE: f64 = 1e-4;
/// The most Newton corrections of one step ([`NewtonKrylov::newton_max`]'s default; 0 keeps the
/// linearised step).
pub const NEWTON_MAX_ITERATIONS: usize = 4;

/// What a model's implicit step gives the solver. Vectors are the step's unknowns.
pub trait StepEquation {
    /// The residual of the step's nonlinear equation at `y` into `r` (0 on held unknowns); the
    /// tangent of later products is then the one at `y`'s positions.
    fn residual(&mut self, y: &[f64], r: &mut [f64]);
    /// `out = (a M + k K_t) p` with the tangent `K_t` of the last residual's positions (the
    /// step's start before any), 0 on held unknowns.
    fn product(&mut self, p: &[f64], out: &mut [f64]);
    /// Replaces `z` by the rest factor's solve of it.
    fn precondition(&mut self, z: &mut [f64]) -> Result<(), SparseError>;
}

/// What the implicit steps' solves have done since their factor was built (a new step size,
/// scheme, damping, parameters or load case builds it anew, and the counts start again).
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct NewtonSolves {
    /// Steps taken.
    pub steps: usize,
    /// Linear solves (one per step and one per Newton correction).
    pub solves: usize,
    /// Conjugate-gradient iterations over all solves (each one tangent product and one solve
    /// with the rest factor).
    pub iterations: usize,
    /// The most iterations one solve took.
    pub most: usize,
    /// Solves that stopped at [`NewtonKrylov::krylov_max`] above the tolerance (their solution
    /// is the last iterate, closer than the rest factor's in the system's energy norm).
    pub unconverged: usize,
    /// Newton corrections over all steps.
    pub newton: usize,
    /// The most Newton corrections in one step.
    pub newton_most: usize,
    /// Steps whose Newton corrections stopped above [`NEWTON_TOLERANCE`]: at
    /// [`NewtonKrylov::newton_max`], or where a correction did not lower the residual (the
    /// iterate before it is kept).
    pub newton_unconverged: usize,
}

/// The solver's buffers, bounds and counts.
#[derive(Debug)]
pub struct NewtonKrylov {
    b: Vec<f64>,
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
    residual: Vec<f64>,
    delta: Vec<f64>,
    /// The most conjugate-gradient iterations of one linear solve ([`KRYLOV_MAX_ITERATIONS`];
    /// 0 keeps the rest factor's solve: the Jacobian frozen at rest).
    pub krylov_max: usize,
    /// The most Newton corrections of one step ([`NEWTON_MAX_ITERATIONS`]; 0 keeps the
    /// linearised step).
    pub newton_max: usize,
    /// What the solves have done.
    pub solves: NewtonSolves,
}

impl NewtonKrylov {
    /// Buffers for `n` unknowns, the default bounds.
    pub fn new(n: usize, krylov_max: usize, newton_max: usize) -> Self {
        let zeros = || vec![0.0; n];
        Self {
            b: zeros(),
            r: zeros(),
            z: zeros(),
            p: zeros(),
            q: zeros(),
            residual: zeros(),
            delta: zeros(),
            krylov_max,
            newton_max,
            solves: NewtonSolves::default(),
        }
    }

    /// Bytes held by the buffers.
    pub fn memory_bytes(&self) -> usize {
        7 * self.b.len() * 8
    }

    /// The step's unknown `y` from the linearised right-hand side `b` (given in `y`): the linear
    /// solve, then Newton's corrections until the residual is [`NEWTON_TOLERANCE`] of `scale`
    /// (the size of the equation's terms). Allocation-free.
    pub fn solve(&mut self, eq: &mut impl StepEquation, y: &mut [f64], scale: f64) -> Result<(), SparseError> {
        self.solves.steps += 1;
        self.linear_solve(eq, y, scale)?;
        if self.newton_max == 0 {
            return Ok(());
        }
        let (mut newton, mut last) = (0, f64::INFINITY);
        loop {
            eq.residual(y, &mut self.residual);
            let residual = self.residual.iter().map(|r| r * r).sum::<f64>().sqrt();
            if residual <= NEWTON_TOLERANCE * scale {
                break;
            }
            if residual.partial_cmp(&last) != Some(std::cmp::Ordering::Less) {
                // Not converging (a tangent that leaves out part of the force's change, far from
                // the solution): back to the last iterate.
                if newton > 0 {
                    for (y, d) in y.iter_mut().zip(&self.delta) {
                        *y -= d;
                    }
                    newton -= 1;
                }
                self.solves.newton_unconverged += 1;
                break;
            }
            if newton == self.newton_max {
                self.solves.newton_unconverged += 1;
                break;
            }
            last = residual;
            let mut delta = std::mem::take(&mut self.delta);
            delta.copy_from_slice(&self.residual);
            let solved = self.linear_solve(eq, &mut delta, scale);
            self.delta = delta;
            solved?;
            for (y, d) in y.iter_mut().zip(&self.delta) {
                *y += d;
            }
            newton += 1;
        }
        self.solves.newton += newton;
        self.solves.newton_most = self.solves.newton_most.max(newton);
        Ok(())
    }

    /// Solves `(a M + k K_t) y = b`, `b` given in `y` and replaced by the solution: conjugate
    /// gradients preconditioned with the rest factor, from its solve, until the residual is
    /// [`KRYLOV_TOLERANCE`] of `|b|` or of `scale` (the equation's terms' size), whichever is
    /// larger, at most [`NewtonKrylov::krylov_max`] iterations. Allocation-free.
    fn linear_solve(&mut self, eq: &mut impl StepEquation, y: &mut [f64], scale: f64) -> Result<(), SparseError> {
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
        self.b.copy_from_slice(y);
        eq.precondition(y)?;
        // r = b - A y.
        eq.product(y, &mut self.q);
        for ((r, b), q) in self.r.iter_mut().zip(&self.b).zip(&self.q) {
            *r = b - q;
        }
        // Relative to `|b|` alone, a step near rest (`b` near 0) would iterate on round-off.
        let stop = (KRYLOV_TOLERANCE * KRYLOV_TOLERANCE) * dot(&self.b, &self.b).max(scale * scale);
        let mut iterations = 0;
        let mut converged = dot(&self.r, &self.r) <= stop;
        if !converged {
            self.z.copy_from_slice(&self.r);
            eq.precondition(&mut self.z)?;
            self.p.copy_from_slice(&self.z);
            let mut rz = dot(&self.r, &self.z);
            while iterations < self.krylov_max {
                eq.product(&self.p, &mut self.q);
                let pq = dot(&self.p, &self.q);
                if pq.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                    break; // p = 0 to round-off: nothing left to reduce
                }
                let step = rz / pq;
                for ((y, r), (p, q)) in y.iter_mut().zip(self.r.iter_mut()).zip(self.p.iter().zip(&self.q)) {
                    *y += step * p;
                    *r -= step * q;
                }
                iterations += 1;
                converged = dot(&self.r, &self.r) <= stop;
                if converged {
                    break;
                }
                self.z.copy_from_slice(&self.r);
                eq.precondition(&mut self.z)?;
                let rz_next = dot(&self.r, &self.z);
                let beta = rz_next / rz;
                rz = rz_next;
                for (p, z) in self.p.iter_mut().zip(&self.z) {
                    *p = z + beta * *p;
                }
            }
        }
        let s = &mut self.solves;
        s.solves += 1;
        s.iterations += iterations;
        s.most = s.most.max(iterations);
        s.unconverged += usize::from(!converged);
        Ok(())
    }
}
