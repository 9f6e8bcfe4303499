//! Reduced unknowns of the mass-spring model: the free degrees of freedom, or the mirror-symmetric
//! subspace of a clamped benchmark case.
//!
//! A reduced unknown `i` stands for the vector `e_i = sum_{d -> i} s_d e_d` over the node degrees
//! of freedom `d` mapped to it with sign `s_d`. With `P` the matrix of these vectors, a tangent
//! system `K du = g` becomes `P^T K P c = P^T g`, `du = P c`.
//!
//! For a clamped case along axis `a` the lattice, its springs, the fixed face and the uniform load
//! are invariant under the reflections `x_b -> L - x_b` of the two transverse axes, so the
//! equilibrium (and every Newton iterate started from rest) is symmetric. Mapping every node onto
//! its representative in the quarter `i_b, i_c <= (n-1)/2` with the sign of the reflected
//! components solves it with a quarter of the unknowns, exactly. A transverse component that a
//! reflection maps onto minus itself (a node on an odd grid's mid-plane) is zero and maps nowhere.

use crate::mechanics::grid::Grid;

/// Node degree of freedom `3 p + c` -> reduced unknown and sign.
#[derive(Debug, Clone, PartialEq)]
pub struct DofMap {
    /// Per node dof: the reduced unknown (`u32::MAX`: held at zero) and the sign.
    pub map: Vec<(u32, f64)>,
    /// Number of reduced unknowns.
    pub n: usize,
    /// Per reduced unknown: how many node dofs map to it (the diagonal of `P^T P`).
    pub multiplicity: Vec<f64>,
    /// The transverse axes whose reflection the map respects (empty: no symmetry used).
    pub mirrored_axes: Vec<usize>,
}

impl DofMap {
    /// The diagonal of `P^T M P` for node masses `masses` (kg), into `out` (one per unknown).
    pub fn fold_masses(&self, masses: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for (d, &(r, _)) in self.map.iter().enumerate() {
            if r != u32::MAX {
                out[r as usize] += masses[d / 3];
            }
        }
    }

    /// Every dof of a free node is its own unknown; fixed nodes are held.
    pub fn free(fixed_node: &[bool]) -> Self {
        let mut map = vec![(u32::MAX, 1.0); 3 * fixed_node.len()];
        let mut n = 0u32;
        for (p, &fixed) in fixed_node.iter().enumerate() {
            if !fixed {
                for c in 0..3 {
                    map[3 * p + c] = (n, 1.0);
                    n += 1;
                }
            }
        }
        Self { map, n: n as usize, multiplicity: vec![1.0; n as usize], mirrored_axes: Vec::new() }
    }

    /// The symmetric subspace of a clamped case along `axis` (0-based): face `x_axis = 0` held,
    /// the two other axes mirrored.
    pub fn clamped_symmetric(grid: &Grid, axis: usize) -> Self {
        let n = grid.n();
        let half = (n - 1) / 2;
        let mirrored = [(axis + 1) % 3, (axis + 2) % 3];
        let mut map = vec![(u32::MAX, 1.0); 3 * grid.num_nodes()];
        let mut next = 0u32;
        // Unknowns for the representatives (transverse indices in the lower half).
        for p in 0..grid.num_nodes() {
            let ijk = grid.ijk(p);
            if ijk[axis] == 0 || mirrored.iter().any(|&b| ijk[b] > half) {
                continue;
            }
            for c in 0..3 {
                let zero = mirrored.iter().any(|&b| c == b && 2 * ijk[b] == n - 1);
                if !zero {
                    map[3 * p + c] = (next, 1.0);
                    next += 1;
                }
            }
        }
        let mut multiplicity = vec![0.0; next as usize];
        for p in 0..grid.num_nodes() {
            let mut rep = grid.ijk(p);
            let mut flipped = [false; 3];
            for &b in &mirrored {
                if rep[b] > half {
                    rep[b] = n - 1 - rep[b];
                    flipped[b] = true;
                }
            }
            let q = grid.node(rep[0], rep[1], rep[2]);
            for c in 0..3 {
                let (i, _) = map[3 * q + c];
                map[3 * p + c] = (i, if flipped[c] { -1.0 } else { 1.0 });
                if i != u32::MAX {
                    multiplicity[i as usize] += 1.0;
                }
            }
        }
        Self { map, n: next as usize, multiplicity, mirrored_axes: mirrored.to_vec() }
    }

    /// `out = P^T v` for a node vector `v` (structure of arrays).
    pub fn fold(&self, v: &[Vec<f64>; 3], out: &mut [f64]) {
        out.fill(0.0);
        for (d, &(i, s)) in self.map.iter().enumerate() {
            if i != u32::MAX {
                out[i as usize] += s * v[d % 3][d / 3];
            }
        }
    }

    /// `x += P c` for reduced values `c`.
    pub fn expand_add(&self, c: &[f64], x: &mut [Vec<f64>; 3]) {
        for (d, &(i, s)) in self.map.iter().enumerate() {
            if i != u32::MAX {
                x[d % 3][d / 3] += s * c[i as usize];
            }
        }
    }

    /// The image of node `p` under the group element `g` (bit `j` set: reflect `mirrored_axes[j]`).
    pub fn reflect_node(&self, grid: &Grid, p: usize, g: usize) -> usize {
        let mut ijk = grid.ijk(p);
        for (j, &b) in self.mirrored_axes.iter().enumerate() {
            if g >> j & 1 == 1 {
                ijk[b] = grid.n() - 1 - ijk[b];
            }
        }
        grid.node(ijk[0], ijk[1], ijk[2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_sizes() {
        let g = Grid::paper();
        let m = DofMap::clamped_symmetric(&g, 0);
        assert_eq!(m.n, 7 * 4 * 4 * 3);
        assert_eq!(m.multiplicity.iter().sum::<f64>(), (3 * 7 * 64) as f64);
        let g = Grid::new(5).unwrap();
        let m = DofMap::clamped_symmetric(&g, 2);
        // 4 layers x 3 x 3 representatives, minus the zero components on the two mid-planes.
        assert_eq!(m.n, 4 * (9 * 3 - 3 - 3));
    }
}
