//! One spring family's pair forces: four pairs at a time in AVX2, or one by one.

/// One family's pair forces: `t = k (1 - l0 / l) d` for each pair's difference `d` (length `l`),
/// from the pairs' ends `[xa, xb, ya, yb, za, zb]`. With AVX2, four pairs at a time with `1 / l`
/// from the f32 reciprocal square root refined by two Newton steps in f64 (relative error under
/// 1e-13, against a square root and a division whose latency held the loop), else one by one.
/// For the explicit step only: a strain carries that error absolutely (1e-13 of a spring's rest
/// length), which is far below any motion but not below a static answer's 1e-12 at a 1 N load.
#[inline(always)]
pub(super) fn pair_loop(k: &[f64], l0: f64, ends: [&[f64]; 6], t: [&mut [f64]; 3]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2, checked just above.
            unsafe { pair_loop_avx2(k, l0, ends, t) };
            return;
        }
    }
    pair_loop_scalar(k, l0, ends, t, 0);
}

/// [`pair_loop`] one pair at a time from pair `from`.
#[inline(always)]
pub(super) fn pair_loop_scalar(k: &[f64], l0: f64, ends: [&[f64]; 6], t: [&mut [f64]; 3], from: usize) {
    let [xa, xb, ya, yb, za, zb] = ends;
    let [tx, ty, tz] = t;
    for p in from..k.len() {
        let dx = xb[p] - xa[p];
        let dy = yb[p] - ya[p];
        let dz = zb[p] - za[p];
        let l = (dx * dx + dy * dy + dz * dz).sqrt().max(f64::MIN_POSITIVE);
        let c = k[p] - k[p] * l0 / l;
        tx[p] = c * dx;
        ty[p] = c * dy;
        tz[p] = c * dz;
    }
}

/// [`pair_loop`] four pairs at a time.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn pair_loop_avx2(k: &[f64], l0: f64, ends: [&[f64]; 6], t: [&mut [f64]; 3]) {
    use std::arch::x86_64::{
        _mm_rsqrt_ps, _mm256_add_pd, _mm256_cvtpd_ps, _mm256_cvtps_pd, _mm256_loadu_pd, _mm256_max_pd, _mm256_mul_pd,
        _mm256_set1_pd, _mm256_storeu_pd, _mm256_sub_pd,
    };
    let len = k.len();
    let [xa, xb, ya, yb, za, zb] = ends;
    debug_assert!(ends.iter().all(|e| e.len() >= len) && t.iter().all(|e| e.len() >= len));
    let [tx, ty, tz] = t;
    let (half, three_halves, l0v) = (_mm256_set1_pd(0.5), _mm256_set1_pd(1.5), _mm256_set1_pd(l0));
    // A floor on `l^2` that f32 still holds (nodes 1e-15 m apart), so `1 / l` stays finite.
    let floor = _mm256_set1_pd(1e-30);
    let mut p = 0;
    while p + 4 <= len {
        // SAFETY: `p + 4 <= len`, and every slice holds at least `len` values (asserted above,
        // and by the callers' ranges).
        unsafe {
            macro_rules! load {
                ($s:expr) => {
                    _mm256_loadu_pd($s.as_ptr().add(p))
                };
            }
            let dx = _mm256_sub_pd(load!(xb), load!(xa));
            let dy = _mm256_sub_pd(load!(yb), load!(ya));
            let dz = _mm256_sub_pd(load!(zb), load!(za));
            let l2 = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
            let l2 = _mm256_max_pd(l2, floor);
            let mut y = _mm256_cvtps_pd(_mm_rsqrt_ps(_mm256_cvtpd_ps(l2)));
            for _ in 0..2 {
                let yy = _mm256_mul_pd(_mm256_mul_pd(half, l2), _mm256_mul_pd(y, y));
                y = _mm256_mul_pd(y, _mm256_sub_pd(three_halves, yy));
            }
            let kv = load!(k);
            let c = _mm256_sub_pd(kv, _mm256_mul_pd(_mm256_mul_pd(kv, l0v), y));
            _mm256_storeu_pd(tx.as_mut_ptr().add(p), _mm256_mul_pd(c, dx));
            _mm256_storeu_pd(ty.as_mut_ptr().add(p), _mm256_mul_pd(c, dy));
            _mm256_storeu_pd(tz.as_mut_ptr().add(p), _mm256_mul_pd(c, dz));
        }
        p += 4;
    }
    pair_loop_scalar(k, l0, [xa, xb, ya, yb, za, zb], [tx, ty, tz], p);
}
