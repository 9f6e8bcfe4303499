//! Wall-time measurement shared by the benchmark and the chart: the median of repeated calls
//! within a time budget.

use std::time::Instant;

/// Median time per call of `f`, from batches of at least ~20 ms over about `budget_s` seconds.
pub fn time_per_call(budget_s: f64, mut f: impl FnMut()) -> f64 {
    f();
    let t = Instant::now();
    f();
    let one = t.elapsed().as_secs_f64().max(1e-9);
    let per_batch = ((0.02 / one).ceil() as usize).max(1);
    let batches = ((budget_s / (one * per_batch as f64)) as usize).clamp(5, 51);
    let mut samples: Vec<f64> = (0..batches)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..per_batch {
                f();
            }
            t.elapsed().as_secs_f64() / per_batch as f64
        })
        .collect();
    samples.sort_by(f64::total_cmp);
    samples[samples.len() / 2]
}

/// [`time_per_call`] of a fallible `f`: the first error, if any call fails.
pub fn time_fallible<E>(budget_s: f64, mut f: impl FnMut() -> Result<(), E>) -> Result<f64, E> {
    let mut failed = None;
    let t = time_per_call(budget_s, || {
        if let Err(e) = f() {
            failed.get_or_insert(e);
        }
    });
    failed.map_or(Ok(t), Err)
}
