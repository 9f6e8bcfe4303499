//! Calibration in the background: the body of a [`Slot`] job that reports every generation and
//! ends with the result, cancelled within one generation.

use crate::app::worker::{Slot, StartError};
use crate::calibrate::{CalibrationResult, CaseSet, GeneSpace, GenerationStats, Problem, Settings, calibrate};
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::msm::Topology;

/// Messages from the calibration thread.
#[derive(Debug)]
pub enum Progress {
    /// One generation done.
    Generation(GenerationStats),
    /// Finished (or failed).
    Done(Result<Box<CalibrationResult>, String>),
}

/// What to calibrate.
#[derive(Debug, Clone)]
pub struct Job {
    /// The material.
    pub material: Material,
    /// The lattice.
    pub topology: Topology,
    /// The grid (the viewer's resolution).
    pub grid: Grid,
    /// The training cases.
    pub cases: CaseSet,
    /// Search settings.
    pub settings: Settings,
}

/// Starts `job` in `slot` (refused while one runs); `wake` repaints the UI after each message.
pub fn start(slot: &mut Slot<Progress>, job: Job, wake: impl Fn() + Send + Sync + 'static) -> Result<(), StartError> {
    let Job { material, topology, grid, cases, settings } = job;
    slot.start("calibration", wake, move |ctx| {
        let space = GeneSpace::new(&material, &grid, topology);
        let problem = Problem::new(material, grid, topology).and_then(|p| p.with_cases(cases));
        let result = problem.map_err(|e| e.to_string()).and_then(|problem| {
            calibrate(&problem, &space, &settings, ctx.cancel_flag(), &mut |s| {
                ctx.send(Progress::Generation(s.clone()));
            })
            .map_err(|e| e.to_string())
        });
        ctx.send(Progress::Done(result.map(Box::new)));
    })
}
