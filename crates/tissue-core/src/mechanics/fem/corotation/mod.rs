//! The corotational hex8 element's force, `f_e = R K_e (R^T x_e - X_e)`, four elements at a time.
//!
//! `R` is each element's rotation, kept as a unit quaternion from one force evaluation to the
//! next and moved to the polar rotation of the deformation gradient at the element's centre,
//! `F = sum_a x_a (grad N_a)^T`. Each iteration measures the correction of the rotation
//! extraction of Mueller et al. (2016), `omega = sum_c r_c x f_c / (|sum_c r_c . f_c| + eps)` over
//! the columns of `R` and `F`, and stops once it is below a tolerance (`Corotation::tolerance`);
//! else it turns `R <- exp(omega) R` by Newton's `omega` on the same equation
//! (`newton_half_turn`: quadratic, where Mueller's fixed-point step shrinks the error only
//! threefold a step near a rigid turn), or by Mueller's where Newton's matrix is near singular.
//! A lane whose Newton turn was small (`SETTLED`: at most 3.2e-5 rad at the 1e-8 rad
//! tolerance) stops after it without measuring again: Newton's error after it is far below the
//! tolerance (tested from 2.6e-5 rad away, stretched up to 20 % or compressed up to 40 %: 5e-15 rad).
//! Here the exponential is its trig-free first order, the unit quaternion
//! `(1, omega / 2) / |(1, omega / 2)|` (a turn of `2 atan(|omega| / 2)` about `omega`, within
//! `|omega|^3 / 12` of `|omega|`); the iteration's fixed point, `omega = 0`, is the same polar
//! rotation.
//!
//! The elements of a grid row (along x) have the same node pattern at consecutive node indices,
//! so on the component-wise positions `x[c][node]` the node `a` of four neighbouring elements is
//! four consecutive values: every operation runs on four lanes in an AVX2 register where the CPU
//! has it (`corotation::lanes`; no fused multiply-add: one element's force has the same bits in any
//! lane and on any path). A row whose length is not a multiple of four ends with four elements
//! that overlap the ones before; the rotations are double-buffered (read from the last
//! evaluation's, written to this one's), so an element computed twice gives the same bits twice,
//! and its force is summed once. Each element is rotated about its lowest node,
//! `R^T (x_a - x_0) - (X_a - X_0)` (`X_a - X_0` is `h` times the node's corner), which differs
//! from `R^T x_a - X_a` by a translation `K_e` does not feel: no rest positions are read. The
//! loops over the element's nodes are unrolled in the source, so that its values stay in
//! registers; each group's forces are summed on the nodes as soon as they are computed.
//!
//! Measured on one core, 16^3 nodes, one evaluation of all 3,375 elements: the loop with its
//! sums on the nodes takes 134 to 157 us, against 184 to 261 us for the element loop on arrays
//! of lanes alone followed by a second pass summing a per-element buffer on the nodes.
//!
//! `parity`: `K_e` in the parity basis of the corners.

mod lanes;

use super::element::{ElementStiffness, NODE_SIDES, NODE_SIGNS};
use crate::mechanics::grid::Grid;
use lanes::Lane;

/// A vector of three lanes.
type V3<L> = [L; 3];

/// `$body` once for each listed value of `$i`: a loop unrolled in the source, so that every
/// array index in it is a constant and the element kernel's arrays stay in registers (the
/// compiler does not unroll loops this long by itself).
macro_rules! unrolled {
    ($i:ident in [$($v:literal),+] $body:block) => {
        $({
            let $i: usize = $v;
            $body
        })+
    };
}

mod parity;
#[cfg(test)]
mod tests;

pub use parity::ParityBlocks;

#[inline(always)]
fn cross<L: Lane>(a: V3<L>, b: V3<L>) -> V3<L> {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[inline(always)]
fn dot<L: Lane>(a: V3<L>, b: V3<L>) -> L {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The rotation matrix `m[row][col]` of the unit quaternion `[w, x, y, z]`.
#[inline(always)]
fn matrix<L: Lane>(q: [L; 4]) -> [V3<L>; 3] {
    let [w, x, y, z] = q;
    let (one, two) = (L::splat(1.0), L::splat(2.0));
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let (xy, xz, yz, wx, wy, wz) = (x * y, x * z, y * z, w * x, w * y, w * z);
    [
        [one - two * (yy + zz), two * (xy - wz), two * (xz + wy)],
        [two * (xy + wz), one - two * (xx + zz), two * (yz - wx)],
        [two * (xz - wy), two * (yz + wx), one - two * (xx + yy)],
    ]
}

/// `K_e local`, eight rows at a time (`K_e` is symmetric: column j is row j): 576 multiply-adds.
#[inline(always)]
fn dense_product<L: Lane>(ke: &ElementStiffness, local: &[V3<L>; 8]) -> [V3<L>; 8] {
    let ke = ke.as_slice();
    let mut fl = [[L::splat(0.0); 3]; 8];
    for block in 0..3 {
        let mut acc = [L::splat(0.0); 8];
        for (j, lj) in local.as_flattened().iter().enumerate() {
            let col = &ke[24 * j + 8 * block..24 * j + 8 * block + 8];
            for (acc, &k) in acc.iter_mut().zip(col) {
                *acc = *acc + L::splat(k) * *lj;
            }
        }
        fl.as_flattened_mut()[8 * block..8 * block + 8].copy_from_slice(&acc);
    }
    fl
}

/// The corner of node `a` (spec order) as bits `bx + 2 by + 4 bz`, 1 on the high side.
#[inline(always)]
fn corner(a: usize) -> usize {
    let b = NODE_SIDES[a];
    b[0] + 2 * b[1] + 4 * b[2]
}

/// Node `a`'s index from its element's lowest node on `grid`.
#[inline(always)]
fn node_offset(a: usize, grid: Grid) -> usize {
    let s = NODE_SIDES[a];
    grid.node(s[0], s[1], s[2])
}

/// The corotated forces of one group of a row's elements (four consecutive along x, or one
/// where the row is shorter than four): `[3 a + c][lane]`, the force on node `a` (spec order),
/// component `c`, of the group's element `lane`. Lanes a group does not fill are left as they were.
type GroupForces = [[f64; 4]; 24];

/// The groups of a row of `m` elements: runs of four, the last overlapping the one before where
/// `m` is not a multiple of four; one element each where `m < 4`.
fn groups_per_row(m: usize) -> usize {
    if m < 4 { m } else { m.div_ceil(4) }
}

/// The first element (along the row) of group `g` of a row of `m` elements.
fn group_start(m: usize, g: usize) -> usize {
    if m < 4 { g } else { (4 * g).min(m - 4) }
}

/// `out[c][node + offset of a] -= ` the forces of one group of elements (`node` is the group's
/// first element's lowest node, an index into `out`), its lanes `skip..lanes` (an overlapping
/// last group skips the elements the one before did). Each of a full group's 24 values is one
/// four-wide read-modify-write on four consecutive nodes.
#[inline(always)]
fn scatter(forces: &GroupForces, node: usize, grid: Grid, lanes: usize, skip: usize, out: &mut [&mut [f64]; 3]) {
    unrolled!(a in [0, 1, 2, 3, 4, 5, 6, 7] {
        let base = node + node_offset(a, grid);
        unrolled!(c in [0, 1, 2] {
            let (dst, src) = (&mut out[c][base..base + lanes], &forces[3 * a + c]);
            if skip == 0
                && let Ok(dst) = <&mut [f64; 4]>::try_from(&mut *dst)
            {
                for l in 0..4 {
                    dst[l] -= src[l];
                }
            } else {
                for (d, s) in dst.iter_mut().zip(src).skip(skip) {
                    *d -= s;
                }
            }
        });
    });
}

/// Half of Newton's turn `omega` towards the polar rotation of `F` from the rotation `R`:
/// `R <- exp(omega) R` makes `B = F R^T` symmetric to first order where
/// `(tr(B) I - sym(B)) omega = t`, `t = sum_c r_c x f_c` (`axis`) and `tr(B) = sum_c r_c . f_c`
/// (`trace`). The fixed-point step `omega = t / tr(B)` of Mueller et al. (2016) takes the same
/// matrix as `tr(B) I`: near a rigid turn (`B ~ I`) it moves `2 / 3` of the way and the error
/// falls by only 3 a step, where Newton's falls quadratically. Where `tr(B) I - sym(B)` is near
/// singular (`det < 0.05 tr(B)^3`, an element crushed or inverted) the lane keeps that
/// fixed-point step, `mueller`, which is robust there. Returns the half-turn, and on each lane 1
/// where it is Newton's, 0 where Mueller's.
#[inline(always)]
fn newton_half_turn<L: Lane>(r: &[V3<L>; 3], f: &[V3<L>; 3], axis: V3<L>, trace: L, mueller: V3<L>) -> (V3<L>, L) {
    // sym(B)[i][j] = sum_c (F[i][c] R[j][c] + F[j][c] R[i][c]) / 2.
    let mut b = [[L::splat(0.0); 3]; 3];
    unrolled!(i in [0, 1, 2] {
        unrolled!(j in [0, 1, 2] {
            if j >= i {
                let mut s = L::splat(0.0);
                unrolled!(c in [0, 1, 2] {
                    s = s + f[i][c] * r[j][c] + f[j][c] * r[i][c];
                });
                b[i][j] = L::splat(0.5) * s;
            }
        });
    });
    let (m00, m11, m22) = (trace - b[0][0], trace - b[1][1], trace - b[2][2]);
    let zero = L::splat(0.0);
    let (m01, m02, m12) = (zero - b[0][1], zero - b[0][2], zero - b[1][2]);
    // The adjugate (symmetric) and the determinant.
    let (a00, a11, a22) = (m11 * m22 - m12 * m12, m00 * m22 - m02 * m02, m00 * m11 - m01 * m01);
    let (a01, a02, a12) = (m02 * m12 - m01 * m22, m01 * m12 - m02 * m11, m01 * m02 - m00 * m12);
    let det = m00 * a00 + m01 * a01 + m02 * a02;
    let half = L::splat(0.5) / det;
    let t = axis;
    let hn = [
        half * (a00 * t[0] + a01 * t[1] + a02 * t[2]),
        half * (a01 * t[0] + a11 * t[1] + a12 * t[2]),
        half * (a02 * t[0] + a12 * t[1] + a22 * t[2]),
    ];
    // Newton's where 0.05 tr(B)^3 <= det and eps <= tr(B), else Mueller's.
    let floor = L::splat(0.05) * trace * trace * trace;
    let eps = L::splat(f64::EPSILON);
    let pick = |i: usize| eps.select_at_most(trace, floor.select_at_most(det, hn[i], mueller[i]), mueller[i]);
    let newton = eps.select_at_most(trace, floor.select_at_most(det, L::splat(1.0), zero), zero);
    ([pick(0), pick(1), pick(2)], newton)
}

/// A lane whose Newton half-turn `h` had `|h|^2` at most this times the tolerance (radians) stops
/// after it without measuring its correction again: `|omega| = 2 |h| <= sqrt(0.1 tolerance)`
/// (3.2e-5 rad at the step's 1e-8), and Newton's error after a step falls as its square, to about
/// a tenth of the tolerance near a rigid turn (`tr(B) I - sym(B) ~ 2 I`). The next evaluation
/// starts from that rotation and measures it.
const SETTLED: f64 = 0.025;

/// What every element's corotated force reads.
#[derive(Debug, Clone, Copy)]
pub struct Corotation<'a> {
    /// Positions, component-wise, metres.
    pub x: [&'a [f64]; 3],
    /// The rest shape's node spacing, metres: the grid's `h`, or 0 for a rest shape of zero size
    /// (the product `K_w p` of the warped stiffness). Each element is rotated about its lowest
    /// node, `R^T (x_a - x_0) - (X_a - X_0)`, which differs from `R^T x_a - X_a` by a translation
    /// that `K_e` does not feel.
    pub rest_spacing: f64,
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

/// The most iterations of the rotation extraction per force evaluation, from the last
/// evaluation's rotation ([`super::dynamics::FemDynamics::rotation_iterations`]'s default). Each element's update
/// runs until its correction is below [`ROTATION_TOLERANCE`] (four elements at a time), so a
/// still element costs one check and a fast-turning one as many iterations as it takes.
///
/// A rotation left lagging behind the polar rotation feeds energy in: at 16^3 (object A, damping
/// ratio 0.2, bottom clamp, 4 symplectic substeps of the 1 ms tick) with the top corner dragged
/// 4 cm up and outwards over 0.1 s and held, a fixed 2 iterations a step rang at 9.9 m/s for
/// the whole second held, a fixed 6 grew from 2 mm/s to 0.63 m/s, and stopping at 1e-6 rad
/// left a 1 mm/s ringing; iterated to 1e-8 rad the cube comes to rest. During that drag the
/// updates took 6.1 iterations on average and at most 18; held still, 0.09. Those counts are
/// of Mueller's fixed-point step; with Newton's (`newton_half_turn`), in the bench
/// sweep's press at 16^3, a group of four elements took 0.99 updates a step over the press and
/// hold against Mueller's 6.4, and 1.00 against 3.9 in the next 0.2 s.
pub const ROTATION_ITERATIONS: usize = 20;
/// Where the rotation extraction stops: every correction of four elements at most this, radians
/// ([`super::dynamics::FemDynamics::rotation_tolerance`]'s default; see [`ROTATION_ITERATIONS`]).
pub const ROTATION_TOLERANCE: f64 = 1e-8;

/// The identity rotation as a quaternion `[w, x, y, z]`.
pub const IDENTITY: [f64; 4] = [1.0, 0.0, 0.0, 0.0];

impl Corotation<'_> {
    /// Elements `first..first + L::W` (consecutive along x in one grid row, the first's lowest
    /// node `node`): their rotations moved on from `last` into `next`, their forces on their
    /// eight nodes into `out` (`out[3 a + c][lane + l]`, the other lanes untouched).
    #[inline(always)]
    fn elements<L: Lane>(
        &self,
        node: usize,
        last: &[[f64; 4]],
        next: &mut [[f64; 4]],
        out: &mut GroupForces,
        lane: usize,
    ) {
        let inv4h = 1.0 / (4.0 * self.grid.h());
        // x_a - x_0.
        let x0: V3<L> = [L::load(&self.x[0][node..]), L::load(&self.x[1][node..]), L::load(&self.x[2][node..])];
        let mut d = [[L::splat(0.0); 3]; 8];
        unrolled!(a in [1, 2, 3, 4, 5, 6, 7] {
            let at = node + node_offset(a, self.grid);
            unrolled!(c in [0, 1, 2] {
                d[a][c] = L::load(&self.x[c][at..]) - x0[c];
            });
        });
        // F[r][c] = sum_a x_a[r] g_a[c], g_a = NODE_SIGNS[a] / 4h (sum_a g_a = 0).
        let mut f = [[L::splat(0.0); 3]; 3];
        unrolled!(a in [1, 2, 3, 4, 5, 6, 7] {
            unrolled!(r in [0, 1, 2] {
                unrolled!(c in [0, 1, 2] {
                    f[r][c] = f[r][c] + L::splat(NODE_SIGNS[a][c] * inv4h) * d[a][r];
                });
            });
        });
        let mut q = [L::splat(0.0); 4];
        unrolled!(i in [0, 1, 2, 3] {
            q[i] = L::from_fn(|l| last[l][i]);
        });
        let q = self.turned(&f, q);
        for (l, slot) in next.iter_mut().enumerate().take(L::W) {
            *slot = [q[0].lane(l), q[1].lane(l), q[2].lane(l), q[3].lane(l)];
        }
        let r = matrix(q);
        // R^T (x_a - x_0) - (X_a - X_0); node 0's is zero.
        let mut local = [[L::splat(0.0); 3]; 8];
        unrolled!(a in [1, 2, 3, 4, 5, 6, 7] {
            unrolled!(c in [0, 1, 2] {
                let rotated = r[0][c] * d[a][0] + r[1][c] * d[a][1] + r[2][c] * d[a][2];
                local[a][c] = rotated - L::splat(self.rest_spacing * NODE_SIDES[a][c] as f64);
            });
        });
        let fl = match self.parity {
            Some(parity) => parity.apply(&local),
            None => dense_product(self.ke, &local),
        };
        // R f_local, per node.
        unrolled!(a in [0, 1, 2, 3, 4, 5, 6, 7] {
            unrolled!(row in [0, 1, 2] {
                dot(r[row], fl[a]).store(&mut out[3 * a + row][lane..]);
            });
        });
    }

    /// The rotations `q` moved on towards the polar rotations of the deformation gradients `f`:
    /// iterated until every lane's correction is within the tolerance or settled by a small
    /// Newton turn ([`SETTLED`]), at most `iterations` times.
    #[inline(always)]
    fn turned<L: Lane>(&self, f: &[V3<L>; 3], mut q: [L; 4]) -> [L; 4] {
        let column = |m: &[V3<L>; 3], c: usize| [m[0][c], m[1][c], m[2][c]];
        let stop = 0.25 * self.tolerance * self.tolerance; // on |omega / 2|^2
        let (one, zero) = (L::splat(1.0), L::splat(0.0));
        // 1 on a lane still iterating, 0 on one settled by a small Newton step ([`SETTLED`]).
        let mut active = one;
        for _ in 0..self.iterations {
            if active.all_at_most(0.0) {
                break;
            }
            let r = matrix(q);
            let mut axis = [L::splat(0.0); 3];
            let mut denom = L::splat(0.0);
            unrolled!(c in [0, 1, 2] {
                let (rc, fc) = (column(&r, c), column(f, c));
                let t = cross(rc, fc);
                axis = [axis[0] + t[0], axis[1] + t[1], axis[2] + t[2]];
                denom = denom + dot(rc, fc);
            });
            let scale = L::splat(0.5) / (denom.abs() + L::splat(f64::EPSILON));
            let h = [axis[0] * scale, axis[1] * scale, axis[2] * scale]; // omega / 2
            // A settled lane counts as within the tolerance (a choice, so an overflowing
            // measure on it cannot turn it).
            let size = active.select_at_most(zero, zero, dot(h, h));
            if size.all_at_most(stop) {
                break;
            }
            let (h, newton) = newton_half_turn(&r, f, axis, denom, h);
            // (1, h) * q, normalised; a lane already within the tolerance keeps its rotation
            // (and measures the same correction again), as it would alone.
            let (w, v) = (q[0], [q[1], q[2], q[3]]);
            let hv = cross(h, v);
            let nw = w - dot(h, v);
            let nv: V3<L> = [v[0] + w * h[0] + hv[0], v[1] + w * h[1] + hv[1], v[2] + w * h[2] + hv[2]];
            let inv = L::splat(1.0) / (nw * nw + dot(nv, nv)).sqrt();
            let turned = [nw * inv, nv[0] * inv, nv[1] * inv, nv[2] * inv];
            let stop = L::splat(stop);
            q = [
                size.select_at_most(stop, q[0], turned[0]),
                size.select_at_most(stop, q[1], turned[1]),
                size.select_at_most(stop, q[2], turned[2]),
                size.select_at_most(stop, q[3], turned[3]),
            ];
            let settled = dot(h, h).select_at_most(L::splat(SETTLED * self.tolerance), newton, zero);
            active = active * (one - settled);
        }
        q
    }

    /// The elements of layer `k` (`i + m j` in `last` and `next`, `m = n - 1`), group by group
    /// along each row ([`group_start`]; `L`'s lanes at a time): their rotations from `last` into
    /// `next`, and `out[c][node - k n^2] -= ` their forces (`out` holds node layers `k` and `k + 1`).
    #[inline(always)]
    fn layer_of<L: Lane>(self, k: usize, last: &[[f64; 4]], next: &mut [[f64; 4]], out: &mut [&mut [f64]; 3]) {
        let n = self.grid.n();
        let m = n - 1;
        let lanes = if m < 4 { 1 } else { 4 };
        let mut forces: GroupForces = [[0.0; 4]; 24];
        for j in 0..m {
            let row = n * j;
            for g in 0..groups_per_row(m) {
                let at = group_start(m, g);
                let e = m * j + at;
                for l in (0..lanes).step_by(L::W) {
                    self.elements::<L>(row + n * n * k + at + l, &last[e + l..], &mut next[e + l..], &mut forces, l);
                }
                scatter(&forces, row + at, self.grid, lanes, if m < 4 { 0 } else { 4 * g - at }, out);
            }
        }
    }

    /// [`Corotation::layer_of`] four elements at a time in AVX2 registers where the CPU has AVX2
    /// and the rows are four or more long, else one at a time: the same bits either way.
    fn layer(self, k: usize, last: &[[f64; 4]], next: &mut [[f64; 4]], mut out: [&mut [f64]; 3]) {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        fn layer_avx2(
            at: Corotation<'_>,
            k: usize,
            last: &[[f64; 4]],
            next: &mut [[f64; 4]],
            out: &mut [&mut [f64]; 3],
        ) {
            at.layer_of::<lanes::F64x4>(k, last, next, out);
        }
        #[cfg(target_arch = "x86_64")]
        if self.grid.n() > 4 && std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            unsafe { layer_avx2(self, k, last, next, &mut out) };
            return;
        }
        self.layer_of::<f64>(k, last, next, &mut out);
    }

    /// `out[c][node] -= ` the corotated forces of the inclusions' changes of stiffness, each
    /// element's turned by its rotation in `rotations` (as [`Corotation::all`] left them).
    /// Allocates nothing.
    pub fn patched(self, patch: &[super::inclusions::PatchedElement], rotations: &[[f64; 4]], out: &mut [Vec<f64>; 3]) {
        for e in patch {
            let r = matrix::<f64>(rotations[e.index]);
            let x0: V3<f64> = std::array::from_fn(|c| self.x[c][e.nodes[0]]);
            let mut local = [[0.0; 3]; 8];
            for a in 1..8 {
                let d: V3<f64> = std::array::from_fn(|c| self.x[c][e.nodes[a]] - x0[c]);
                for c in 0..3 {
                    let rotated = r[0][c] * d[0] + r[1][c] * d[1] + r[2][c] * d[2];
                    local[a][c] = rotated - self.rest_spacing * NODE_SIDES[a][c] as f64;
                }
            }
            let fl = dense_product::<f64>(&e.delta, &local);
            for (a, &p) in e.nodes.iter().enumerate() {
                for (row, out) in out.iter_mut().enumerate() {
                    out[p] -= dot(r[row], fl[a]);
                }
            }
        }
    }

    /// Every element's rotation (from `last` into `next`, element order `i + m (j + m k)`) and
    /// `out[c][node] -= ` its forces. Two passes, the even layers of elements and then the odd
    /// ones: within a pass no two layers share a node, so the layers of a pass are split over
    /// the physics pool where `parallel` and the grid is large enough
    /// ([`crate::mechanics::parallel`]), with the same sums in the same order on any split.
    /// Allocates nothing.
    pub fn all(self, last: &[[f64; 4]], next: &mut [[f64; 4]], out: &mut [Vec<f64>; 3], parallel: bool) {
        let n = self.grid.n();
        let m = n - 1;
        debug_assert!(last.len() == m * m * m && next.len() == m * m * m, "one rotation an element");
        debug_assert!(out.iter().all(|o| o.len() == n * n * n), "one force a node");
        let (layer_nodes, layer_elements) = (n * n, m * m);
        let pool = crate::mechanics::parallel::pool()
            .filter(|_| parallel && next.len() >= crate::mechanics::parallel::MIN_PARALLEL_ITEMS);
        for pass in [0, 1] {
            // Task t: element layer k = pass + 2 t, which writes node layers k and k + 1.
            let layers = m.saturating_sub(pass).div_ceil(2);
            let [o0, o1, o2] = &mut *out;
            let (next, o0, o1, o2) = (
                &mut next[pass * layer_elements..],
                &mut o0[pass * layer_nodes..],
                &mut o1[pass * layer_nodes..],
                &mut o2[pass * layer_nodes..],
            );
            let task =
                |(t, (((next, a), b), c)): (usize, (((&mut [[f64; 4]], &mut [f64]), &mut [f64]), &mut [f64]))| {
                    let k = pass + 2 * t;
                    let at = k * layer_elements;
                    self.layer(k, &last[at..at + layer_elements], &mut next[..layer_elements], [a, b, c]);
                };
            match pool {
                Some(pool) => pool.install(|| {
                    use rayon::prelude::*;
                    next.par_chunks_mut(2 * layer_elements)
                        .zip(o0.par_chunks_mut(2 * layer_nodes))
                        .zip(o1.par_chunks_mut(2 * layer_nodes))
                        .zip(o2.par_chunks_mut(2 * layer_nodes))
                        .take(layers)
                        .enumerate()
                        .for_each(task);
                }),
                None => next
                    .chunks_mut(2 * layer_elements)
                    .zip(o0.chunks_mut(2 * layer_nodes))
                    .zip(o1.chunks_mut(2 * layer_nodes))
                    .zip(o2.chunks_mut(2 * layer_nodes))
                    .take(layers)
                    .enumerate()
                    .for_each(task),
            }
        }
    }
}
