//! The linear FEM's force `K u` on the regular grid as a stencil: every node's row of `K` is 27
//! blocks of 3x3 (itself and its 26 neighbours), and since every element has the same `K_e`,
//! a row depends only on which faces of the cube the node lies on (below, inside or above along
//! each axis: 27 classes). So `K` is never stored: 27 classes x 27 blocks x 9 values, and a
//! product costs at most 243 multiply-adds a node, gathered row by row (no scatter), against the
//! element loop's 576 a node scattered over eight elements. With an orthotropic material on the
//! grid's axes most blocks couple few components (`Pattern`): 153 multiply-adds a node inside
//! the cube (measured on one core, 24^3, the linear FEM's 1 ms tick of six
//! substeps with the probe pressed: 1.98 to 2.17 ms with every entry, 1.81 to 1.85 without the
//! zero ones, runs alternated).
//!
//! Two layouts: interleaved (`3 node + component`, [`Stencil::apply`]) and component-wise
//! (`u[c][node]`, [`Stencil::apply_components`], the running FEM's state, in `f64` or `f32`). In
//! the second, the nodes of a grid row that are inside along x share one class and read their
//! neighbours at the same index steps, so with AVX2 a register of them (four in `f64`, eight in
//! `f32`) is summed at a time, two registers where the row has room; an x face's nodes inside
//! along y likewise, gathered n apart. Every node's sum is the same sequence of operations in
//! both layouts and on every path, so in `f64` the bits are the same. The `f32` product (the
//! linear FEM's `cpu-f32` step) took 105 to 106 us at 24^3 on one core against 178 to 181 us in
//! `f64` (minimum of 30 batches of 100 products, three runs; see `docs/speed.md`).
//!
//! `run`: a run of rows, one node at a time or in AVX2 registers.

use super::element::{ElementStiffness, NODE_SIDES};
use crate::mechanics::grid::Grid;

/// A neighbour in a node's row of `K`: the step in node index to it, its 3x3 block (row-major,
/// in `f64` or `f32`) and which of the block's entries are not zero.
#[derive(Debug, Clone, Copy)]
pub struct Tap<T> {
    delta: isize,
    block: [T; 9],
    pattern: Pattern,
}

/// A class's taps grouped by pattern (diagonal blocks, then those coupling x and y, x and z, y
/// and z, then full ones; each group in increasing offset), so that a group's products are
/// written out without a branch on the pattern.
#[derive(Debug, Clone)]
pub struct ClassTaps<T> {
    taps: Vec<Tap<T>>,
    /// Where each pattern's group ends in `taps`.
    ends: [usize; 5],
}

impl<T: Copy> ClassTaps<T> {
    /// `taps` (in increasing offset) grouped by pattern.
    fn grouped(taps: &[Tap<T>]) -> Self {
        let mut sorted = Vec::with_capacity(taps.len());
        let ends = Pattern::ALL.map(|pattern| {
            sorted.extend(taps.iter().filter(|t| t.pattern == pattern));
            sorted.len()
        });
        Self { taps: sorted, ends }
    }

    /// The taps of the `i`-th pattern of [`Pattern::ALL`].
    #[inline(always)]
    fn group(&self, i: usize) -> &[Tap<T>] {
        &self.taps[if i == 0 { 0 } else { self.ends[i - 1] }..self.ends[i]]
    }

    /// The same taps with each block in another precision.
    fn map<U>(&self, f: impl Fn(T) -> U) -> ClassTaps<U> {
        let taps =
            self.taps.iter().map(|t| Tap { delta: t.delta, block: t.block.map(&f), pattern: t.pattern }).collect();
        ClassTaps { taps, ends: self.ends }
    }
}

/// `$group!(taps, pattern)` for each pattern's group of a [`ClassTaps`], the pattern a constant.
macro_rules! by_pattern {
    ($class:expr, $group:ident) => {{
        $group!($class.group(0), Pattern::Diagonal);
        $group!($class.group(1), Pattern::Xy);
        $group!($class.group(2), Pattern::Xz);
        $group!($class.group(3), Pattern::Yz);
        $group!($class.group(4), Pattern::Full);
    }};
}

/// The number a product runs in: `f64` (the model's own) or `f32` (half the memory and twice
/// the lanes; [`Stencil::apply_components`] in either), with its taps and its rows inside along x.
pub trait Precision:
    Copy + Default + Send + Sync + std::ops::Add<Output = Self> + std::ops::Mul<Output = Self> + std::ops::AddAssign
{
    /// The stencil's taps in this precision.
    #[doc(hidden)]
    fn taps(stencil: &Stencil) -> &[ClassTaps<Self>];
    /// The rows of one class's [`Run`] of nodes into `out[..][l stride]`, `l < len`.
    #[doc(hidden)]
    fn run(taps: &ClassTaps<Self>, u: [&[Self]; 3], run: Run, out: [&mut [Self]; 3]);
}

/// Nodes of one class at even steps: `from + l stride` for `l < len` (a grid row's nodes inside
/// along x, stride 1, or an x face's nodes inside along y, stride n).
#[doc(hidden)]
#[derive(Debug, Clone, Copy)]
pub struct Run {
    from: usize,
    stride: usize,
    len: usize,
}

impl Precision for f64 {
    fn taps(stencil: &Stencil) -> &[ClassTaps<f64>] {
        &stencil.taps
    }
    fn run(taps: &ClassTaps<f64>, u: [&[f64]; 3], run: Run, out: [&mut [f64]; 3]) {
        #[cfg(target_arch = "x86_64")]
        {
            if run.len >= 4 && std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports AVX2, checked just above.
                unsafe { row_avx2_f64(taps, u, run, out) };
                return;
            }
        }
        run_scalar(taps, u, run, out);
    }
}

impl Precision for f32 {
    fn taps(stencil: &Stencil) -> &[ClassTaps<f32>] {
        &stencil.taps_f32
    }
    fn run(taps: &ClassTaps<f32>, u: [&[f32]; 3], run: Run, out: [&mut [f32]; 3]) {
        #[cfg(target_arch = "x86_64")]
        {
            if run.len >= 8 && std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports AVX2, checked just above.
                unsafe { row_avx2_f32(taps, u, run, out) };
                return;
            }
        }
        run_scalar(taps, u, run, out);
    }
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
    /// Every pattern, in the order a class's taps are summed.
    const ALL: [Pattern; 5] = [Self::Diagonal, Self::Xy, Self::Xz, Self::Yz, Self::Full];

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
    /// `taps[class]`: the neighbours a node of `class` has, grouped by pattern.
    taps: Vec<ClassTaps<f64>>,
    /// `taps` with each block rounded to `f32`.
    taps_f32: Vec<ClassTaps<f32>>,
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

/// A node's row of `K` times `u`: the sum over its taps, pattern group by pattern group, each
/// `b u_q` summed as `(b0 x + b1 y) + b2 z` per component without its zero terms
/// ([`pattern_rows`]; the order [`simd_run`] keeps).
#[inline(always)]
fn row_sum<T: Precision>(class: &ClassTaps<T>, p: usize, load: impl Fn(usize) -> [T; 3]) -> [T; 3] {
    let mut acc = [T::default(); 3];
    macro_rules! group {
        ($taps:expr, $pattern:expr) => {
            for t in $taps {
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
                let rows = pattern_rows!($pattern, x, y, z, m, a);
                for (acc, r) in acc.iter_mut().zip(rows) {
                    *acc += r;
                }
            }
        };
    }
    by_pattern!(class, group);
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
        let taps: Vec<ClassTaps<f64>> = (0..27)
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
                    .collect::<Vec<_>>()
            })
            .map(|class| ClassTaps::grouped(&class))
            .collect();
        let taps_f32 = taps.iter().map(|class| class.map(|b| b as f32)).collect();
        Self { n, blocks, taps, taps_f32 }
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
    /// over the physics pool on a large enough grid: in `f64` the same bits as
    /// [`Stencil::apply`]; in `f32` the same sums with the blocks rounded to `f32`. Allocates
    /// nothing.
    pub fn apply_components<T: Precision>(&self, u: &[Vec<T>; 3], out: &mut [Vec<T>; 3]) {
        self.apply_components_on(u, out, true);
    }

    /// [`Stencil::apply_components`], on the calling thread alone unless `parallel`.
    pub fn apply_components_on<T: Precision>(&self, u: &[Vec<T>; 3], out: &mut [Vec<T>; 3], parallel: bool) {
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
    fn components_slab<T: Precision>(&self, u: [&[T]; 3], k: usize, out: [&mut [T]; 3]) {
        let (n, taps) = (self.n, T::taps(self));
        let load = |q: usize| [u[0][q], u[1][q], u[2][q]];
        let [o0, o1, o2] = out;
        let plane = n * n * k;
        for i in [0, n - 1] {
            for j in [0, n - 1] {
                let acc = row_sum(&taps[side(i, n) + 3 * side(j, n) + 9 * side(k, n)], plane + n * j + i, load);
                (o0[n * j + i], o1[n * j + i], o2[n * j + i]) = (acc[0], acc[1], acc[2]);
            }
            if n > 2 {
                // The x face's nodes inside along y, n apart.
                let class = &taps[side(i, n) + 3 + 9 * side(k, n)];
                let at = n + i..;
                let run = Run { from: plane + n + i, stride: n, len: n - 2 };
                T::run(class, u, run, [&mut o0[at.clone()], &mut o1[at.clone()], &mut o2[at]]);
            }
        }
        if n > 2 {
            for j in 0..n {
                let at = n * j + 1..n * j + n - 1;
                let run = Run { from: plane + n * j + 1, stride: 1, len: n - 2 };
                let class = &taps[1 + 3 * side(j, n) + 9 * side(k, n)];
                T::run(class, u, run, [&mut o0[at.clone()], &mut o1[at.clone()], &mut o2[at]]);
            }
        }
    }
}

mod run;

use run::run_scalar;
#[cfg(target_arch = "x86_64")]
use run::{row_avx2_f32, row_avx2_f64};

#[cfg(test)]
mod tests;
