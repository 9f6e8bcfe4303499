//! A node tied to a point by a spring and a damper (the user's drag), carried inside an implicit
//! step's solve.
//!
//! An implicit step solves `(a M + c_s C + k_s K) y = b` for its unknown `y` (`v'` for backward
//! Euler, `dx` for the trapezoidal rule). The anchor's spring `k` and damper `c` act on its node's
//! three unknowns alone and are linear, so they add `d = c_s c + k_s k` to those three diagonal
//! entries, and the spring's pull at the step's start, `k (target - x)`, joins the node's external
//! force (its caller puts it there). The step then treats the anchor exactly as its scheme treats
//! the tissue: a trapezoidal step stays trapezoidal and the held node comes to rest where the pull
//! balances the tissue. (A split step after the tissue's, backward Euler on the node alone, is
//! consistent with symplectic Euler only: after a trapezoidal step it left the held node a steady
//! velocity of `dt f / (2 m)`.)
//!
//! A system factorised once without the anchor is corrected by the Woodbury identity:
//! `(A + d U U^T)^-1 b = A^-1 b - W (I / d + U^T W)^-1 U^T A^-1 b`, `U` the node's three unit
//! columns and `W = A^-1 U`. [`AnchoredSolve`] keeps `W`: three solves when the node, `d` or the
//! factor changes, then a 3x3 product and three updates a solve. Allocation-free once built.

use super::sparse::{SparseError, SpdSystem};

/// A node tied to a point by an isotropic spring and damper.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Anchor {
    /// The held node.
    pub node: usize,
    /// Spring stiffness, N/m.
    pub stiffness: f64,
    /// Damping, N s/m.
    pub damping: f64,
}

impl Anchor {
    /// What the anchor adds to the diagonal of its node's three unknowns in a system scaled
    /// `c_scale` on damping and `k_scale` on stiffness.
    pub fn diagonal(&self, c_scale: f64, k_scale: f64) -> f64 {
        c_scale * self.damping + k_scale * self.stiffness
    }
}

/// An anchor in one step's system: its node's three unknowns and what it adds to their diagonal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Held {
    /// The node's unknowns.
    pub unknowns: [usize; 3],
    /// `c_s c + k_s k` ([`Anchor::diagonal`]).
    pub diagonal: f64,
}

impl Held {
    /// Adds `sign d y` on the held unknowns to `out` (the anchor's share of a product, or, with
    /// `sign = -1`, of a residual).
    pub fn add_to(&self, y: &[f64], sign: f64, out: &mut [f64]) {
        for j in self.unknowns {
            out[j] += sign * self.diagonal * y[j];
        }
    }
}

/// The correction of a factorised system `A` to `A + d U U^T` on three unknowns (see the
/// module's documentation).
#[derive(Debug)]
pub struct AnchoredSolve {
    /// `A^-1 e_j` for the three unknowns.
    w: [Vec<f64>; 3],
    /// `(I / d + U^T W)^-1`.
    inverse: [[f64; 3]; 3],
    /// The unknowns and `d` that `w` and `inverse` are for.
    key: Option<([usize; 3], f64)>,
}

impl AnchoredSolve {
    /// Buffers for a system of `n` unknowns.
    pub fn new(n: usize) -> Self {
        Self { w: std::array::from_fn(|_| vec![0.0; n]), inverse: [[0.0; 3]; 3], key: None }
    }

    /// Forgets the correction (the factor changed).
    pub fn invalidate(&mut self) {
        self.key = None;
    }

    /// Makes the correction ready for `d` on `unknowns` of the factorised `system`: three solves
    /// when they or the factor changed since the last call, nothing otherwise. Allocation-free.
    pub fn prepare(&mut self, system: &mut SpdSystem, held: Held) -> Result<(), SparseError> {
        let Held { unknowns, diagonal: d } = held;
        if self.key == Some((unknowns, d)) {
            return Ok(());
        }
        self.key = None;
        if !(d.is_finite() && d > 0.0) {
            return Err(SparseError::Pattern(format!("an anchor's diagonal of {d}: it must be positive")));
        }
        for (w, &j) in self.w.iter_mut().zip(&unknowns) {
            w.fill(0.0);
            w[j] = 1.0;
            system.solve_in_place(w)?;
        }
        // I / d + U^T W, symmetric positive definite: inverted by its cofactors.
        let m: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| self.w[j][unknowns[i]] + if i == j { 1.0 / d } else { 0.0 })
        });
        let cofactor = |i: usize, j: usize| {
            let (r, s) = ((i + 1) % 3, (i + 2) % 3);
            let (p, q) = ((j + 1) % 3, (j + 2) % 3);
            m[r][p] * m[s][q] - m[r][q] * m[s][p]
        };
        let det = m[0][0] * cofactor(0, 0) + m[0][1] * cofactor(0, 1) + m[0][2] * cofactor(0, 2);
        if !(det.is_finite() && det > 0.0) {
            return Err(SparseError::NotPositiveDefinite);
        }
        self.inverse = std::array::from_fn(|i| std::array::from_fn(|j| cofactor(j, i) / det));
        self.key = Some((unknowns, d));
        Ok(())
    }

    /// Turns `y = A^-1 b` into `(A + d U U^T)^-1 b` (after [`AnchoredSolve::prepare`]). A no-op
    /// when not prepared.
    pub fn correct(&self, y: &mut [f64]) {
        let Some((unknowns, _)) = self.key else {
            return;
        };
        let at = unknowns.map(|j| y[j]);
        let s: [f64; 3] = std::array::from_fn(|i| (0..3).map(|j| self.inverse[i][j] * at[j]).sum());
        for (w, s) in self.w.iter().zip(s) {
            for (y, w) in y.iter_mut().zip(w) {
                *y -= s * w;
            }
        }
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        3 * self.w[0].len() * 8
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small SPD system: a 1-D chain of springs with masses on the diagonal.
    fn chain(n: usize) -> (SpdSystem, Vec<Vec<f64>>) {
        let mut entries = Vec::new();
        let mut dense = vec![vec![0.0; n]; n];
        for i in 0..n {
            entries.push((i, i));
            dense[i][i] += 3.0;
            if i + 1 < n {
                entries.push((i + 1, i));
                dense[i][i] += 1.0;
                dense[i + 1][i + 1] += 1.0;
                dense[i + 1][i] -= 1.0;
                dense[i][i + 1] -= 1.0;
            }
        }
        let (mut system, slots) = SpdSystem::new(n, &entries).expect("pattern");
        for (slot, &(r, c)) in slots.iter().zip(&entries) {
            system.add(*slot, dense[r][c]);
        }
        system.factor().expect("factor");
        (system, dense)
    }

    /// The corrected solve satisfies the anchored system to round-off, on any three unknowns.
    #[test]
    fn the_corrected_solve_solves_the_anchored_system() {
        let n = 12;
        let (mut system, dense) = chain(n);
        let mut anchored = AnchoredSolve::new(n);
        for (unknowns, d) in [([3, 4, 5], 7.5), ([0, 6, 11], 1e6), ([9, 10, 11], 1e-3)] {
            anchored.prepare(&mut system, Held { unknowns, diagonal: d }).expect("prepare");
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin() + 0.3).collect();
            let mut y = b.clone();
            system.solve_in_place(&mut y).expect("solve");
            anchored.correct(&mut y);
            for i in 0..n {
                let ay: f64 = (0..n).map(|j| dense[i][j] * y[j]).sum::<f64>()
                    + if unknowns.contains(&i) { d * y[i] } else { 0.0 };
                assert!((ay - b[i]).abs() < 1e-9 * (1.0 + d), "{unknowns:?}, d = {d}, row {i}: {ay} vs {}", b[i]);
            }
        }
        let negative = Held { unknowns: [0, 1, 2], diagonal: -1.0 };
        assert!(anchored.prepare(&mut system, negative).is_err(), "a negative diagonal is refused");
        let mut y = vec![1.0; n];
        anchored.correct(&mut y);
        assert_eq!(y, vec![1.0; n], "a refused correction corrects nothing");
    }
}
