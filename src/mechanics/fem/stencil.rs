//! The linear FEM's force `K u` on the regular grid as a stencil: every node's row of `K` is 27
//! blocks of 3x3 (itself and its 26 neighbours), and since every element has the same `K_e`,
//! a row depends only on which faces of the cube the node lies on (below, inside or above along
//! each axis: 27 classes). So `K` is never stored: 27 classes x 27 blocks x 9 values, and a
//! product costs at most 243 multiply-adds a node, gathered row by row (no scatter), against the
//! element loop's 576 a node scattered over eight elements. With an orthotropic material on the
//! grid's axes most blocks couple few components (`Pattern`): 153 multiply-adds a node inside
//! the cube (measured in a scratch harness, one core, 24^3, the linear FEM's 1 ms tick of six
//! substeps with the probe pressed: 1.98 to 2.17 ms with every entry, 1.81 to 1.85 without the
//! zero ones, runs alternated).
//!
//! Two layouts: interleaved (`3 node + component`, [`Stencil::apply`]) and component-wise
//! (`u[c][node]`, [`Stencil::apply_components`], the running FEM's state). In the second, the
//! nodes of a grid row that are inside along x share one class and read their neighbours at
//! the same index steps, so with AVX2 eight (or four) of them are summed at a time; every node's sum is
//! the same sequence of operations in both layouts and on both paths, so the bits are the same.

use super::element::{ElementStiffness, NODE_SIDES};
use crate::mechanics::grid::Grid;

/// A neighbour in a node's row of `K`: the step in node index to it, its 3x3 block (row-major)
/// and which of the block's entries are not zero.
#[derive(Debug, Clone, Copy)]
struct Tap {
    delta: isize,
    block: [f64; 9],
    pattern: Pattern,
}

/// Which off-diagonal entries of a 3x3 block are not zero: none, one symmetric pair, or any.
/// With an orthotropic material on the grid's axes, a neighbour along an axis couples no two
/// components, one in a coordinate plane only that plane's two, and only the 8 corner neighbours
/// all: 153 of a row's 243 products are left (inside the cube).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pattern {
    Diagonal,
    Xy,
    Xz,
    Yz,
    Full,
}

impl Pattern {
    fn of(b: &[f64; 9]) -> Self {
        let coupled = |i: usize, j: usize| b[i] != 0.0 || b[j] != 0.0;
        match (coupled(1, 3), coupled(2, 6), coupled(5, 7)) {
            (false, false, false) => Self::Diagonal,
            (true, false, false) => Self::Xy,
            (false, true, false) => Self::Xz,
            (false, false, true) => Self::Yz,
            _ => Self::Full,
        }
    }
}

/// A block's product `b (x, y, z)` by its pattern: each row `(b_r0 x + b_r1 y) + b_r2 z` with its
/// zero terms left out, through the caller's macros `$m!(entry, value)` (a product) and
/// `$a!(p, q)` (a sum), so that the scalar and the AVX2 rows are the same operations.
macro_rules! pattern_rows {
    ($pattern:expr, $x:expr, $y:expr, $z:expr, $m:ident, $a:ident) => {
        match $pattern {
            Pattern::Diagonal => [$m!(0, $x), $m!(4, $y), $m!(8, $z)],
            Pattern::Xy => [$a!($m!(0, $x), $m!(1, $y)), $a!($m!(3, $x), $m!(4, $y)), $m!(8, $z)],
            Pattern::Xz => [$a!($m!(0, $x), $m!(2, $z)), $m!(4, $y), $a!($m!(6, $x), $m!(8, $z))],
            Pattern::Yz => [$m!(0, $x), $a!($m!(4, $y), $m!(5, $z)), $a!($m!(7, $y), $m!(8, $z))],
            Pattern::Full => [
                $a!($a!($m!(0, $x), $m!(1, $y)), $m!(2, $z)),
                $a!($a!($m!(3, $x), $m!(4, $y)), $m!(5, $z)),
                $a!($a!($m!(6, $x), $m!(7, $y)), $m!(8, $z)),
            ],
        }
    };
}

/// Entries of a class's blocks at most this fraction of its largest are the quadrature's rounding
/// of couplings that are zero (at most 5.4e-17 of it with objects A and B, where 8 to 48 of a
/// class's 243 entries are such sums): set to zero.
const ROUNDING: f64 = 1e-13;

/// `K` of a grid's hex8 FEM as per-class 3x3 blocks.
#[derive(Debug, Clone)]
pub struct Stencil {
    n: usize,
    /// `blocks[class][offset]`: the 3x3 block (row-major) coupling a node of `class` with its
    /// neighbour at `offset = (dx + 1) + 3 (dy + 1) + 9 (dz + 1)`.
    blocks: Vec<[[f64; 9]; 27]>,
    /// `taps[class]`: the neighbours a node of `class` has, in increasing offset.
    taps: Vec<Vec<Tap>>,
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

/// A node's row of `K` times `u`: the sum over its taps, each `b u_q` summed as
/// `(b0 x + b1 y) + b2 z` per component without its zero terms ([`pattern_rows`]; the order
/// [`row_avx2`] keeps).
#[inline(always)]
fn row_sum(taps: &[Tap], p: usize, load: impl Fn(usize) -> [f64; 3]) -> [f64; 3] {
    let mut acc = [0.0; 3];
    for t in taps {
        let [x, y, z] = load(p.wrapping_add_signed(t.delta));
        let b = &t.block;
        macro_rules! m {
            ($i:expr, $v:expr) => {
                b[$i] * $v
            };
        }
        macro_rules! a {
            ($p:expr, $q:expr) => {
                $p + $q
            };
        }
        let rows = pattern_rows!(t.pattern, x, y, z, m, a);
        for (acc, r) in acc.iter_mut().zip(rows) {
            *acc += r;
        }
    }
    acc
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
                let local = |l: usize| NODE_SIDES[l];
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
        for block in &mut blocks {
            let largest = block.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            for v in block.iter_mut().flatten() {
                if v.abs() <= ROUNDING * largest {
                    *v = 0.0;
                }
            }
        }
        let taps = (0..27)
            .map(|class| {
                let s = [class % 3, (class / 3) % 3, class / 9];
                (0..27)
                    .filter(|&o: &usize| {
                        let d = [o % 3, (o / 3) % 3, o / 9];
                        // No neighbour below the low face or above the high one.
                        (0..3).all(|a| (s[a], d[a]) != (0, 0) && (s[a], d[a]) != (2, 2))
                    })
                    .map(|o| {
                        let d = [o % 3, (o / 3) % 3, o / 9].map(|d| d as isize - 1);
                        let n = n as isize;
                        let block = blocks[class][o];
                        Tap { delta: d[0] + n * d[1] + n * n * d[2], block, pattern: Pattern::of(&block) }
                    })
                    .collect()
            })
            .collect();
        Self { n, blocks, taps }
    }

    /// `blocks()[class][offset]`: the 3x3 block (row-major) coupling a node of `class` (`sx + 3 sy
    /// + 9 sz`, each side 0 on the low face, 1 inside, 2 on the high face) with its neighbour at
    /// `offset = (dx + 1) + 3 (dy + 1) + 9 (dz + 1)`.
    pub fn blocks(&self) -> &[[[f64; 9]; 27]] {
        &self.blocks
    }

    /// Whether a product on this grid splits its slabs over the physics pool.
    fn pool(&self, parallel: bool) -> Option<&'static rayon::ThreadPool> {
        let n = self.n;
        crate::mechanics::parallel::pool()
            .filter(|_| parallel && n * n * n >= crate::mechanics::parallel::MIN_PARALLEL_ITEMS.max(4096))
    }

    /// `out = K u`, interleaved (`3 node + component`), slab by slab of constant z, the slabs
    /// split over the physics pool ([`crate::mechanics::parallel`]) on a large enough grid (each
    /// row the same sum however split). Allocates nothing.
    pub fn apply(&self, u: &[f64], out: &mut [f64]) {
        self.apply_on(u, out, true);
    }

    /// [`Stencil::apply`], on the calling thread alone unless `parallel` (the bench's baseline).
    pub fn apply_on(&self, u: &[f64], out: &mut [f64], parallel: bool) {
        let slab = 3 * self.n * self.n;
        match self.pool(parallel) {
            Some(pool) => pool.install(|| {
                use rayon::prelude::*;
                out.par_chunks_mut(slab).enumerate().for_each(|(k, o)| self.interleaved_slab(u, k, o));
            }),
            None => out.chunks_mut(slab).enumerate().for_each(|(k, o)| self.interleaved_slab(u, k, o)),
        }
    }

    /// The rows of the slab `z = k` into `out` (that slab's part of `K u`), interleaved.
    fn interleaved_slab(&self, u: &[f64], k: usize, out: &mut [f64]) {
        let n = self.n;
        let load = |q: usize| [u[3 * q], u[3 * q + 1], u[3 * q + 2]];
        for j in 0..n {
            for i in 0..n {
                let taps = &self.taps[side(i, n) + 3 * side(j, n) + 9 * side(k, n)];
                let acc = row_sum(taps, i + n * (j + n * k), load);
                let at = 3 * (i + n * j);
                out[at..at + 3].copy_from_slice(&acc);
            }
        }
    }

    /// `out[c] = (K u)[c]` with both component-wise (`u[c][node]`), slab by slab of constant z
    /// over the physics pool on a large enough grid: the same bits as [`Stencil::apply`].
    /// Allocates nothing.
    pub fn apply_components(&self, u: &[Vec<f64>; 3], out: &mut [Vec<f64>; 3]) {
        self.apply_components_on(u, out, true);
    }

    /// [`Stencil::apply_components`], on the calling thread alone unless `parallel`.
    pub fn apply_components_on(&self, u: &[Vec<f64>; 3], out: &mut [Vec<f64>; 3], parallel: bool) {
        let plane = self.n * self.n;
        let u = [&u[0][..], &u[1][..], &u[2][..]];
        let [o0, o1, o2] = out;
        match self.pool(parallel) {
            Some(pool) => pool.install(|| {
                use rayon::prelude::*;
                o0.par_chunks_mut(plane)
                    .zip(o1.par_chunks_mut(plane))
                    .zip(o2.par_chunks_mut(plane))
                    .enumerate()
                    .for_each(|(k, ((a, b), c))| self.components_slab(u, k, [a, b, c]));
            }),
            None => o0
                .chunks_mut(plane)
                .zip(o1.chunks_mut(plane))
                .zip(o2.chunks_mut(plane))
                .enumerate()
                .for_each(|(k, ((a, b), c))| self.components_slab(u, k, [a, b, c])),
        }
    }

    /// The rows of the slab `z = k` into `out` (that slab's part of `K u`), component-wise: the
    /// nodes on the x faces one by one, those between them as one run of a class.
    fn components_slab(&self, u: [&[f64]; 3], k: usize, out: [&mut [f64]; 3]) {
        let n = self.n;
        let load = |q: usize| [u[0][q], u[1][q], u[2][q]];
        let [o0, o1, o2] = out;
        for j in 0..n {
            let row_class = 3 * side(j, n) + 9 * side(k, n);
            let first = n * (j + n * k);
            for i in [0, n - 1] {
                let acc = row_sum(&self.taps[side(i, n) + row_class], first + i, load);
                (o0[n * j + i], o1[n * j + i], o2[n * j + i]) = (acc[0], acc[1], acc[2]);
            }
            if n > 2 {
                let at = n * j + 1..n * j + n - 1;
                let run = [&mut o0[at.clone()], &mut o1[at.clone()], &mut o2[at]];
                inside_run(&self.taps[1 + row_class], u, first + 1, run);
            }
        }
    }
}

/// The rows of the nodes `from..from + out[0].len()` of one class (a grid row's nodes inside
/// along x) into `out`, component-wise.
fn inside_run(taps: &[Tap], u: [&[f64]; 3], from: usize, out: [&mut [f64]; 3]) {
    #[cfg(target_arch = "x86_64")]
    {
        if out[0].len() >= 4 && std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2, checked just above.
            unsafe { row_avx2(taps, u, from, out) };
            return;
        }
    }
    let load = |q: usize| [u[0][q], u[1][q], u[2][q]];
    let [o0, o1, o2] = out;
    for s in 0..o0.len() {
        let acc = row_sum(taps, from + s, load);
        (o0[s], o1[s], o2[s]) = (acc[0], acc[1], acc[2]);
    }
}

/// [`inside_run`] eight nodes at a time (two registers, each of a tap's entries broadcast once
/// for both), then four, the last group overlapping the ones before where the run is not a
/// multiple of four (the same sums written twice); at least four nodes. No fused multiply-add,
/// so every node's sum has the bits of [`row_sum`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn row_avx2(taps: &[Tap], u: [&[f64]; 3], from: usize, out: [&mut [f64]; 3]) {
    let len = out[0].len();
    debug_assert!(len >= 4 && out.iter().all(|o| o.len() == len));
    let [o0, o1, o2] = out;
    let mut s = 0;
    while s + 8 <= len {
        // SAFETY: the caller's CPU supports AVX2 (this function's own feature).
        unsafe { group_avx2::<2>(taps, u, from, s, [&mut *o0, &mut *o1, &mut *o2]) };
        s += 8;
    }
    while s < len {
        let start = s.min(len - 4);
        // SAFETY: as above.
        unsafe { group_avx2::<1>(taps, u, from, start, [&mut *o0, &mut *o1, &mut *o2]) };
        s = start + 4;
    }
}

/// The rows of the `4 V` nodes `from + start..` into `out[..][start..]` ([`row_avx2`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn group_avx2<const V: usize>(taps: &[Tap], u: [&[f64]; 3], from: usize, start: usize, out: [&mut [f64]; 3]) {
    use std::arch::x86_64::{
        __m256d, _mm256_add_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_set1_pd, _mm256_setzero_pd, _mm256_storeu_pd,
    };
    let p = from + start;
    let mut acc: [[__m256d; 3]; V] = [[_mm256_setzero_pd(); 3]; V];
    for t in taps {
        let q = p.wrapping_add_signed(t.delta);
        // The 4 V neighbours of one tap are contiguous: bounds-checked once as slices.
        let (x, y, z) = (&u[0][q..q + 4 * V], &u[1][q..q + 4 * V], &u[2][q..q + 4 * V]);
        let b = &t.block;
        macro_rules! m {
            ($i:expr, $v:expr) => {
                _mm256_mul_pd(_mm256_set1_pd(b[$i]), $v)
            };
        }
        macro_rules! a {
            ($p:expr, $q:expr) => {
                _mm256_add_pd($p, $q)
            };
        }
        for (w, acc) in acc.iter_mut().enumerate() {
            // SAFETY: each slice holds exactly 4 V values, just checked, and `4 w + 4 <= 4 V`.
            let (x, y, z) = unsafe {
                (
                    _mm256_loadu_pd(x.as_ptr().add(4 * w)),
                    _mm256_loadu_pd(y.as_ptr().add(4 * w)),
                    _mm256_loadu_pd(z.as_ptr().add(4 * w)),
                )
            };
            let rows = pattern_rows!(t.pattern, x, y, z, m, a);
            for (a, r) in acc.iter_mut().zip(rows) {
                *a = _mm256_add_pd(*a, r);
            }
        }
    }
    for (c, o) in out.into_iter().enumerate() {
        let d = &mut o[start..start + 4 * V];
        for (w, acc) in acc.iter().enumerate() {
            // SAFETY: `d` holds exactly 4 V values, just checked, and `4 w + 4 <= 4 V`.
            unsafe { _mm256_storeu_pd(d.as_mut_ptr().add(4 * w), acc[c]) };
        }
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

    #[test]
    fn component_wise_is_interleaved_bit_for_bit() {
        let material = Material::object_b();
        // Runs inside along x of 0, 1, 3, 4, 6, 8, 9, 11 and 14 nodes (the AVX2 path from 4, in
        // groups of eight from 8, the last four overlapping from 6), and 16^3 split over the pool.
        for n in [2, 3, 5, 6, 8, 10, 11, 13, 16] {
            let grid = Grid::new(n).unwrap();
            let fem = super::super::FemModel::new(grid, &material);
            let stencil = Stencil::new(&grid, &fem.ke);
            let nn = grid.num_nodes();
            let u: Vec<f64> = (0..3 * nn).map(|d| ((d * 7919) % 101) as f64 * 1e-5 - 5e-4).collect();
            let split: [Vec<f64>; 3] = std::array::from_fn(|c| (0..nn).map(|p| u[3 * p + c]).collect());
            let mut interleaved = vec![0.0; 3 * nn];
            stencil.apply_on(&u, &mut interleaved, false);
            for parallel in [false, true] {
                let mut out: [Vec<f64>; 3] = std::array::from_fn(|_| vec![f64::NAN; nn]);
                stencil.apply_components_on(&split, &mut out, parallel);
                for p in 0..nn {
                    for c in 0..3 {
                        assert_eq!(out[c][p].to_bits(), interleaved[3 * p + c].to_bits(), "n = {n}, node {p}, {c}");
                    }
                }
            }
        }
    }
}
