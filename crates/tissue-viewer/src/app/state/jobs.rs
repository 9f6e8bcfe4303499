//! The viewer state's background jobs: the touch validation of the running model, the FEM's
//! probe force beside the model's, and the calibration.

use std::sync::Arc;

use super::super::physics::Command;
use crate::app::exercise::FELT_DEPTH_M;
use crate::io::cache::CacheEvent;
use crate::mechanics::grid::CUBE_SIDE_M;
use crate::sim::material_surface::MaterialSurface;
use crate::sim::material_surface::compliance::{SurfaceCompliance, SurfaceContactScratch};
use crate::study::palpate::{Face, Palpation, PalpationMap};

use super::super::calibration_job;
use super::{ProbeComparison, ViewerState};
use crate::calibrate::Settings;
use crate::mechanics::msm::MsmParams;
use crate::sim::Model;

/// Messages of the surface compliance job.
#[derive(Debug)]
pub(super) enum ComplianceMessage {
    /// What it computes now.
    Stage(String),
    /// The fraction done.
    Progress(f64),
    /// Ready (or failed): the material's, its background's compliance, and the force over the
    /// hidden lump with it and without, if one is.
    Done(Result<(MaterialSurface, Arc<SurfaceCompliance>, Option<[f64; 2]>), String>),
}

/// The free face a probe centred at `centre` (outside the cube) pressed: the one it stands
/// farthest out of (the top face where it is over none).
fn pressed_face(centre: [f64; 3]) -> Face {
    let l = crate::mechanics::grid::CUBE_SIDE_M;
    let mut best = (0.0, Face { axis: 2, high: true });
    for axis in 0..3 {
        for (out, high) in [(centre[axis] - l, true), (-centre[axis], false)] {
            if out > best.0 && (axis != 2 || high) {
                best = (out, Face { axis, high });
            }
        }
    }
    best.1
}

/// What the validation job reports: the touch benchmark's scores, then, for a material with
/// inclusions, the model against the material with them.
#[derive(Debug)]
pub(super) enum Scored {
    Touch(Result<crate::sim::shipped::RecordedScores, String>),
    Inclusions(Result<crate::validate::inclusions::InclusionReport, String>),
}

impl ViewerState {
    /// Loads (or computes, about a minute, and keeps) the material's surface compliance in the
    /// background; the probe uses the model's surface nodes until it is ready.
    pub(super) fn start_compliance(&mut self) {
        // A map or a compliance of the material before: gone.
        self.compliances = None;
        self.forget_map();
        if self.compliance.busy() {
            // Another material's: stopped within a batch, then this one starts.
            self.compliance.cancel();
            self.compliance_stale = true;
            return;
        }
        let material = self.shown.felt_material();
        // A hidden lump's correction lives in memory only (random, seldom met again).
        let keep_correction = self.shown.exercise.is_none();
        // Find the lump: what the probe can feel of it, pressed over its centre.
        let over = self.shown.exercise.as_ref().map(|e| {
            let c = e.lump.inclusion.centre;
            let radius = self.settings.probe_radius_mm * 1e-3;
            ([c[0], c[1], CUBE_SIDE_M + radius - FELT_DEPTH_M], radius)
        });
        let wake = Arc::clone(&self.wake);
        self.shown.contact_status = Some("probe contact: the material's surface compliance is loading".into());
        self.shown.material_contact_in = Some("the material's: loading".into());
        self.compliance_since = (std::time::Instant::now(), None);
        let started = self.compliance.start(
            "surface compliance",
            move || wake(),
            move |ctx| {
                let dir = crate::io::cache_dir();
                // Stopped within a batch when the viewer closes or the material changes.
                let r = MaterialSurface::with_background(&material, dir.as_deref(), keep_correction, &mut |event| {
                    match event {
                        CacheEvent::Progress(f) => {
                            ctx.send(ComplianceMessage::Progress(f));
                            !ctx.cancelled()
                        }
                        // A cache file refused, or the answer not kept: said where the viewer was started.
                        CacheEvent::Warning(line) => {
                            eprintln!("{line}");
                            true
                        }
                        CacheEvent::Computing { .. } => {
                            ctx.send(ComplianceMessage::Stage("the material's surface compliance".into()));
                            true
                        }
                        CacheEvent::Part { what, .. } => {
                            ctx.send(ComplianceMessage::Stage(what.into()));
                            true
                        }
                    }
                });
                let r = r.map_err(|e| format!("{e:#}")).and_then(|(background, surface)| {
                    let felt = match over {
                        Some((centre, radius)) => {
                            let mut scratch = SurfaceContactScratch::default();
                            let mut press = |c: &SurfaceCompliance| {
                                c.press(centre, radius, &mut scratch).map(|f| f[2]).map_err(|e| e.to_string())
                            };
                            Some([press(&surface.compliance)?, press(&background)?])
                        }
                        None => None,
                    };
                    Ok((surface, background, felt))
                });
                ctx.send(ComplianceMessage::Done(r));
            },
        );
        if let Err(e) = started {
            self.shown.contact_status = Some(format!("probe contact: the model's nodes ({e})"));
            self.shown.material_contact_in = Some("the material's: not computed".into());
        }
    }

    /// Takes the surface compliance job's messages; a ready compliance goes to the physics.
    pub(super) fn poll_compliance(&mut self, send: &mut dyn FnMut(Command)) {
        let shown = &mut self.shown;
        let stale = self.compliance_stale;
        let stage = &mut self.compliance_stage;
        let compliances = &mut self.compliances;
        let deferred = &mut self.deferred_press;
        let since = &mut self.compliance_since;
        let ended = self.compliance.poll(|m| match m {
            // Another material's: dropped.
            _ if stale => {}
            ComplianceMessage::Stage(what) => {
                *stage = what;
                *since = (std::time::Instant::now(), None);
            }
            ComplianceMessage::Progress(f) => {
                let first = *since.1.get_or_insert(f);
                let left = time_left(since.0.elapsed().as_secs_f64(), first, f);
                let eta = left.as_ref().map_or(String::new(), |s| format!(", about {s} left"));
                shown.contact_status = Some(format!(
                    "probe contact: computing {stage}, {:.0} %{eta} (meanwhile the model's nodes push back)",
                    100.0 * f
                ));
                shown.material_contact_in =
                    Some(left.map_or_else(|| "the material's: computing".into(), |s| format!("the material's in {s}")));
            }
            ComplianceMessage::Done(Ok((c, background, felt))) => {
                shown.contact_status = None;
                shown.material_contact_in = None;
                *compliances = Some([Arc::clone(&c.compliance), background]);
                send(Command::SetSurfaceProbe(Some(c)));
                if let Some(p) = deferred.take() {
                    send(Command::Press(p));
                }
                if let Some(e) = shown.exercise.as_mut().filter(|e| e.ready.is_none()) {
                    e.ready = Some(std::time::Instant::now());
                    e.felt = felt;
                }
            }
            ComplianceMessage::Done(Err(e)) => {
                if let Some(p) = deferred.take() {
                    send(Command::Press(p));
                }
                shown.contact_status =
                    Some(format!("probe contact: the model's nodes (surface compliance failed: {e})"));
                shown.material_contact_in = Some("the material's failed".into());
                if shown.exercise.take_if(|e| e.ready.is_none()).is_some() {
                    shown.note = Some(format!("the hidden lump cannot be felt, so it is gone: {e}"));
                }
            }
        });
        if let Some(super::super::worker::State::Stopped(why)) = &ended {
            self.shown.contact_status = Some(format!("probe contact: the model's nodes (the job stopped: {why})"));
            self.shown.material_contact_in = Some("the material's stopped".into());
        }
        if ended.is_some() && stale {
            self.compliance_stale = false;
            self.start_compliance();
        }
    }

    /// Scores the running model on the touch benchmark in the background, and for a material
    /// with inclusions against the material with them (again when it ends, if the model changes
    /// meanwhile: the running one is asked to stop).
    pub(super) fn start_validation(&mut self) {
        if self.validation.busy() {
            self.validation.cancel();
            self.validation_stale = true;
            return;
        }
        self.validation_stale = false;
        self.shown.validation = None;
        self.shown.inclusion_validation = None;
        let (material, grid) = (self.shown.modelled_material(), self.grid);
        let model = self.model_under_test();
        let wake = Arc::clone(&self.wake);
        let started = self.validation.start(
            "touch validation",
            move || wake(),
            move |ctx| {
                let r = crate::validate::touch::score::Reference::new(&material, grid)
                    .and_then(|reference| {
                        crate::validate::touch::score::evaluate(&reference, &material, model.0, Some(model.1))
                    })
                    .map(|r| crate::sim::shipped::RecordedScores {
                        worst_force_error: r.worst_force_error,
                        median_force_error: r.median_force_error,
                        worst_frequency_error: r.worst_frequency_error,
                    })
                    .map_err(|e| format!("{e:#}"));
                let touched = r.is_ok();
                ctx.send(Scored::Touch(r));
                if material.inclusions.is_empty() || ctx.cancelled() {
                    return;
                }
                let r = if touched {
                    let stop = || ctx.cancelled();
                    crate::validate::inclusions::evaluate_until(&material, model.0, Some(model.1), grid, &stop)
                        .map_err(|e| format!("{e:#}"))
                } else {
                    Err("not scored (the touch validation failed)".into())
                };
                ctx.send(Scored::Inclusions(r));
            },
        );
        if let Err(e) = started {
            self.shown.validation = Some(Err(e.to_string()));
            self.shown.inclusion_validation = Some(Err(e.to_string()));
        }
    }

    /// The probe's last press set beside the material's force for it (the converged continuum of
    /// the felt material, kept in the cache folder) and the running model's static force with its
    /// own nodes as the contact.
    pub(super) fn start_comparison(&mut self) {
        let Some((press, reading)) = self.shown.last_reading else {
            self.shown.note = Some("press the probe into the cube first".into());
            return;
        };
        let (felt, grid) = (self.shown.felt_material(), self.grid);
        let model = self.model_under_test();
        let modelled = self.shown.modelled_material();
        let wake = Arc::clone(&self.wake);
        let started = self.comparison.start(
            "press comparison",
            move || wake(),
            move |ctx| {
                let material_n = {
                    let dir = crate::io::cache_dir();
                    let mut kept = crate::validate::continuum::cache::ContinuumCache::open(&felt, dir.as_deref());
                    let tolerance = crate::validate::continuum::DEFAULT_TOLERANCE;
                    let r = kept.force(&felt, &press, tolerance, &mut |_| {}).map(|c| c.force_n);
                    kept.save();
                    r.map_err(|e| format!("{e:#}"))
                };
                let model_n = (|| -> anyhow::Result<f64> {
                    let (mut r, _) = crate::validate::touch::score::responder(model.0, Some(model.1), &modelled, grid)?;
                    Ok(r.solver.probe(&grid, press.centre(), press.radius)?.force_n())
                })()
                .map_err(|e| format!("{e:#}"));
                ctx.send(Ok(ProbeComparison {
                    press,
                    shown_n: reading.force_n,
                    shown_contact: reading.contact,
                    material_n,
                    model_n,
                }));
            },
        );
        match started {
            Ok(()) => self.shown.comparing = true,
            Err(e) => self.shown.note = Some(e.to_string()),
        }
    }

    /// The running model as the touch benchmark scores it: the model and the lattice's
    /// parameters (unused by the FEM).
    fn model_under_test(&self) -> (Model, MsmParams) {
        (self.shown.model(), self.shown.params)
    }

    /// Starts a calibration of the running topology with the panel's settings in the background.
    pub(super) fn start_calibration(&mut self) {
        let settings = Settings {
            method: self.settings.calib_method,
            seed: self.settings.calib_seed,
            population: self.settings.calib_population,
            generations: self.settings.calib_generations,
            ..Settings::default()
        };
        let wake = Arc::clone(&self.wake);
        let material = self.shown.material.clone();
        let job = calibration_job::Job {
            material,
            topology: self.shown.topology(),
            grid: self.grid,
            cases: self.settings.calib_cases,
            settings,
        };
        match calibration_job::start(&mut self.calibration, job, move || wake()) {
            Ok(()) => {
                self.shown.history.clear();
                self.shown.result = None;
                self.shown.calibration = None;
                self.shown.note = None;
                self.shown.calibrating = true;
                self.shown.calib_generations = self.settings.calib_generations;
                self.shown.calib_cases = self.settings.calib_cases;
            }
            Err(e) => self.shown.note = Some(format!("cannot start the calibration: {e}")),
        }
    }
}

impl ViewerState {
    /// The palpation map of the top face with the probe's radius, in the background (about two
    /// seconds: 2 x 441 presses), once the surface compliance is loaded.
    pub(super) fn start_map(&mut self) {
        let Some([felt, background]) = self.compliances.clone() else {
            self.shown.face_map = Some(Err("the surface compliance is still loading".into()));
            return;
        };
        let material = self.shown.felt_material();
        let palpation = Palpation {
            face: self.shown.last_probe.map_or(Face { axis: 2, high: true }, |(centre, _)| pressed_face(centre)),
            radius: self.settings.probe_radius_mm * 1e-3,
            depth: crate::app::face_map::DEPTH_M,
            grid: crate::app::face_map::GRID,
        };
        let wake = Arc::clone(&self.wake);
        let generation = self.map_generation;
        let started = self.map.start(
            "palpation map",
            move || wake(),
            move |ctx| {
                let r = palpation.check().and_then(|()| {
                    let forces = palpation.forces(&felt, &mut || {})?;
                    let plain = palpation.forces(&background, &mut || {})?;
                    Ok(PalpationMap::new(&material, &palpation, forces, plain))
                });
                ctx.send((generation, r));
            },
        );
        if let Err(e) = started {
            self.shown.face_map = Some(Err(e.to_string()));
        }
    }

    /// Takes the palpation map when it is ready (one of another material or grid is dropped).
    pub(super) fn poll_map(&mut self) {
        let (grid, current) = (self.grid, self.map_generation);
        let shown = &mut self.shown;
        self.map.poll(|(generation, r): (u64, Result<PalpationMap, String>)| {
            if generation == current {
                shown.face_map = Some(r.map(|m| crate::app::face_map::FaceMap::new(m, &grid)));
            }
        });
    }

    /// The map shown, and any being computed, are of another material or grid.
    pub(super) fn forget_map(&mut self) {
        self.shown.face_map = None;
        self.map_generation += 1;
    }
}

/// The time left of a job `f` done (0 to 1) after `elapsed_s` seconds since it stood at `first`,
/// as a person reads it (`12 s`, `2 min`), at its rate since; `None` before it moved 2 % (no rate
/// to tell yet).
fn time_left(elapsed_s: f64, first: f64, f: f64) -> Option<String> {
    if f - first < 0.02 || f >= 1.0 {
        return None;
    }
    let left = elapsed_s * (1.0 - f) / (f - first);
    Some(if left < 90.0 { format!("{:.0} s", left.max(1.0)) } else { format!("{:.0} min", left / 60.0) })
}
