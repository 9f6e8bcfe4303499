//! The physics' own thread pool: the per-element and per-node loops of a step split over the
//! machine's cores. Its own pool (not rayon's global one, which a background calibration fills),
//! so a step never waits behind a calibration's tasks (see [`on_pool`] for what it may take).

use std::sync::OnceLock;

/// Below this many items a loop runs on the calling thread: a split costs some 30 us, more than
/// it saves on the 343 elements of the 8^3 corotational FEM (`bench`: 88 us on one thread,
/// 121 us on two; 1.22x faster on two at 16^3). Measured when the corotational elements split
/// by rows; they now split by layers of elements, half of them a pass (not measured again).
pub const MIN_PARALLEL_ITEMS: usize = 1000;

/// The pool, one thread per core; `None` on one core or where no thread can be started.
pub fn pool() -> Option<&'static rayon::ThreadPool> {
    static POOL: OnceLock<Option<rayon::ThreadPool>> = OnceLock::new();
    POOL.get_or_init(|| {
        let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
        if cores < 2 {
            return None;
        }
        rayon::ThreadPoolBuilder::new().num_threads(cores).thread_name(|i| format!("physics-{i}")).build().ok()
    })
    .as_ref()
}

/// Runs `f` on a thread of the pool (here, where there is no pool), and returns its answer. A
/// loop of steps run this way splits each step over the pool from inside it, where a split goes
/// on the thread's own task queue and allocates nothing. A call into the pool from outside
/// queues each split in rayon's shared injector instead, which allocates a block every 63
/// calls. The viewer's physics loop and `bench`'s timed ticks run here. The loop's thread is
/// then one of the pool's: while it waits for a split's other half it may take another queued
/// task of the pool's (a background FEM answer's stencil product at 16^3 and above), which it
/// finishes first. On one core there is no pool: `f` runs here.
pub fn on_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    match pool() {
        Some(pool) => pool.install(f),
        None => f(),
    }
}
