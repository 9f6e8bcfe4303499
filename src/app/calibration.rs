//! Calibration on a background thread: progress per generation through a channel, cancel, and a
//! result to apply. At most one runs at a time.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, channel};
use std::thread::JoinHandle;

use crate::calibrate::{CalibrationResult, GeneSpace, GenerationStats, Problem, Settings, calibrate};
use crate::grid::Grid;
use crate::material::Material;
use crate::msm::Topology;

/// Messages from the calibration thread.
#[derive(Debug)]
pub enum Progress {
    /// One generation done.
    Generation(GenerationStats),
    /// Finished (or failed).
    Done(Result<Box<CalibrationResult>, String>),
}

/// A running calibration.
#[derive(Debug)]
pub struct Job {
    rx: Receiver<Progress>,
    cancel: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
    /// Generations requested.
    pub generations: usize,
}

impl Job {
    /// Starts calibrating `material`'s `topology` with `settings`; `wake` is called after each
    /// message (to repaint the UI).
    pub fn start(
        material: Material,
        topology: Topology,
        settings: Settings,
        wake: impl Fn() + Send + 'static,
    ) -> std::io::Result<Self> {
        let (tx, rx) = channel();
        let cancel = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&cancel);
        let generations = settings.generations;
        let handle = std::thread::Builder::new().name("calibration".into()).spawn(move || {
            let grid = Grid::paper();
            let space = GeneSpace::new(&material, &grid, topology);
            let result = Problem::new(material, grid, topology).map_err(|e| e.to_string()).and_then(|problem| {
                calibrate(&problem, &space, &settings, &flag, &mut |s| {
                    let _ = tx.send(Progress::Generation(s.clone()));
                    wake();
                })
                .map_err(|e| e.to_string())
            });
            let _ = tx.send(Progress::Done(result.map(Box::new)));
            wake();
        })?;
        Ok(Self { rx, cancel, handle: Some(handle), generations })
    }

    /// Messages received since the last call.
    pub fn poll(&self) -> Vec<Progress> {
        self.rx.try_iter().collect()
    }

    /// Whether the thread has ended (check [`Job::poll`] first for its result).
    pub fn finished(&self) -> bool {
        self.handle.as_ref().is_none_or(JoinHandle::is_finished)
    }

    /// Asks the run to stop (within one generation).
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

impl Drop for Job {
    fn drop(&mut self) {
        self.cancel();
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}
