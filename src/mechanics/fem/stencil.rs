//! The linear FEM's force `K u` on the regular grid as a stencil: every node's row of `K` is 27
//! blocks of 3x3 (itself and its 26 neighbours), and since every element has the same `K_e`,
//! a row depends only on which faces of the cube the node lies on (below, inside or above along
//! each axis: 27 classes). So `K` is never stored: 27 classes x 27 blocks x 9 values, and a
//! product costs 243 multiply-adds a node, gathered row by row (no scatter), against the
//! element loop's 576 a node scattered over eight elements.

use super::element::{ElementStiffness, NODE_SIGNS};
use crate::mechanics::grid::Grid;

/// `K` of a grid's hex8 FEM as per-class 3x3 blocks.
#[derive(Debug, Clone)]
pub struct Stencil {
    n: usize,
    /// `blocks[class][offset]`: the 3x3 block (row-major) coupling a node of `class` with its
    /// neighbour at `offset = (dx + 1) + 3 (dy + 1) + 9 (dz + 1)`.
    blocks: Vec<[[f64; 9]; 27]>,
}

/// The class of index `i` along an axis of `n` nodes: 0 on the low face, 2 on the high one, 1
/// inside.
fn side(i: usize, n: usize) -> usize {
    if i == 0 {
        0
    } else if i + 1 == n {
        2
    } else {
        1
    }
}

impl Stencil {
    /// The stencil of `ke` (every element's matrix) on `grid`.
    pub fn new(grid: &Grid, ke: &ElementStiffness) -> Self {
        let n = grid.n();
        let mut blocks = vec![[[0.0; 9]; 27]; 27];
        // A representative node index per side: 0, 1 (inside) and n - 1.
        let representative = [0, 1.min(n - 1), n - 1];
        for (class, block) in blocks.iter_mut().enumerate() {
            let at = [class % 3, (class / 3) % 3, class / 9].map(|s| representative[s]);
            if (0..3).any(|a| side(at[a], n) != [class % 3, (class / 3) % 3, class / 9][a]) {
                continue; // no such node (n = 2 has no inside)
            }
            // Every element around the node: its lower corner at `at - 1` or `at` per axis.
            for corner in 0..8 {
                let lo: [isize; 3] = std::array::from_fn(|a| at[a] as isize - ((corner >> a) & 1) as isize);
                if lo.iter().any(|&l| l < 0 || l as usize + 1 >= n) {
                    continue;
                }
                let local = |l: usize| NODE_SIGNS[l].map(|s| usize::from(s > 0.0));
                let Some(a) = (0..8).find(|&l| (0..3).all(|c| lo[c] as usize + local(l)[c] == at[c])) else {
                    continue;
                };
                for b in 0..8 {
                    let d: [usize; 3] =
                        std::array::from_fn(|c| (local(b)[c] as isize - local(a)[c] as isize + 1) as usize);
                    let offset = d[0] + 3 * d[1] + 9 * d[2];
                    for r in 0..3 {
                        for c in 0..3 {
                            block[offset][3 * r + c] += ke[(3 * a + r, 3 * b + c)];
                        }
                    }
                }
            }
        }
        Self { n, blocks }
    }

    /// `blocks()[class][offset]`: the 3x3 block (row-major) coupling a node of `class` (`sx + 3 sy
    /// + 9 sz`, each side 0 on the low face, 1 inside, 2 on the high face) with its neighbour at
    /// `offset = (dx + 1) + 3 (dy + 1) + 9 (dz + 1)`.
    pub fn blocks(&self) -> &[[[f64; 9]; 27]] {
        &self.blocks
    }

    /// `out = K u`, interleaved (`3 node + component`), slab by slab of constant z, the slabs
    /// split over the physics pool ([`crate::mechanics::parallel`]) on a large enough grid (each
    /// row the same sum however split). Allocates nothing.
    pub fn apply(&self, u: &[f64], out: &mut [f64]) {
        self.apply_on(u, out, true);
    }

    /// [`Stencil::apply`], on the calling thread alone unless `parallel` (the bench's baseline).
    pub fn apply_on(&self, u: &[f64], out: &mut [f64], parallel: bool) {
        let n = self.n;
        let slab = 3 * n * n;
        let pool = crate::mechanics::parallel::pool()
            .filter(|_| parallel && n * n * n >= crate::mechanics::parallel::MIN_PARALLEL_ITEMS.max(4096));
        match pool {
            Some(pool) => pool.install(|| {
                use rayon::prelude::*;
                out.par_chunks_mut(slab).enumerate().for_each(|(k, o)| self.apply_slab(u, k, o));
            }),
            None => out.chunks_mut(slab).enumerate().for_each(|(k, o)| self.apply_slab(u, k, o)),
        }
    }

    /// The rows of the slab `z = k` into `out` (that slab's part of `K u`).
    fn apply_slab(&self, u: &[f64], k: usize, out: &mut [f64]) {
        let n = self.n;
        // Dof offsets of the 27 neighbours of an inside node.
        let offsets: [usize; 27] = std::array::from_fn(|o| 3 * ((o % 3) + n * ((o / 3) % 3) + n * n * (o / 9)));
        let inside = &self.blocks[13];
        for j in 0..n {
            let row_inside = side(j, n) == 1 && side(k, n) == 1;
            for i in 0..n {
                let p = i + n * (j + n * k);
                let acc = if row_inside && side(i, n) == 1 {
                    // All 27 neighbours exist: the first is at (i - 1, j - 1, k - 1).
                    let first = 3 * (p - 1 - n - n * n);
                    let mut acc = [0.0; 3];
                    for (b, &o) in inside.iter().zip(&offsets) {
                        let v = &u[first + o..first + o + 3];
                        acc[0] += b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
                        acc[1] += b[3] * v[0] + b[4] * v[1] + b[5] * v[2];
                        acc[2] += b[6] * v[0] + b[7] * v[1] + b[8] * v[2];
                    }
                    acc
                } else {
                    self.boundary_row(u, [i, j, k])
                };
                let at = 3 * (i + n * j);
                out[at..at + 3].copy_from_slice(&acc);
            }
        }
    }

    /// The row of a node on the cube's boundary (some neighbours missing).
    fn boundary_row(&self, u: &[f64], [i, j, k]: [usize; 3]) -> [f64; 3] {
        let n = self.n;
        let row = &self.blocks[side(i, n) + 3 * side(j, n) + 9 * side(k, n)];
        let range = |c: usize| (usize::from(c == 0), 1 + usize::from(c + 1 < n));
        let ((x0, x1), (y0, y1), (z0, z1)) = (range(i), range(j), range(k));
        let p = i + n * (j + n * k);
        let mut acc = [0.0; 3];
        for dz in z0..=z1 {
            for dy in y0..=y1 {
                for dx in x0..=x1 {
                    // The neighbour at (i + dx - 1, j + dy - 1, k + dz - 1).
                    let q = p + dx + n * (dy + n * dz) - 1 - n - n * n;
                    let b = &row[dx + 3 * dy + 9 * dz];
                    let v = &u[3 * q..3 * q + 3];
                    acc[0] += b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
                    acc[1] += b[3] * v[0] + b[4] * v[1] + b[5] * v[2];
                    acc[2] += b[6] * v[0] + b[7] * v[1] + b[8] * v[2];
                }
            }
        }
        acc
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::material::Material;

    #[test]
    fn the_stencil_is_the_element_loop() {
        let material = Material::object_a();
        for n in [2, 3, 5, 8] {
            let grid = Grid::new(n).unwrap();
            let fem = super::super::FemModel::new(grid, &material);
            let stencil = Stencil::new(&grid, &fem.ke);
            let u: Vec<f64> = (0..3 * grid.num_nodes()).map(|d| ((d * 7919) % 101) as f64 * 1e-5 - 5e-4).collect();
            let (mut a, mut b) = (vec![0.0; u.len()], vec![0.0; u.len()]);
            fem.apply_by_elements(&u, &mut a);
            stencil.apply(&u, &mut b);
            let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (x, y) in a.iter().zip(&b) {
                assert!((x - y).abs() <= 1e-12 * scale, "n = {n}: {x} vs {y}");
            }
        }
    }
}
