//! A symmetric positive-definite sparse system with a fixed pattern, factorised by faer's sparse
//! Cholesky (`L L^T`).
//!
//! The symbolic factorisation (ordering and elimination tree) is computed once per pattern. After
//! that, [`SpdSystem::factor`] and [`SpdSystem::solve_in_place`] allocate nothing: values are
//! written into preallocated storage through precomputed slots, and faer works in a preallocated
//! scratch buffer. This is what lets the FEM refactor cheaply per constraint set and the MSM
//! Newton and implicit solvers refactor every step.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

/// Errors of the sparse solver.
#[derive(Debug, thiserror::Error)]
pub enum SparseError {
    /// The pattern could not be built (index out of range, out of memory).
    #[error("sparse pattern: {0}")]
    Pattern(String),
    /// The matrix is not numerically positive definite.
    #[error("matrix is not positive definite (Cholesky factorisation failed)")]
    NotPositiveDefinite,
    /// A contact solved on the system did not settle (`response::contact`).
    #[error("{0}")]
    Contact(String),
    /// [`SpdSystem::solve_in_place`] was called before a successful [`SpdSystem::factor`].
    #[error("solve called before a successful factorisation")]
    NotFactored,
    /// The factor would need more memory than [`MAX_FACTOR_BYTES`] (found by the symbolic
    /// analysis, before any numeric work).
    #[error(
        "the sparse factor of this {n}-unknown system would need {} MB, above the bound of {} MB",
        bytes >> 20,
        MAX_FACTOR_BYTES >> 20
    )]
    TooLarge {
        /// Unknowns.
        n: usize,
        /// Bytes the factor's values and indices would take.
        bytes: usize,
    },
}

/// Largest sparse factor any solver allocates, bytes.
pub const MAX_FACTOR_BYTES: usize = 3 << 30;

/// A symmetric matrix stored as its lower triangle (CSC), with its kept symbolic Cholesky.
pub struct SpdSystem {
    n: usize,
    pattern: SymbolicSparseColMat<u32>,
    values: Vec<f64>,
    symbolic: SymbolicCholesky<u32>,
    l_values: Vec<f64>,
    scratch: MemBuffer,
    factored: bool,
}

impl std::fmt::Debug for SpdSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpdSystem")
            .field("n", &self.n)
            .field("nnz_lower", &self.values.len())
            .field("nnz_factor", &self.l_values.len())
            .finish()
    }
}

impl SpdSystem {
    /// Builds the pattern from `(row, col)` entries (either triangle; each is mapped to the lower
    /// one) and returns the system with, for each entry, the slot its value goes to. The
    /// elimination order is faer's approximate minimum degree.
    pub fn new(n: usize, entries: &[(usize, usize)]) -> Result<(Self, Vec<u32>), SparseError> {
        Self::ordered(n, entries, None)
    }

    /// [`SpdSystem::new`] for unknowns on the nodes of a grid, `node_of[u]` the `(i, j, k)` of
    /// unknown `u`'s node (couplings only between nodes at most one apart along each axis), in
    /// the grid's nested dissection ([`nested_dissection`]). On the cube's full systems the
    /// factor is 1.8 (FEM, 27 neighbours) to 3.2 (shear lattice, 19) times smaller than with
    /// approximate minimum degree at 32^3: 1.2 GB where it was 2.2 and 3.8 GB.
    pub fn on_grid(
        n: usize,
        entries: &[(usize, usize)],
        node_of: &[[u32; 3]],
    ) -> Result<(Self, Vec<u32>), SparseError> {
        if node_of.len() != n {
            return Err(SparseError::Pattern(format!("{} node positions for {n} unknowns", node_of.len())));
        }
        Self::ordered(n, entries, Some(&nested_dissection(node_of)))
    }

    /// [`SpdSystem::new`] eliminating in the order `order` (`order[k]`: the unknown eliminated
    /// `k`-th), else in approximate minimum degree.
    fn ordered(n: usize, entries: &[(usize, usize)], order: Option<&[u32]>) -> Result<(Self, Vec<u32>), SparseError> {
        // Lower-triangle (row, col) of every entry, then every diagonal (so a shift always fits).
        let mut lower = Vec::with_capacity(entries.len() + n);
        for &(r, c) in entries {
            if r >= n || c >= n {
                return Err(SparseError::Pattern(format!("entry ({r}, {c}) outside {n} x {n}")));
            }
            lower.push(if r >= c { (r as u32, c as u32) } else { (c as u32, r as u32) });
        }
        lower.extend((0..n as u32).map(|d| (d, d)));
        // Counting sort by column, then sort and deduplicate the rows of each column.
        let mut start = vec![0usize; n + 1];
        for &(_, c) in &lower {
            start[c as usize + 1] += 1;
        }
        for c in 0..n {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut by_col = vec![(0u32, 0u32); lower.len()];
        for (e, &(r, c)) in lower.iter().enumerate() {
            by_col[fill[c as usize]] = (r, e as u32);
            fill[c as usize] += 1;
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        let mut slot_of = vec![0u32; lower.len()];
        col_ptr.push(0u32);
        for c in 0..n {
            let col = &mut by_col[start[c]..start[c + 1]];
            col.sort_unstable();
            let mut last = u32::MAX;
            for &(r, e) in col.iter() {
                if r != last {
                    row_idx.push(r);
                    last = r;
                }
                slot_of[e as usize] = (row_idx.len() - 1) as u32;
            }
            col_ptr.push(row_idx.len() as u32);
        }
        let pattern = SymbolicSparseColMat::<u32>::new_checked(n, n, col_ptr, None, row_idx);
        slot_of.truncate(entries.len());
        let slots = slot_of;
        let mut inverse = Vec::new();
        let ordering = match order {
            Some(forward) => {
                // Each unknown exactly once, else no permutation (faer would panic).
                inverse = vec![u32::MAX; n];
                for (k, &u) in forward.iter().enumerate() {
                    match inverse.get_mut(u as usize) {
                        Some(slot) if *slot == u32::MAX => *slot = k as u32,
                        _ => return Err(SparseError::Pattern(format!("elimination order repeats or exceeds {u}"))),
                    }
                }
                if forward.len() != n {
                    return Err(SparseError::Pattern(format!(
                        "elimination order of {} for {n} unknowns",
                        forward.len()
                    )));
                }
                SymmetricOrdering::Custom(PermRef::new_checked(forward, &inverse, n))
            }
            None => SymmetricOrdering::Amd,
        };
        let symbolic = factorize_symbolic_cholesky(pattern.as_ref(), Side::Lower, ordering, Default::default())
            .map_err(|e| SparseError::Pattern(format!("{e:?}")))?;
        drop(inverse);
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        let bytes = symbolic.len_val().saturating_mul(8 + 4);
        if bytes > MAX_FACTOR_BYTES {
            return Err(SparseError::TooLarge { n, bytes });
        }
        let scratch = MemBuffer::try_new(req).map_err(|_| SparseError::Pattern("out of memory".into()))?;
        let values = vec![0.0; pattern.row_idx().len()];
        let l_values = vec![0.0; symbolic.len_val()];
        Ok((Self { n, pattern, values, symbolic, l_values, scratch, factored: false }, slots))
    }

    /// Dimension.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Approximate bytes held: matrix pattern and values, factor values (the symbolic
    /// factor's index arrays are counted as one index per factor entry).
    pub fn memory_bytes(&self) -> usize {
        self.values.len() * (8 + 4) + (self.n + 1) * 4 + self.l_values.len() * (8 + 4)
    }

    /// Whether the current values are factorised.
    pub fn is_factored(&self) -> bool {
        self.factored
    }

    /// Forgets the factorisation (the next solve needs a new [`SpdSystem::factor`]).
    pub fn invalidate(&mut self) {
        self.factored = false;
    }

    /// Sets every stored value to zero (and invalidates the factorisation).
    pub fn clear(&mut self) {
        self.values.fill(0.0);
        self.factored = false;
    }

    /// Adds `v` at a slot returned by [`SpdSystem::new`].
    #[inline]
    pub fn add(&mut self, slot: u32, v: f64) {
        self.values[slot as usize] += v;
        self.factored = false;
    }

    /// The stored values (lower triangle, CSC order).
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Replaces the stored values (same length and order as [`SpdSystem::values`]).
    pub fn set_values(&mut self, values: &[f64]) {
        self.values.copy_from_slice(values);
        self.factored = false;
    }

    /// Decouples the degrees of freedom marked in `fixed`: their rows and columns become zero and
    /// their diagonal `diag`, so that a solve with a zero right-hand side there returns zero there
    /// and the other unknowns see exactly the reduced system.
    pub fn decouple(&mut self, fixed: &[bool], diag: f64) {
        let col_ptr = self.pattern.col_ptr();
        let row_idx = self.pattern.row_idx();
        for c in 0..self.n {
            for s in col_ptr[c] as usize..col_ptr[c + 1] as usize {
                let r = row_idx[s] as usize;
                if fixed[c] || fixed[r] {
                    self.values[s] = if r == c { diag } else { 0.0 };
                }
            }
        }
        self.factored = false;
    }

    /// Adds `v` to every diagonal entry.
    pub fn add_diagonal(&mut self, v: f64) {
        let col_ptr = self.pattern.col_ptr();
        let row_idx = self.pattern.row_idx();
        for c in 0..self.n {
            // The diagonal is the first entry of each lower-triangle column (rows sorted).
            let s = col_ptr[c] as usize;
            debug_assert_eq!(row_idx[s] as usize, c);
            self.values[s] += v;
        }
        self.factored = false;
    }

    /// Adds `v * w[i]` to diagonal entry `i`.
    pub fn add_diagonal_scaled(&mut self, v: f64, w: &[f64]) {
        let col_ptr = self.pattern.col_ptr();
        for (c, wc) in w.iter().enumerate().take(self.n) {
            self.values[col_ptr[c] as usize] += v * wc;
        }
        self.factored = false;
    }

    /// Computes `y = A x` from the stored lower triangle.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        let col_ptr = self.pattern.col_ptr();
        let row_idx = self.pattern.row_idx();
        for c in 0..self.n {
            for s in col_ptr[c] as usize..col_ptr[c + 1] as usize {
                let r = row_idx[s] as usize;
                let a = self.values[s];
                y[r] += a * x[c];
                if r != c {
                    y[c] += a * x[r];
                }
            }
        }
    }

    /// Numeric Cholesky factorisation of the current values, in preallocated memory.
    pub fn factor(&mut self) -> Result<(), SparseError> {
        self.factored = false;
        let a = SparseColMatRef::new(self.pattern.as_ref(), &self.values);
        self.symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.l_values,
                a,
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut self.scratch),
                Default::default(),
            )
            .map_err(|_| SparseError::NotPositiveDefinite)?;
        self.factored = true;
        Ok(())
    }

    /// Solves `A x = b` in place (`rhs` holds `b` on entry, `x` on exit). Allocation-free.
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) -> Result<(), SparseError> {
        if !self.factored {
            return Err(SparseError::NotFactored);
        }
        let llt = LltRef::new(&self.symbolic, &self.l_values);
        let n = self.n;
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            Par::Seq,
            MemStack::new(&mut self.scratch),
        );
        Ok(())
    }
}

impl SpdSystem {
    /// Solves `A X = B` in place for `cols` right-hand sides stored column after column in `rhs`
    /// (`n * cols` values). Allocates its own scratch: for reference computations, not for a step.
    pub fn solve_columns_in_place(&mut self, rhs: &mut [f64], cols: usize) -> Result<(), SparseError> {
        if !self.factored {
            return Err(SparseError::NotFactored);
        }
        if rhs.len() != self.n * cols {
            return Err(SparseError::Pattern(format!("{} values for {cols} columns of {}", rhs.len(), self.n)));
        }
        let req = self.symbolic.solve_in_place_scratch::<f64>(cols, Par::Seq);
        let mut scratch = MemBuffer::try_new(req).map_err(|_| SparseError::Pattern("out of memory".into()))?;
        let llt = LltRef::new(&self.symbolic, &self.l_values);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, self.n, cols),
            Par::Seq,
            MemStack::new(&mut scratch),
        );
        Ok(())
    }

    /// Nonzeros of the Cholesky factor.
    pub fn factor_nonzeros(&self) -> usize {
        self.l_values.len()
    }
}

/// A set of this few unknowns, or one this thin along its longest axis, is eliminated as it comes.
const DISSECTION_LEAF: usize = 64;

/// The nested dissection of unknowns on grid nodes (`node_of[u]`, as in [`SpdSystem::on_grid`]):
/// the set's longest axis is cut by the plane of nodes at its middle coordinate, which
/// separates the two sides (no coupling reaches two nodes apart); each side is ordered the same
/// way, then the plane last. Returns the unknowns in elimination order.
pub fn nested_dissection(node_of: &[[u32; 3]]) -> Vec<u32> {
    let mut order = Vec::with_capacity(node_of.len());
    // Sets still to order, each with its separator to append after it (taken last in, first
    // out: the left side, the right side, then the plane).
    enum Task {
        Split(Vec<u32>),
        Emit(Vec<u32>),
    }
    let mut stack = vec![Task::Split((0..node_of.len() as u32).collect())];
    while let Some(task) = stack.pop() {
        let set = match task {
            Task::Emit(set) => {
                order.extend(set);
                continue;
            }
            Task::Split(set) => set,
        };
        let (mut lo, mut hi) = ([u32::MAX; 3], [0u32; 3]);
        for &u in &set {
            for a in 0..3 {
                lo[a] = lo[a].min(node_of[u as usize][a]);
                hi[a] = hi[a].max(node_of[u as usize][a]);
            }
        }
        let axis = (0..3).max_by_key(|&a| hi[a].saturating_sub(lo[a])).unwrap_or(0);
        if set.len() <= DISSECTION_LEAF || hi[axis].saturating_sub(lo[axis]) < 2 {
            order.extend(set);
            continue;
        }
        let middle = lo[axis] + (hi[axis] - lo[axis]) / 2;
        let (mut left, mut right, mut plane) = (Vec::new(), Vec::new(), Vec::new());
        for u in set {
            match node_of[u as usize][axis].cmp(&middle) {
                std::cmp::Ordering::Less => left.push(u),
                std::cmp::Ordering::Greater => right.push(u),
                std::cmp::Ordering::Equal => plane.push(u),
            }
        }
        stack.push(Task::Emit(plane));
        stack.push(Task::Split(right));
        stack.push(Task::Split(left));
    }
    order
}

/// The largest grid each direct solve accepts, nodes per axis, at the memory its factor needs
/// (the sparse factor bound, [`MAX_FACTOR_BYTES`]); checked before any work
/// ([`DirectSolve::check_grid`]): the FEM patch cases and the touch benchmark (full, unreduced
/// systems).
pub const MAX_NODES_FEM_PATCH: usize = 32;
/// See [`MAX_NODES_FEM_PATCH`]: the static Newton solve of the shear and hex lattices.
pub const MAX_NODES_MSM_NEWTON: usize = 40;

/// A direct solve whose factor bounds the grid ([`MAX_NODES_FEM_PATCH`],
/// [`MAX_NODES_MSM_NEWTON`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DirectSolve {
    /// The FEM patch cases: a full, unreduced system.
    FemPatch,
    /// The touch benchmark: full, unreduced FEM systems.
    TouchBenchmark,
    /// The static Newton solve of the shear and hex lattices.
    MsmNewton,
}

impl DirectSolve {
    /// The largest grid this solve accepts, nodes per axis.
    pub const fn max_nodes(self) -> usize {
        match self {
            DirectSolve::FemPatch | DirectSolve::TouchBenchmark => MAX_NODES_FEM_PATCH,
            DirectSolve::MsmNewton => MAX_NODES_MSM_NEWTON,
        }
    }

    /// Refuses a grid of `n` nodes per axis above [`DirectSolve::max_nodes`], with a message
    /// naming `--nodes`.
    pub fn check_grid(self, n: usize) -> Result<(), String> {
        let what = match self {
            DirectSolve::FemPatch => "the FEM patch cases (a full, unreduced system)",
            DirectSolve::TouchBenchmark => "the touch benchmark (full, unreduced systems)",
            DirectSolve::MsmNewton => "the static Newton solve of the shear and hex lattices",
        };
        let max = self.max_nodes();
        if n > max {
            return Err(format!(
                "--nodes {n} is too large for {what}: at most {max} nodes per axis, whose factor fits the bound of \
                 {} MB",
                MAX_FACTOR_BYTES >> 20
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
