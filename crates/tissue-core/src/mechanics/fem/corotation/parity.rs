//! The element matrix in the parity basis of the cube's corners: the Walsh transform of eight
//! corner values by butterflies and `K_e` as eight 3x3 blocks where it commutes with the
//! element's reflections.

use super::V3;
use super::corner;
use super::lanes::Lane;
use crate::mechanics::fem::element::{ElementStiffness, NODE_SIGNS};

/// The Walsh transform of eight corner values (index `bx + 2 by + 4 bz`) by butterflies over the
/// bits 1, 2, 4, each `(lo, hi) -> (lo + hi, hi - lo)`: `v_m = sum_i H_mi t_i`, `H = +-1`.
#[inline(always)]
fn walsh_transform<L: Lane>(mut t: [L; 8]) -> [L; 8] {
    unrolled!(pair in [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11] {
        let (i, j) = BUTTERFLIES[pair];
        (t[i], t[j]) = (t[i] + t[j], t[j] - t[i]);
    });
    t
}

/// The transpose of [`walsh_transform`]: butterflies `(lo, hi) -> (lo - hi, lo + hi)` in the same order.
#[inline(always)]
fn walsh_transform_transposed<L: Lane>(mut t: [L; 8]) -> [L; 8] {
    unrolled!(pair in [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11] {
        let (i, j) = BUTTERFLIES[pair];
        (t[i], t[j]) = (t[i] - t[j], t[i] + t[j]);
    });
    t
}

/// The pairs `(i, i | bit)`, `i & bit == 0`, of the butterflies over eight corners: bit 1, then
/// 2, then 4.
const BUTTERFLIES: [(usize, usize); 12] =
    [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)];

/// The Walsh function of mode `m` (bits `mx + 2 my + 4 mz`) at node `a`: the product of the
/// node's signs along the axes of `m`'s bits.
fn walsh(m: usize, a: usize) -> f64 {
    (0..3).filter(|axis| (m >> axis) & 1 == 1).map(|axis| NODE_SIGNS[a][axis]).product()
}

/// The element matrix in the parity basis of the cube's corners.
///
/// Per displacement component, the eight nodal values become eight Walsh modes, `v_m = sum_a
/// H_ma u_a` with `H_ma = +-1` (the product of node `a`'s signs along the axes of `m`). A reflection of the element along an axis flips the
/// modes odd along it and the displacement component along it, so a member `(c, m)` has the
/// parity `m xor e_c` under the three reflections. Where `K_e` commutes with them (a cube of an
/// orthotropic material whose axes are the grid's: both objects), it couples only members of
/// one parity: eight 3x3 blocks, 72 entries instead of 576, and `K_e u = H^T B H u` costs 72
/// multiplies and 192 adds (the transforms as butterflies) instead of 576 multiply-adds.
#[derive(Debug, Clone)]
pub struct ParityBlocks {
    /// `blocks[s][3 c + d]`: the coupling of component `c` in mode `s xor e_c` with component
    /// `d` in mode `s xor e_d` (`e = 1, 2, 4`), `H K_e H^T / 64`.
    blocks: [[f64; 9]; 8],
}

impl ParityBlocks {
    /// `ke`'s blocks, or `None` where it couples members of different parities by more than
    /// round-off (a material whose axes are not the grid's).
    pub fn of(ke: &ElementStiffness) -> Option<Self> {
        let entry = |(c, m): (usize, usize), (d, k): (usize, usize)| {
            let mut sum = 0.0;
            for a in 0..8 {
                for b in 0..8 {
                    sum += walsh(m, a) * ke[(3 * a + c, 3 * b + d)] * walsh(k, b);
                }
            }
            sum / 64.0
        };
        let members: Vec<(usize, usize)> = (0..3).flat_map(|c| (0..8).map(move |m| (c, m))).collect();
        let parity = |(c, m): (usize, usize)| m ^ (1 << c);
        let scale = ke.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for &i in &members {
            for &j in &members {
                if parity(i) != parity(j) && entry(i, j).abs() > 1e-12 * scale {
                    return None;
                }
            }
        }
        let blocks = std::array::from_fn(|s| {
            std::array::from_fn(|e| entry((e / 3, s ^ (1 << (e / 3))), (e % 3, s ^ (1 << (e % 3)))))
        });
        Some(Self { blocks })
    }

    /// `K_e local` through the parity blocks, `local[a][c]` the displacement of node `a` (spec
    /// order), component `c`.
    #[inline(always)]
    pub(super) fn apply<L: Lane>(&self, local: &[V3<L>; 8]) -> [V3<L>; 8] {
        // v[c][m] = sum_a H_ma local[a][c].
        let mut v = [[L::splat(0.0); 8]; 3];
        unrolled!(a in [0, 1, 2, 3, 4, 5, 6, 7] {
            unrolled!(c in [0, 1, 2] {
                v[c][corner(a)] = local[a][c];
            });
        });
        let v = [walsh_transform(v[0]), walsh_transform(v[1]), walsh_transform(v[2])];
        let mut g = [[L::splat(0.0); 8]; 3];
        unrolled!(s in [0, 1, 2, 3, 4, 5, 6, 7] {
            let b = &self.blocks[s];
            let m = [s ^ 1, s ^ 2, s ^ 4];
            let (x, y, z) = (v[0][m[0]], v[1][m[1]], v[2][m[2]]);
            unrolled!(c in [0, 1, 2] {
                g[c][m[c]] = L::splat(b[3 * c]) * x + L::splat(b[3 * c + 1]) * y + L::splat(b[3 * c + 2]) * z;
            });
        });
        // local forces = H^T g.
        let g = [walsh_transform_transposed(g[0]), walsh_transform_transposed(g[1]), walsh_transform_transposed(g[2])];
        let mut out = [[L::splat(0.0); 3]; 8];
        unrolled!(a in [0, 1, 2, 3, 4, 5, 6, 7] {
            unrolled!(c in [0, 1, 2] {
                out[a][c] = g[c][corner(a)];
            });
        });
        out
    }
}
