//! The cube's structured grid: nodes, hex8 elements, faces and the lattice spring families.
//!
//! Conventions (`shared/spec/benchmark.md`): side `L = 0.1 m`, `n` nodes per axis, spacing
//! `h = L / (n - 1)`, node `(i, j, k)` at `(i h, j h, k h)` with linear index `i + n j + n^2 k`
//! (x fastest). Axis 1 = x, 2 = y, 3 = z; in code axes are 0-based (`0 = x`).

/// Side of the cube, metres.
pub const CUBE_SIDE_M: f64 = 0.1;

/// Errors in grid construction.
#[derive(Debug, thiserror::Error)]
pub enum GridError {
    /// Fewer than two nodes per axis.
    #[error("nodes per axis must be at least 2, got {0}")]
    TooFewNodes(usize),
    /// More nodes than this program handles (the 3D arrays would not fit in memory).
    #[error("nodes per axis must be at most {max}, got {n}")]
    TooManyNodes {
        /// Requested.
        n: usize,
        /// Allowed maximum.
        max: usize,
    },
}

/// Largest supported number of nodes per axis: the GPU's explicit step runs at 64^3. (The FEM's
/// sparse Cholesky, in the grid's nested dissection, needs about 1.2 GB at 32^3 and grows like
/// n^4 (the factor's nonzeros): solves refuse a factor over
/// [`crate::mechanics::sparse::MAX_FACTOR_BYTES`] after its symbolic analysis, before the
/// numeric factorisation; some solvers have their own smaller grid limits.)
pub const MAX_NODES_PER_AXIS: usize = 64;

/// An `n x n x n` node cube of side [`CUBE_SIDE_M`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    n: usize,
    h: f64,
}

/// A family of lattice springs: every pair of nodes `(p, p + offset)` that both lie in the grid.
///
/// The offset is sign-normalised so that its linear index offset is positive.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SpringFamily {
    /// Lattice offset `(di, dj, dk)`.
    pub offset: [i32; 3],
}

impl SpringFamily {
    /// The family with lattice offset `o` (or `-o`, whichever has a positive linear offset).
    pub fn new(o: [i32; 3]) -> Self {
        // Linear order is x fastest, so the sign of the last non-zero component decides.
        let last = o.iter().rev().copied().find(|&c| c != 0).unwrap_or(0);
        let offset = if last < 0 { [-o[0], -o[1], -o[2]] } else { o };
        Self { offset }
    }

    /// Rest length in units of `h`.
    pub fn length_in_h(&self) -> f64 {
        let [a, b, c] = self.offset.map(f64::from);
        (a * a + b * b + c * c).sqrt()
    }
}

/// The three axis-aligned (structural) spring families, x, y, z: the paper's lattice.
pub fn axis_families() -> [SpringFamily; 3] {
    [SpringFamily::new([1, 0, 0]), SpringFamily::new([0, 1, 0]), SpringFamily::new([0, 0, 1])]
}

/// The face-diagonal families of each coordinate plane, both diagonals of every lattice square:
/// index 0 is the 1-2 (x-y) plane, 1 the 1-3 (x-z) plane, 2 the 2-3 (y-z) plane.
pub fn face_diagonal_families() -> [[SpringFamily; 2]; 3] {
    [
        [SpringFamily::new([1, 1, 0]), SpringFamily::new([1, -1, 0])],
        [SpringFamily::new([1, 0, 1]), SpringFamily::new([1, 0, -1])],
        [SpringFamily::new([0, 1, 1]), SpringFamily::new([0, 1, -1])],
    ]
}

/// The four body-diagonal families (the diagonals of every lattice cube).
pub fn body_diagonal_families() -> [SpringFamily; 4] {
    [[1, 1, 1], [1, 1, -1], [1, -1, 1], [-1, 1, 1]].map(SpringFamily::new)
}

impl Grid {
    /// The fraction of the elements around a spring of family `fam` starting at `node` that
    /// exist in the grid: an element-assembled lattice gives the spring this share of an
    /// interior spring's stiffness. A spring along a lattice axis has up to 4 elements around it,
    /// a face diagonal up to 2, a body diagonal 1: along each axis the spring does not move in,
    /// an element may lie on either side, unless the spring is on the boundary.
    pub fn element_share(&self, fam: SpringFamily, node: usize) -> f64 {
        let ijk = self.ijk(node);
        let mut share = 1.0;
        for a in 0..3 {
            if fam.offset[a] == 0 {
                let sides = usize::from(ijk[a] > 0) + usize::from(ijk[a] + 1 < self.n);
                share *= sides as f64 / 2.0;
            }
        }
        share
    }

    /// A grid with `n` nodes per axis.
    pub fn new(n: usize) -> Result<Self, GridError> {
        if n < 2 {
            return Err(GridError::TooFewNodes(n));
        }
        if n > MAX_NODES_PER_AXIS {
            return Err(GridError::TooManyNodes { n, max: MAX_NODES_PER_AXIS });
        }
        Ok(Self { n, h: CUBE_SIDE_M / (n - 1) as f64 })
    }

    /// The paper's grid, 8 nodes per axis.
    pub fn paper() -> Self {
        Self { n: 8, h: CUBE_SIDE_M / 7.0 }
    }

    /// Nodes per axis.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Node spacing, metres.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// Number of nodes, `n^3`.
    pub fn num_nodes(&self) -> usize {
        self.n * self.n * self.n
    }

    /// Number of hex elements, `(n-1)^3`.
    pub fn num_elements(&self) -> usize {
        let m = self.n - 1;
        m * m * m
    }

    /// Linear index of node `(i, j, k)`.
    #[inline]
    pub fn node(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.n * (j + self.n * k)
    }

    /// Lattice coordinates `(i, j, k)` of a node.
    #[inline]
    pub fn ijk(&self, node: usize) -> [usize; 3] {
        [node % self.n, (node / self.n) % self.n, node / (self.n * self.n)]
    }

    /// The `(i, j, k)` of each dof's node, three dofs a node ([`SpdSystem::on_grid`] for a full
    /// system).
    ///
    /// [`SpdSystem::on_grid`]: crate::mechanics::sparse::SpdSystem::on_grid
    pub fn dof_nodes(&self) -> Vec<[u32; 3]> {
        (0..3 * self.num_nodes()).map(|d| self.ijk(d / 3).map(|i| i as u32)).collect()
    }

    /// The `(i, j, k)` of each of `n` reduced unknowns, `unknown_of[d]` the unknown of node dof
    /// `d` (`u32::MAX`: none); an unknown that several dofs share (a mirrored system) takes the
    /// first one's node.
    pub fn unknown_nodes(&self, unknown_of: impl Iterator<Item = u32>, n: usize) -> Vec<[u32; 3]> {
        let mut nodes = vec![[u32::MAX; 3]; n];
        for (d, u) in unknown_of.enumerate() {
            if let Some(node) = nodes.get_mut(u as usize)
                && node[0] == u32::MAX
            {
                *node = self.ijk(d / 3).map(|i| i as u32);
            }
        }
        nodes
    }

    /// Whether a node lies on the cube's boundary.
    pub fn on_boundary(&self, node: usize) -> bool {
        self.ijk(node).iter().any(|&c| c == 0 || c + 1 == self.n)
    }

    /// Rest position of a node, metres.
    #[inline]
    pub fn position(&self, node: usize) -> [f64; 3] {
        self.ijk(node).map(|c| c as f64 * self.h)
    }

    /// Rest positions of all nodes.
    pub fn positions(&self) -> Vec<[f64; 3]> {
        (0..self.num_nodes()).map(|p| self.position(p)).collect()
    }

    /// The 8 nodes of element `(i, j, k)` in the spec's hex8 order.
    pub fn element_nodes(&self, i: usize, j: usize, k: usize) -> [usize; 8] {
        let n = |a, b, c| self.node(a, b, c);
        [
            n(i, j, k),
            n(i + 1, j, k),
            n(i + 1, j + 1, k),
            n(i, j + 1, k),
            n(i, j, k + 1),
            n(i + 1, j, k + 1),
            n(i + 1, j + 1, k + 1),
            n(i, j + 1, k + 1),
        ]
    }

    /// All elements, `(i, j, k)` with i fastest.
    pub fn elements(&self) -> impl Iterator<Item = [usize; 8]> + '_ {
        let m = self.n - 1;
        (0..m).flat_map(move |k| (0..m).flat_map(move |j| (0..m).map(move |i| self.element_nodes(i, j, k))))
    }

    /// The nodes of the cell holding the point `x` (clamped into the cube) and their trilinear
    /// weights: on a face, the face's nodes only (the others weigh 0); the one interpolation of a
    /// point onto the grid.
    pub fn corners(&self, x: [f64; 3]) -> [(usize, f64); 8] {
        let (n, h) = (self.n(), self.h());
        let mut base = [0usize; 3];
        let mut frac = [0.0; 3];
        for c in 0..3 {
            let u = (x[c] / h).clamp(0.0, (n - 1) as f64);
            base[c] = (u.floor() as usize).min(n - 2);
            frac[c] = u - base[c] as f64;
        }
        std::array::from_fn(|corner| {
            let o = [corner & 1, (corner >> 1) & 1, corner >> 2];
            let w = (0..3).map(|c| if o[c] == 1 { frac[c] } else { 1.0 - frac[c] }).product();
            (self.node(base[0] + o[0], base[1] + o[1], base[2] + o[2]), w)
        })
    }

    /// Nodes on the face `coordinate[axis] = 0` (`high = false`) or `= L` (`high = true`), in
    /// increasing index order. `axis` is 0-based.
    pub fn face_nodes(&self, axis: usize, high: bool) -> Vec<usize> {
        let layer = if high { self.n - 1 } else { 0 };
        (0..self.num_nodes()).filter(|&p| self.ijk(p)[axis] == layer).collect()
    }

    /// The node range `[lo, hi)` and validity of each pair `(p, p + s)` of a spring family, where
    /// `s` is the family's linear offset. Pairs whose lattice partner falls outside the grid (a
    /// wrap-around in linear index) are `false`.
    pub fn family_pairs(&self, fam: SpringFamily) -> (usize, usize, Vec<bool>) {
        let s = self.linear_offset(fam);
        let total = self.num_nodes();
        let (lo, hi) = if s < total { (0, total - s) } else { (0, 0) };
        let valid = (lo..hi)
            .map(|p| {
                let c = self.ijk(p);
                (0..3).all(|a| {
                    let t = c[a] as i64 + i64::from(fam.offset[a]);
                    t >= 0 && t < self.n as i64
                })
            })
            .collect();
        (lo, hi, valid)
    }

    /// Linear index offset of a family (positive by construction).
    pub fn linear_offset(&self, fam: SpringFamily) -> usize {
        let n = self.n as i64;
        let [a, b, c] = fam.offset.map(i64::from);
        let s = a + n * (b + n * c);
        debug_assert!(s > 0);
        s.unsigned_abs() as usize
    }

    /// The springs of a family as node pairs `(p, q)` with `p < q`.
    pub fn springs(&self, fam: SpringFamily) -> Vec<(usize, usize)> {
        let s = self.linear_offset(fam);
        let (lo, _, valid) = self.family_pairs(fam);
        valid.iter().enumerate().filter(|(_, v)| **v).map(|(p, _)| (lo + p, lo + p + s)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn element_shares() {
        let g = Grid::new(4).unwrap();
        let x = SpringFamily::new([1, 0, 0]);
        assert_eq!(g.element_share(x, g.node(1, 1, 1)), 1.0);
        assert_eq!(g.element_share(x, g.node(1, 0, 1)), 0.5);
        assert_eq!(g.element_share(x, g.node(1, 0, 3)), 0.25);
        let xy = SpringFamily::new([1, 1, 0]);
        assert_eq!(g.element_share(xy, g.node(0, 0, 1)), 1.0);
        assert_eq!(g.element_share(xy, g.node(0, 0, 0)), 0.5);
        assert_eq!(g.element_share(body_diagonal_families()[0], g.node(0, 0, 0)), 1.0);
    }

    #[test]
    fn spec_node_numbering() {
        let g = Grid::paper();
        assert_eq!(g.num_nodes(), 512);
        assert_eq!(g.num_elements(), 343);
        assert_eq!(g.position(7), [0.1, 0.0, 0.0]);
        assert_eq!(g.position(56), [0.0, 0.1, 0.0]);
        assert_eq!(g.position(511), [0.1, 0.1, 0.1]);
        assert_eq!(g.h(), 0.1 / 7.0);
        assert_eq!(g.element_nodes(0, 0, 0), [0, 1, 9, 8, 64, 65, 73, 72]);
        assert_eq!(g.face_nodes(0, true).len(), 64);
    }

    #[test]
    fn spring_counts() {
        for n in [2, 3, 8, 11] {
            let g = Grid::new(n).unwrap();
            let axis: usize = axis_families().iter().map(|f| g.springs(*f).len()).sum();
            assert_eq!(axis, 3 * n * n * (n - 1));
            let diag: usize = face_diagonal_families().iter().flatten().map(|f| g.springs(*f).len()).sum();
            assert_eq!(diag, 6 * n * (n - 1) * (n - 1));
        }
        let g = Grid::paper();
        let axis: usize = axis_families().iter().map(|f| g.springs(*f).len()).sum();
        assert_eq!(axis, 1344);
    }

    #[test]
    fn diagonal_springs_connect_lattice_neighbours() {
        let g = Grid::new(5).unwrap();
        for fam in face_diagonal_families().iter().flatten() {
            for (p, q) in g.springs(*fam) {
                let (a, b) = (g.position(p), g.position(q));
                let l: f64 = (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>().sqrt();
                assert!((l - g.h() * 2f64.sqrt()).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn rejects_small_grid() {
        assert!(Grid::new(1).is_err());
        assert!(Grid::new(2).is_ok());
    }
}
