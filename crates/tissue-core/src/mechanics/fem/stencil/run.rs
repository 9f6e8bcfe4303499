//! A run of the stencil's rows: one node at a time, or AVX2 registers of nodes side by side (`f64` and `f32`), with the same bits.

use super::*;

/// The rows of a [`Run`] into `out[..][l stride]`, one node at a time.
pub(super) fn run_scalar<T: Precision>(taps: &ClassTaps<T>, u: [&[T]; 3], run: Run, out: [&mut [T]; 3]) {
    let load = |q: usize| [u[0][q], u[1][q], u[2][q]];
    let [o0, o1, o2] = out;
    for l in 0..run.len {
        let acc = row_sum(taps, run.from + l * run.stride, load);
        let at = l * run.stride;
        (o0[at], o1[at], o2[at]) = (acc[0], acc[1], acc[2]);
    }
}

/// A [`Run`]'s rows with AVX2, `W` nodes a register (4 in `f64`, 8 in `f32`): along x two
/// registers at a time (each of a tap's entries broadcast once for both), then one; along y
/// one, gathered; the last group overlapping the ones before where the run is not a multiple of
/// `W` (the same sums written twice); at least `W` nodes. No fused multiply-add, so every node's
/// sum has the bits of [`row_sum`].
macro_rules! simd_run {
    ($run:ident, $group:ident, $gather:ident, $t:ty, $w:expr, $vec:ident, $zero:ident, $set1:ident,
     $load:ident, $store:ident, $mul:ident, $add:ident) => {
        /// The rows of a run ([`simd_run`]).
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        pub(super) unsafe fn $run(taps: &ClassTaps<$t>, u: [&[$t]; 3], run: Run, out: [&mut [$t]; 3]) {
            debug_assert!(run.len >= $w && out.iter().all(|o| o.len() > (run.len - 1) * run.stride));
            let [o0, o1, o2] = out;
            let mut s = 0;
            if run.stride == 1 {
                while s + 2 * $w <= run.len {
                    // SAFETY: the caller's CPU supports AVX2 (this function's own feature).
                    unsafe { $group::<2, false>(taps, u, run, s, [&mut *o0, &mut *o1, &mut *o2]) };
                    s += 2 * $w;
                }
            }
            while s < run.len {
                let start = s.min(run.len - $w);
                // SAFETY: as above.
                unsafe {
                    if run.stride == 1 {
                        $group::<1, false>(taps, u, run, start, [&mut *o0, &mut *o1, &mut *o2]);
                    } else {
                        $group::<1, true>(taps, u, run, start, [&mut *o0, &mut *o1, &mut *o2]);
                    }
                }
                s = start + $w;
            }
        }

        /// The rows of the `W V` nodes `start..` of `run` into `out[..][start stride..]`
        /// (`STRIDED`: gathered `stride` apart, else contiguous).
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        #[inline]
        unsafe fn $group<const V: usize, const STRIDED: bool>(
            taps: &ClassTaps<$t>,
            u: [&[$t]; 3],
            run: Run,
            start: usize,
            out: [&mut [$t]; 3],
        ) {
            use std::arch::x86_64::{$add, $load, $mul, $set1, $store, $vec, $zero};
            let (p, stride) = (run.from + start * run.stride, run.stride);
            // The span of one register's nodes in `u`.
            let span = if STRIDED { stride * ($w - 1) + 1 } else { $w * V };
            let mut acc: [[$vec; 3]; V] = [[$zero(); 3]; V];
            macro_rules! group {
                ($taps:expr, $pattern:expr) => {
                    for t in $taps {
                        let q = p.wrapping_add_signed(t.delta);
                        // One tap's neighbours of the group: bounds-checked once as slices.
                        let (x, y, z) = (&u[0][q..q + span], &u[1][q..q + span], &u[2][q..q + span]);
                        let b = &t.block;
                        macro_rules! m {
                            ($i:expr, $v:expr) => {
                                $mul($set1(b[$i]), $v)
                            };
                        }
                        macro_rules! a {
                            ($p:expr, $q:expr) => {
                                $add($p, $q)
                            };
                        }
                        for (w, acc) in acc.iter_mut().enumerate() {
                            // SAFETY: contiguous, each slice holds W V values and `W w + W <= W
                            // V`; strided (V = 1), the W values `stride` apart end at the last.
                            let (x, y, z) = unsafe {
                                if STRIDED {
                                    ($gather(x.as_ptr(), stride), $gather(y.as_ptr(), stride), $gather(z.as_ptr(), stride))
                                } else {
                                    (
                                        $load(x.as_ptr().add($w * w)),
                                        $load(y.as_ptr().add($w * w)),
                                        $load(z.as_ptr().add($w * w)),
                                    )
                                }
                            };
                            let rows = pattern_rows!($pattern, x, y, z, m, a);
                            for (a, r) in acc.iter_mut().zip(rows) {
                                *a = $add(*a, r);
                            }
                        }
                    }
                };
            }
            by_pattern!(taps, group);
            for (c, o) in out.into_iter().enumerate() {
                if STRIDED {
                    let mut lanes = [<$t>::default(); $w];
                    // SAFETY: `lanes` holds W values.
                    unsafe { $store(lanes.as_mut_ptr(), acc[0][c]) };
                    for (l, v) in lanes.into_iter().enumerate() {
                        o[(start + l) * stride] = v;
                    }
                } else {
                    let d = &mut o[start..start + $w * V];
                    for (w, acc) in acc.iter().enumerate() {
                        // SAFETY: `d` holds exactly W V values, just checked, and `W w + W <= W V`.
                        unsafe { $store(d.as_mut_ptr().add($w * w), acc[c]) };
                    }
                }
            }
        }
    };
}

/// `W = 4` values `stride` apart from `p`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) unsafe fn gather_f64(p: *const f64, stride: usize) -> std::arch::x86_64::__m256d {
    use std::arch::x86_64::{_mm_setr_epi32, _mm256_i32gather_pd};
    let s = stride as i32;
    // SAFETY: the caller's values are in one slice (its bounds checked).
    unsafe { _mm256_i32gather_pd::<8>(p, _mm_setr_epi32(0, s, 2 * s, 3 * s)) }
}

/// `W = 8` values `stride` apart from `p`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(super) unsafe fn gather_f32(p: *const f32, stride: usize) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::{_mm256_i32gather_ps, _mm256_setr_epi32};
    let s = stride as i32;
    // SAFETY: the caller's values are in one slice (its bounds checked).
    unsafe { _mm256_i32gather_ps::<4>(p, _mm256_setr_epi32(0, s, 2 * s, 3 * s, 4 * s, 5 * s, 6 * s, 7 * s)) }
}

simd_run!(
    row_avx2_f64,
    group_avx2_f64,
    gather_f64,
    f64,
    4,
    __m256d,
    _mm256_setzero_pd,
    _mm256_set1_pd,
    _mm256_loadu_pd,
    _mm256_storeu_pd,
    _mm256_mul_pd,
    _mm256_add_pd
);
simd_run!(
    row_avx2_f32,
    group_avx2_f32,
    gather_f32,
    f32,
    8,
    __m256,
    _mm256_setzero_ps,
    _mm256_set1_ps,
    _mm256_loadu_ps,
    _mm256_storeu_ps,
    _mm256_mul_ps,
    _mm256_add_ps
);
