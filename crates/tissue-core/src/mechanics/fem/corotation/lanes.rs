//! Values of several elements side by side, operated on lane by lane: one `f64` (one element at a
//! time, any CPU) or four in an AVX2 register (`F64x4`, only where the CPU has AVX2).
//!
//! Every operation is IEEE's correctly rounded one on each lane (add, subtract, multiply,
//! divide, square root; no fused multiply-add), so an element's values have the same bits in
//! either type and in any lane.

use std::ops::{Add, Div, Mul, Sub};

/// `W` values operated on lane by lane.
pub trait Lane: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> {
    /// How many lanes.
    const W: usize;
    /// `v` in every lane.
    fn splat(v: f64) -> Self;
    /// `s[0..W]`.
    fn load(s: &[f64]) -> Self;
    /// Lane `l` is `f(l)`.
    fn from_fn(f: impl Fn(usize) -> f64) -> Self;
    /// Into `out[0..W]`.
    fn store(self, out: &mut [f64]);
    /// Lane `l`.
    fn lane(self, l: usize) -> f64;
    /// `|v|` on every lane.
    fn abs(self) -> Self;
    /// `sqrt(v)` on every lane.
    fn sqrt(self) -> Self;
    /// Whether every lane is at most `bound` (false on a NaN).
    fn all_at_most(self, bound: f64) -> bool;
    /// On each lane, `kept` where `self <= bound`, else (and on a NaN) `moved`: a choice, not
    /// arithmetic, so the chosen lane's bits are kept.
    fn select_at_most(self, bound: Self, kept: Self, moved: Self) -> Self;
}

impl Lane for f64 {
    const W: usize = 1;
    #[inline(always)]
    fn splat(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn load(s: &[f64]) -> Self {
        s[0]
    }
    #[inline(always)]
    fn from_fn(f: impl Fn(usize) -> f64) -> Self {
        f(0)
    }
    #[inline(always)]
    fn store(self, out: &mut [f64]) {
        out[0] = self;
    }
    #[inline(always)]
    fn lane(self, _: usize) -> f64 {
        self
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f64::abs(self)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn all_at_most(self, bound: f64) -> bool {
        self <= bound
    }
    #[inline(always)]
    fn select_at_most(self, bound: Self, kept: Self, moved: Self) -> Self {
        if self <= bound { kept } else { moved }
    }
}

#[cfg(target_arch = "x86_64")]
pub use avx2::F64x4;

#[cfg(target_arch = "x86_64")]
mod avx2 {
    //! SAFETY (every `unsafe` block below): the AVX2 intrinsics need a CPU that has AVX2. An
    //! `F64x4` is used only inside functions compiled with AVX2 (`#[target_feature(enable =
    //! "avx2")]`, where its methods are inlined) that are called only after
    //! `is_x86_feature_detected!("avx2")`; the type is private to the corotated element's module
    //! for that reason.

    use std::arch::x86_64::*;
    use std::ops::{Add, Div, Mul, Sub};

    use super::Lane;

    /// Four `f64` lanes in an AVX2 register.
    #[derive(Debug, Clone, Copy)]
    pub struct F64x4(__m256d);

    macro_rules! binary {
        ($trait:ident, $method:ident, $intrinsic:ident) => {
            impl $trait for F64x4 {
                type Output = Self;
                #[inline(always)]
                fn $method(self, o: Self) -> Self {
                    // SAFETY: see the module's note.
                    Self(unsafe { $intrinsic(self.0, o.0) })
                }
            }
        };
    }
    binary!(Add, add, _mm256_add_pd);
    binary!(Sub, sub, _mm256_sub_pd);
    binary!(Mul, mul, _mm256_mul_pd);
    binary!(Div, div, _mm256_div_pd);

    impl Lane for F64x4 {
        const W: usize = 4;
        #[inline(always)]
        fn splat(v: f64) -> Self {
            // SAFETY: see the module's note.
            Self(unsafe { _mm256_set1_pd(v) })
        }
        #[inline(always)]
        fn load(s: &[f64]) -> Self {
            let s = &s[..4];
            // SAFETY: four values in bounds (sliced just above); see the module's note.
            Self(unsafe { _mm256_loadu_pd(s.as_ptr()) })
        }
        #[inline(always)]
        fn from_fn(f: impl Fn(usize) -> f64) -> Self {
            Self::load(&[f(0), f(1), f(2), f(3)])
        }
        #[inline(always)]
        fn store(self, out: &mut [f64]) {
            let out = &mut out[..4];
            // SAFETY: four values in bounds (sliced just above); see the module's note.
            unsafe { _mm256_storeu_pd(out.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        fn lane(self, l: usize) -> f64 {
            let mut a = [0.0; 4];
            self.store(&mut a);
            a[l]
        }
        #[inline(always)]
        fn abs(self) -> Self {
            // SAFETY: see the module's note.
            Self(unsafe { _mm256_andnot_pd(_mm256_set1_pd(-0.0), self.0) })
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            // SAFETY: see the module's note.
            Self(unsafe { _mm256_sqrt_pd(self.0) })
        }
        #[inline(always)]
        fn all_at_most(self, bound: f64) -> bool {
            // SAFETY: see the module's note.
            unsafe { _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LE_OQ>(self.0, _mm256_set1_pd(bound))) == 0b1111 }
        }
        #[inline(always)]
        fn select_at_most(self, bound: Self, kept: Self, moved: Self) -> Self {
            // SAFETY: see the module's note.
            Self(unsafe { _mm256_blendv_pd(moved.0, kept.0, _mm256_cmp_pd::<_CMP_LE_OQ>(self.0, bound.0)) })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_lanes_give_each_lanes_bits_alone() {
        let a = [1.0 / 3.0, -2.5e-7, 7.0, f64::MIN_POSITIVE];
        let b = [3.0, 1e-9, -0.1, 2.0];
        let alone = |l: usize| {
            let (x, y) = (a[l], b[l]);
            ((x + y) * x - y / (x.abs() + 1.0)).sqrt()
        };
        assert!(!f64::NAN.all_at_most(1.0));
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            #[target_feature(enable = "avx2")]
            fn four(a: &[f64; 4], b: &[f64; 4]) -> ([f64; 4], [bool; 2], [f64; 4]) {
                let (x, y) = (F64x4::load(a), F64x4::load(b));
                let r = ((x + y) * x - y / (x.abs() + F64x4::splat(1.0))).sqrt();
                let at_most = [F64x4::splat(1.0).all_at_most(1.0), F64x4::from_fn(|l| l as f64).all_at_most(2.5)];
                let chosen = x.select_at_most(y, F64x4::splat(1.0), F64x4::splat(-0.0));
                (std::array::from_fn(|l| r.lane(l)), at_most, std::array::from_fn(|l| chosen.lane(l)))
            }
            // SAFETY: the CPU has AVX2, checked just above.
            let (four, at_most, chosen) = unsafe { four(&a, &b) };
            for (l, v) in four.iter().enumerate() {
                assert_eq!(v.to_bits(), alone(l).to_bits(), "lane {l}");
                assert_eq!(chosen[l].to_bits(), a[l].select_at_most(b[l], 1.0, -0.0).to_bits(), "lane {l}");
            }
            assert_eq!(at_most, [true, false]);
            assert_eq!(chosen.map(f64::to_bits), [1.0, 1.0, -0.0, 1.0].map(f64::to_bits));
        }
    }
}
