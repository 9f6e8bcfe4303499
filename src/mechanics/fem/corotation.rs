//! The corotational hex8 element's force, `f_e = R K_e (R^T x_e - X_e)`, four elements at a time.
//!
//! `R` is each element's rotation, kept as a unit quaternion from one force evaluation to the
//! next and moved to the polar rotation of the deformation gradient at the element's centre,
//! `F = sum_a x_a (grad N_a)^T`, by iterations of the rotation extraction of Mueller et al. (2016)
//! until the correction is below a tolerance (`Corotation::tolerance`):
//! `omega = sum_c r_c x f_c / (|sum_c r_c . f_c| + eps)` over the columns of `R` and `F`, then
//! `R <- exp(omega) R`. Here the exponential is its trig-free first order, the
//! unit quaternion `(1, omega / 2) / |(1, omega / 2)|` (a turn of `2 atan(|omega| / 2)` about
//! `omega`, within `|omega|^3 / 12` of `|omega|`); the iteration's fixed point, `omega = 0`, is the
//! same polar rotation.
//!
//! The elements of a grid row (along x) have the same node pattern at consecutive node indices,
//! so on the component-wise positions `x[c][node]` the node `a` of four neighbouring elements is
//! four consecutive values: every operation runs on four lanes (`Lanes`), with AVX2 where the
//! CPU has it (no fused multiply-add: one element's force has the same bits in any lane and on
//! any path). A row whose length is not a multiple of four ends with four elements that overlap
//! the ones before; the rotations are double-buffered (read from the last evaluation's, written
//! to this one's), so an element computed twice gives the same bits twice.

use std::ops::{Add, Mul, Sub};

use super::element::{ElementStiffness, NODE_SIGNS};
use crate::mechanics::grid::Grid;

/// `W` values, one per element, operated on lane by lane.
#[derive(Debug, Clone, Copy)]
struct Lanes<const W: usize>([f64; W]);

impl<const W: usize> Lanes<W> {
    #[inline(always)]
    fn splat(v: f64) -> Self {
        Self([v; W])
    }
    #[inline(always)]
    fn map(self, f: impl Fn(f64) -> f64) -> Self {
        Self(self.0.map(f))
    }
    /// `W` consecutive values from `s[at..]`.
    #[inline(always)]
    fn load(s: &[f64], at: usize) -> Self {
        let s = &s[at..at + W];
        Self(std::array::from_fn(|l| s[l]))
    }
}

impl<const W: usize> Add for Lanes<W> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self(std::array::from_fn(|l| self.0[l] + o.0[l]))
    }
}

impl<const W: usize> Sub for Lanes<W> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self(std::array::from_fn(|l| self.0[l] - o.0[l]))
    }
}

impl<const W: usize> Mul for Lanes<W> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Self(std::array::from_fn(|l| self.0[l] * o.0[l]))
    }
}

impl<const W: usize> Mul<Lanes<W>> for f64 {
    type Output = Lanes<W>;
    #[inline(always)]
    fn mul(self, o: Lanes<W>) -> Lanes<W> {
        Lanes(o.0.map(|v| self * v))
    }
}

/// A vector of three lanes.
type V3<const W: usize> = [Lanes<W>; 3];

#[inline(always)]
fn cross<const W: usize>(a: V3<W>, b: V3<W>) -> V3<W> {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[inline(always)]
fn dot<const W: usize>(a: V3<W>, b: V3<W>) -> Lanes<W> {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The rotation matrix `m[row][col]` of the unit quaternion `[w, x, y, z]`.
#[inline(always)]
fn matrix<const W: usize>(q: [Lanes<W>; 4]) -> [V3<W>; 3] {
    let [w, x, y, z] = q;
    let one = Lanes::splat(1.0);
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let (xy, xz, yz, wx, wy, wz) = (x * y, x * z, y * z, w * x, w * y, w * z);
    [
        [one - 2.0 * (yy + zz), 2.0 * (xy - wz), 2.0 * (xz + wy)],
        [2.0 * (xy + wz), one - 2.0 * (xx + zz), 2.0 * (yz - wx)],
        [2.0 * (xz - wy), 2.0 * (yz + wx), one - 2.0 * (xx + yy)],
    ]
}

/// `K_e local`, eight rows at a time (`K_e` is symmetric: column j is row j): 576 multiply-adds.
#[inline(always)]
fn dense_product<const W: usize>(ke: &ElementStiffness, local: &[Lanes<W>; 24]) -> [Lanes<W>; 24] {
    let ke = ke.as_slice();
    let mut fl = [Lanes::<W>::splat(0.0); 24];
    for block in 0..3 {
        let mut acc = [Lanes::<W>::splat(0.0); 8];
        for (j, lj) in local.iter().enumerate() {
            let col = &ke[24 * j + 8 * block..24 * j + 8 * block + 8];
            for (acc, &k) in acc.iter_mut().zip(col) {
                *acc = *acc + k * *lj;
            }
        }
        fl[8 * block..8 * block + 8].copy_from_slice(&acc);
    }
    fl
}

/// The corner of node `a` (spec order) as bits `bx + 2 by + 4 bz`, 1 on the high side.
#[inline(always)]
fn corner(a: usize) -> usize {
    let b = NODE_SIGNS[a].map(|s| usize::from(s > 0.0));
    b[0] + 2 * b[1] + 4 * b[2]
}

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

    /// `K_e local` through the parity blocks.
    #[inline(always)]
    fn apply<const W: usize>(&self, local: &[Lanes<W>; 24]) -> [Lanes<W>; 24] {
        // v[c][m] = sum_a H_ma local[3 a + c], by butterflies over the corner bits.
        let mut v = [[Lanes::<W>::splat(0.0); 8]; 3];
        for a in 0..8 {
            for c in 0..3 {
                v[c][corner(a)] = local[3 * a + c];
            }
        }
        for t in &mut v {
            for bit in [1, 2, 4] {
                for i in (0..8).filter(|i| i & bit == 0) {
                    let (lo, hi) = (t[i], t[i | bit]);
                    (t[i], t[i | bit]) = (lo + hi, hi - lo);
                }
            }
        }
        let mut g = [[Lanes::<W>::splat(0.0); 8]; 3];
        for (s, b) in self.blocks.iter().enumerate() {
            let m = [s ^ 1, s ^ 2, s ^ 4];
            let (x, y, z) = (v[0][m[0]], v[1][m[1]], v[2][m[2]]);
            for c in 0..3 {
                g[c][m[c]] = b[3 * c] * x + b[3 * c + 1] * y + b[3 * c + 2] * z;
            }
        }
        // local forces = H^T g.
        for t in &mut g {
            for bit in [1, 2, 4] {
                for i in (0..8).filter(|i| i & bit == 0) {
                    let (lo, hi) = (t[i], t[i | bit]);
                    (t[i], t[i | bit]) = (lo - hi, lo + hi);
                }
            }
        }
        let mut out = [Lanes::<W>::splat(0.0); 24];
        for a in 0..8 {
            for c in 0..3 {
                out[3 * a + c] = g[c][corner(a)];
            }
        }
        out
    }
}

/// What every element's corotated force reads.
#[derive(Debug, Clone, Copy)]
pub struct Corotation<'a> {
    /// Positions, component-wise, metres.
    pub x: [&'a [f64]; 3],
    /// Rest positions, component-wise, metres.
    pub rest: [&'a [f64]; 3],
    /// The element matrix.
    pub ke: &'a ElementStiffness,
    /// The element matrix in the corners' parity basis, where it has that form.
    pub parity: Option<&'a ParityBlocks>,
    /// The grid.
    pub grid: Grid,
    /// The most iterations of the rotation extraction per evaluation.
    pub iterations: usize,
    /// Where the extraction stops: every lane's correction `|omega|` at most this, radians.
    pub tolerance: f64,
}

/// The identity rotation as a quaternion `[w, x, y, z]`.
pub const IDENTITY: [f64; 4] = [1.0, 0.0, 0.0, 0.0];

impl Corotation<'_> {
    /// Elements `first..first + W` (consecutive along x in one grid row, the first's lowest node
    /// `node`): their rotations moved on from `last` into `next`, their forces on their eight
    /// nodes into `out` (`out[e][3 a + c]`).
    #[inline(always)]
    fn elements<const W: usize>(&self, node: usize, last: &[[f64; 4]], next: &mut [[f64; 4]], out: &mut [[f64; 24]]) {
        let n = self.grid.n();
        let inv4h = 1.0 / (4.0 * self.grid.h());
        let corner = |a: usize| {
            let s = NODE_SIGNS[a].map(|s| usize::from(s > 0.0));
            node + s[0] + n * (s[1] + n * s[2])
        };
        let mut xa = [[Lanes::<W>::splat(0.0); 3]; 8];
        for (a, xa) in xa.iter_mut().enumerate() {
            for (c, v) in xa.iter_mut().enumerate() {
                *v = Lanes::load(self.x[c], corner(a));
            }
        }
        // F[r][c] = sum_a x_a[r] g_a[c], g_a = NODE_SIGNS[a] / 4h.
        let mut f = [[Lanes::<W>::splat(0.0); 3]; 3];
        for (a, x) in xa.iter().enumerate() {
            for (r, row) in f.iter_mut().enumerate() {
                for (c, v) in row.iter_mut().enumerate() {
                    *v = *v + (NODE_SIGNS[a][c] * inv4h) * x[r];
                }
            }
        }
        let column = |m: &[V3<W>; 3], c: usize| [m[0][c], m[1][c], m[2][c]];
        let mut q = [Lanes::<W>::splat(0.0); 4];
        for (l, last) in last.iter().enumerate().take(W) {
            for i in 0..4 {
                q[i].0[l] = last[i];
            }
        }
        let stop = 0.25 * self.tolerance * self.tolerance; // on |omega / 2|^2
        for _ in 0..self.iterations {
            let r = matrix(q);
            let mut axis = [Lanes::splat(0.0); 3];
            let mut denom = Lanes::splat(0.0);
            for c in 0..3 {
                let (rc, fc) = (column(&r, c), column(&f, c));
                let t = cross(rc, fc);
                axis = [axis[0] + t[0], axis[1] + t[1], axis[2] + t[2]];
                denom = denom + dot(rc, fc);
            }
            let scale = denom.map(|d| 0.5 / (d.abs() + f64::EPSILON));
            let h = axis.map(|a| a * scale); // omega / 2
            if dot(h, h).0.iter().all(|&s| s <= stop) {
                break;
            }
            // (1, h) * q, normalised.
            let (w, v) = (q[0], [q[1], q[2], q[3]]);
            let hv = cross(h, v);
            let nw = w - dot(h, v);
            let nv: V3<W> = [v[0] + w * h[0] + hv[0], v[1] + w * h[1] + hv[1], v[2] + w * h[2] + hv[2]];
            let inv = (nw * nw + dot(nv, nv)).map(|s| 1.0 / s.sqrt());
            q = [nw * inv, nv[0] * inv, nv[1] * inv, nv[2] * inv];
        }
        for (l, slot) in next.iter_mut().enumerate().take(W) {
            for i in 0..4 {
                slot[i] = q[i].0[l];
            }
        }
        let r = matrix(q);
        // R^T x_a - X_a.
        let mut local = [Lanes::<W>::splat(0.0); 24];
        for a in 0..8 {
            for c in 0..3 {
                let rotated = r[0][c] * xa[a][0] + r[1][c] * xa[a][1] + r[2][c] * xa[a][2];
                local[3 * a + c] = rotated - Lanes::load(self.rest[c], corner(a));
            }
        }
        let fl = match self.parity {
            Some(parity) => parity.apply(&local),
            None => dense_product(self.ke, &local),
        };
        // R f_local, per node, then out lane by lane.
        let mut fg = [Lanes::<W>::splat(0.0); 24];
        for a in 0..8 {
            let fa = [fl[3 * a], fl[3 * a + 1], fl[3 * a + 2]];
            for row in 0..3 {
                fg[3 * a + row] = dot(r[row], fa);
            }
        }
        for (l, e) in out.iter_mut().enumerate().take(W) {
            for (e, g) in e.iter_mut().zip(&fg) {
                *e = g.0[l];
            }
        }
    }

    /// The elements of grid row `row` (`j + (n - 1) k`): four at a time where the row has four.
    #[inline(always)]
    fn row(&self, row: usize, last: &[[f64; 4]], next: &mut [[f64; 4]], out: &mut [[f64; 24]]) {
        let n = self.grid.n();
        let m = n - 1;
        let (j, k) = (row % m, row / m);
        let node = n * (j + n * k);
        if m < 4 {
            for s in 0..m {
                self.elements::<1>(node + s, &last[s..], &mut next[s..], &mut out[s..]);
            }
            return;
        }
        let mut s = 0;
        loop {
            let at = s.min(m - 4);
            self.elements::<4>(node + at, &last[at..], &mut next[at..], &mut out[at..]);
            if at + 4 >= m {
                break;
            }
            s += 4;
        }
    }

    /// The rows `first..` of elements, one `m = n - 1` long chunk of `last`, `next` and `out` each.
    #[inline(always)]
    fn rows_generic(self, first: usize, last: &[[f64; 4]], next: &mut [[f64; 4]], out: &mut [[f64; 24]]) {
        let m = self.grid.n() - 1;
        for (i, (next, out)) in next.chunks_mut(m).zip(out.chunks_mut(m)).enumerate() {
            self.row(first + i, &last[i * m..], next, out);
        }
    }

    /// Every element's rotation (from `last` into `next`) and force (into `out`), element order
    /// (`i + m (j + m k)`), rows split over the physics pool where `parallel` and the grid is
    /// large enough ([`crate::mechanics::parallel`]). Allocates nothing.
    pub fn all(self, last: &[[f64; 4]], next: &mut [[f64; 4]], out: &mut [[f64; 24]], parallel: bool) {
        let m = self.grid.n() - 1;
        let pool = crate::mechanics::parallel::pool()
            .filter(|_| parallel && out.len() >= crate::mechanics::parallel::MIN_PARALLEL_ITEMS);
        match pool {
            Some(pool) => pool.install(|| {
                use rayon::prelude::*;
                // Whole rows per task, a few rows each (64 elements or more).
                let rows = 64usize.div_ceil(m);
                next.par_chunks_mut(rows * m)
                    .zip(out.par_chunks_mut(rows * m))
                    .enumerate()
                    .for_each(|(t, (next, out))| self.rows(t * rows, &last[t * rows * m..], next, out));
            }),
            None => self.rows(0, last, next, out),
        }
    }

    /// [`Corotation::rows_generic`], compiled with AVX2 where the CPU has it.
    fn rows(self, first: usize, last: &[[f64; 4]], next: &mut [[f64; 4]], out: &mut [[f64; 24]]) {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        unsafe fn rows_avx2(
            at: Corotation<'_>,
            first: usize,
            last: &[[f64; 4]],
            next: &mut [[f64; 4]],
            out: &mut [[f64; 24]],
        ) {
            at.rows_generic(first, last, next, out);
        }
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports AVX2, checked just above.
                unsafe { rows_avx2(self, first, last, next, out) };
                return;
            }
        }
        self.rows_generic(first, last, next, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::fem::FemModel;
    use crate::mechanics::material::Material;

    /// Positions of a grid stretched by `stretch` along x, moved by up to `wobble` metres (so that
    /// no two elements deform alike), then turned by `angle` about z.
    fn deformed(grid: &Grid, angle: f64, stretch: f64, wobble: f64) -> [Vec<f64>; 3] {
        let (s, c) = angle.sin_cos();
        let mut x: [Vec<f64>; 3] = std::array::from_fn(|_| Vec::new());
        for p in 0..grid.num_nodes() {
            let r = grid.position(p);
            let wobble = wobble * ((p * 7919) % 13) as f64 / 13.0;
            let (px, py) = (stretch * r[0] + wobble, r[1]);
            x[0].push(c * px - s * py);
            x[1].push(s * px + c * py);
            x[2].push(r[2] - wobble);
        }
        x
    }

    /// `f` on object A's elements at positions `x` (the dense product where `dense`).
    fn with_corotation<R>(
        grid: Grid,
        x: &[Vec<f64>; 3],
        iterations: usize,
        dense: bool,
        f: impl FnOnce(&Corotation<'_>, &FemModel) -> R,
    ) -> R {
        let fem = FemModel::new(grid, &Material::object_a());
        let parity = if dense { None } else { ParityBlocks::of(&fem.ke) };
        let rest: [Vec<f64>; 3] = std::array::from_fn(|c| (0..grid.num_nodes()).map(|p| grid.position(p)[c]).collect());
        let at = Corotation {
            x: [&x[0], &x[1], &x[2]],
            rest: [&rest[0], &rest[1], &rest[2]],
            ke: &fem.ke,
            parity: parity.as_ref(),
            grid,
            iterations,
            tolerance: 1e-12,
        };
        f(&at, &fem)
    }

    fn forces(
        grid: Grid,
        x: &[Vec<f64>; 3],
        iterations: usize,
        parallel: bool,
        dense: bool,
    ) -> (Vec<[f64; 4]>, Vec<[f64; 24]>) {
        with_corotation(grid, x, iterations, dense, |at, fem| {
            let elements = fem.elements().len();
            let (last, mut next, mut out) =
                (vec![IDENTITY; elements], vec![[0.0; 4]; elements], vec![[0.0; 24]; elements]);
            at.all(&last, &mut next, &mut out, parallel);
            (next, out)
        })
    }

    #[test]
    fn a_rigid_turn_gives_no_force_once_the_rotation_has_converged() {
        for n in [3, 6, 12] {
            let grid = Grid::new(n).unwrap();
            let x = deformed(&grid, 0.3, 1.0, 0.0);
            let (q, _) = forces(grid, &x, 0, false, false);
            let (q1, f) = forces(grid, &x, 60, false, false);
            assert!(q.iter().all(|q| *q == IDENTITY));
            let worst = f.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(worst < 1e-9, "n = {n}: force {worst} N on a rigid turn");
            // The turn found is 0.3 rad about z: q = (cos 0.15, 0, 0, sin 0.15).
            for q in &q1 {
                assert!((q[0] - 0.15f64.cos()).abs() < 1e-10 && (q[3] - 0.15f64.sin()).abs() < 1e-10, "{q:?}");
            }
        }
    }

    #[test]
    fn every_element_has_the_same_bits_in_any_lane_and_on_any_split() {
        // 13 elements a row: three runs of four and one overlapping; 6: one and one overlapping.
        for n in [7, 14] {
            let grid = Grid::new(n).unwrap();
            let x = deformed(&grid, 0.2, 1.05, 1e-3);
            let (q, f) = forces(grid, &x, 2, false, false);
            let (qp, fp) = forces(grid, &x, 2, true, false);
            assert_eq!(q, qp);
            assert_eq!(f, fp);
            // Each element alone (one lane) against its lane in a run.
            with_corotation(grid, &x, 2, false, |at, fem| {
                for (e, nodes) in fem.elements().iter().enumerate() {
                    let (mut next, mut out) = ([[0.0; 4]], [[0.0; 24]]);
                    at.elements::<1>(nodes[0], &[IDENTITY], &mut next, &mut out);
                    assert_eq!(next[0], q[e], "element {e}");
                    assert_eq!(out[0], f[e], "element {e}");
                }
            });
        }
    }

    #[test]
    fn the_parity_blocks_are_the_element_matrix() {
        for material in [Material::object_a(), Material::object_b()] {
            let ke = FemModel::new(Grid::new(5).unwrap(), &material).ke;
            let parity = ParityBlocks::of(&ke).expect("an orthotropic cube has the parity form");
            let local: [Lanes<1>; 24] = std::array::from_fn(|i| Lanes([((i * 7919) % 23) as f64 * 1e-4 - 1e-3]));
            let (dense, blocks) = (dense_product(&ke, &local), parity.apply(&local));
            let scale = dense.iter().fold(0.0f64, |m, v| m.max(v.0[0].abs()));
            for (d, b) in dense.iter().zip(&blocks) {
                assert!((d.0[0] - b.0[0]).abs() <= 1e-12 * scale, "{} vs {}", d.0[0], b.0[0]);
            }
            // Coupling the x displacement of node 0 with the y of node 1 alone breaks the
            // reflections: no parity form, the dense product instead.
            let mut skew = ke;
            skew[(0, 4)] += 1e-3 * scale;
            skew[(4, 0)] += 1e-3 * scale;
            assert!(ParityBlocks::of(&skew).is_none());
        }
    }

    #[test]
    fn the_dense_and_the_parity_products_turn_alike() {
        let grid = Grid::new(9).unwrap();
        let x = deformed(&grid, 0.4, 1.1, 2e-3);
        let (q, f) = forces(grid, &x, 2, false, false);
        let (qd, fd) = forces(grid, &x, 2, false, true);
        assert_eq!(q, qd, "the rotations do not depend on the product");
        let scale = fd.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for (a, b) in f.iter().flatten().zip(fd.iter().flatten()) {
            assert!((a - b).abs() <= 1e-12 * scale, "{a} vs {b}");
        }
    }
}
