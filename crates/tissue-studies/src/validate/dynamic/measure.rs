//! A running model's dynamics, measured by time stepping through the same [`Tissue::step`] the
//! viewer and `simulate` use:
//!
//! * **Period and decay of the fundamental:** the model is released at rest from the static
//!   shape of its own fundamental (the shape under the load `M phi_1`, `phi_1` scaled to
//!   [`RELEASE_AMPLITUDE_M`] at most) on the viewer's scene, and stepped for
//!   [`RELEASE_PERIODS`] periods; the modal coordinate `q = phi_1^T M u` then obeys, for a linear
//!   model, `q_{n+1} = trace q_n - det q_{n-1}` exactly, whose least-squares fit gives the
//!   discrete eigenvalues and so the measured period and damping ratio
//!   ([`crate::response::single_mode::from_recurrence`]). They are compared with the model's own damped
//!   fundamental (integrator error) and with the FEM's (model error).
//! * **Trajectory error:** each reference transient ([`crate::validate::dynamic::reference`]) run on the model
//!   with the same load, the relative L2 in time of the loaded face's displacement; the probe tap
//!   run in the viewer's simulation (its contact and force readout, [`crate::validate::probe::tap`]), the
//!   relative L2 of the force on the probe, against the material's tap and on the model's own
//!   nodes against the same-mesh FEM's.

use crate::mechanics::cases::LoadCase;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::msm::{MsmModel, MsmParams};
use crate::response::damping::Damping;
use crate::response::modal::{ModalModel, Mode};
use crate::response::single_mode::{self, ModeMotion};
use crate::sim::material_surface::MaterialSurface;
use crate::sim::{Integrator, Model, Tissue};
use crate::validate::continuum::tap::ContinuumTap;
use crate::validate::transient::{self as dynamic_reference, ReferenceTransient, Trajectory, Transient};

/// Largest displacement of the release shape, m (small: every model is near linear).
pub const RELEASE_AMPLITUDE_M: f64 = 5e-4;
/// Periods of the fundamental stepped in the release.
pub const RELEASE_PERIODS: f64 = 4.0;
/// Fewest steps of a release.
const MIN_RELEASE_STEPS: usize = 40;
/// Most steps of one run (a tiny explicit step on a stiff model).
pub const MAX_STEPS: usize = 400_000;

/// The FEM's dynamic reference of one object on the viewer's scene.
#[derive(Debug, Clone)]
pub struct References {
    /// Object label.
    pub object: String,
    /// The material.
    pub material: Material,
    /// The damping ratio of every transient.
    pub zeta: f64,
    /// The scene (clamp and load).
    pub scene: LoadCase,
    /// The FEM's fundamental on the scene, rad/s.
    pub fem_omega_1: f64,
    /// The FEM's lowest [`MODES`] natural frequencies on the scene, Hz (lumped masses).
    pub fem_modes_hz: Vec<f64>,
    /// The converged transients.
    pub transients: Vec<ReferenceTransient>,
    /// On the viewer's scene: the material's converged tap and surface compliance (the viewer's
    /// contact).
    pub material_tap: Option<(ContinuumTap, MaterialSurface)>,
}

impl References {
    /// The FEM's fundamental and converged transients of `material` on the viewer's 8^3 scene,
    /// damped by `zeta`.
    pub fn new(material: &Material, zeta: f64) -> anyhow::Result<Self> {
        Self::with_scene(material, zeta, dynamic_reference::view_scene(&Grid::paper()))
    }

    /// The same on another 8^3 `scene` (a clamp and a load, e.g. [`dynamic_reference::paper_scene`]):
    /// its step load and release (the probe tap belongs to the viewer's scene only), and its
    /// modes; the damping ratio stays set at the viewer scene's fundamental.
    pub fn with_scene(material: &Material, zeta: f64, scene: LoadCase) -> anyhow::Result<Self> {
        let grid = Grid::paper();
        if scene.load.len() != 3 * grid.num_nodes() {
            anyhow::bail!("scene {} is not on the viewer's {}^3 grid", scene.id, grid.n());
        }
        let fem = ModalModel::fem(&crate::mechanics::fem::FemModel::new(grid, material), material.density);
        let fem_modes_hz = hz(&fem.modes(&scene.fixed, MODES)?);
        let fem_omega_1 = crate::response::modal::scene_fundamental(&fem).map_err(|e| anyhow::anyhow!("{e}"))?;
        let is_view = scene.fixed == crate::response::linear::scene_fixed_dofs(&grid);
        let transients = Transient::ALL
            .iter()
            .filter(|&&t| is_view || t != Transient::ProbeTap)
            .map(|&t| dynamic_reference::converged(material, grid, &scene, zeta, t))
            .collect::<anyhow::Result<Vec<_>>>()?;
        let material_tap = if is_view {
            let dir = crate::io::cache_dir();
            let tap = crate::validate::continuum::cache::tap(material, zeta, dir.as_deref(), &mut |s| {
                crate::io::progress(&format!("the material's tap ({}): {s}", material.name));
            })?;
            let mut report = crate::sim::material_surface::stderr_report();
            let compliance = MaterialSurface::load_or_compute(material, dir.as_deref(), &mut |e| report.event(e))?;
            Some((tap, compliance))
        } else {
            None
        };
        Ok(Self {
            object: material.name.clone(),
            material: material.clone(),
            zeta,
            scene,
            fem_omega_1,
            fem_modes_hz,
            transients,
            material_tap,
        })
    }
}

/// How many of the lowest modes a report lists.
pub const MODES: usize = 6;

fn hz(modes: &[Mode]) -> Vec<f64> {
    modes.iter().map(|m| m.omega / (2.0 * std::f64::consts::PI)).collect()
}

/// One model, integrator and step, measured (`tissue-sim dynamics --json`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct DynamicReport {
    /// Object label.
    pub object: String,
    /// The model (`hex`, `shear`, `fem-linear`, `fem-corotational`).
    pub model: Model,
    /// `symplectic`, `implicit`, `prefactored` or `newmark`.
    pub integrator: Integrator,
    /// Time step, s.
    pub dt_s: f64,
    /// The damping ratio set at the fundamental (mass-proportional).
    pub damping_ratio_set: f64,
    /// The model's own damped fundamental period `2 pi / (omega_1 sqrt(1 - zeta^2))`, from its
    /// eigenvalues (`omega_1`: rest stiffness, lumped masses, the viewer's scene), s.
    pub modal_period_s: f64,
    /// The same for the FEM on the same mesh and scene, s.
    pub fem_period_s: f64,
    /// Period measured by time stepping (release from the fundamental's static shape), s.
    pub measured_period_s: f64,
    /// Damping ratio measured by time stepping.
    pub measured_damping_ratio: f64,
    /// The worst relative L2 error in time of the loaded face's displacement against the FEM's
    /// reference transients (the step load and the release, [`DynamicReport::transients`]) over
    /// their first 0.2 s.
    pub trajectory_error: f64,
    /// The relative L2 error in time of the force on the probe in the 20 ms tap, run in the
    /// viewer's simulation with its contact (the material's surface compliance and slow modes) and force readout, against the material's converged tap
    /// ([`crate::validate::continuum::tap`]); NaN off the viewer's scene.
    pub probe_tap_error: f64,
    /// The same with the model's own surface nodes as contact, against the same-mesh FEM's
    /// converged tap (the `probe_tap` transient).
    pub probe_tap_own_mesh_error: f64,
    /// `|measured / modal period - 1|`: the integrator's period error.
    pub period_error: f64,
    /// `|measured - set damping ratio|`, in units of critical: the integrator's damping error.
    pub damping_error: f64,
    /// `|measured / FEM period - 1|`: model and integrator together against the FEM.
    pub fem_period_error: f64,
    /// What the integrator's closed form predicts at the model's fundamental (single mode).
    pub predicted: Option<ModeMotion>,
    /// Relative residual of the two-term recurrence fit to the released motion (0 for a pure
    /// linear mode).
    pub fit_residual: f64,
    /// The model's undamped fundamental period `2 pi / omega_1`, s.
    pub modal_undamped_period_s: f64,
    /// The scene (`view_top_shear_x`, or a paper case id): its clamp and load give the modes and
    /// the trajectories; the period and damping are measured on the viewer's scene, where the
    /// ratio is set.
    pub scene: String,
    /// The model's lowest [`MODES`] natural frequencies on the scene's clamp, Hz (lumped masses).
    pub modes_hz: Vec<f64>,
    /// The FEM's, Hz.
    pub fem_modes_hz: Vec<f64>,
    /// Each transient's trajectory error.
    pub transients: Vec<TransientError>,
}

/// The trajectory error of one transient.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TransientError {
    /// `step_load`, `release` or `probe_tap`.
    pub transient: Transient,
    /// Relative L2 in time of the loaded face's displacement (of the probe force for the tap);
    /// infinite when the blow-up guard stopped the run.
    pub error: f64,
    /// The reference's converged Newmark step, s.
    pub reference_step_s: f64,
}

/// What to measure.
#[derive(Debug, Clone, Copy)]
pub struct Configuration {
    /// The model.
    pub model: Model,
    /// Lattice parameters (the shipped tissue where `None`).
    pub params: Option<MsmParams>,
    /// Integrator.
    pub integrator: Integrator,
    /// Time step, s.
    pub dt: f64,
}

/// The model's rest stiffness and masses.
pub fn modal_model(material: &Material, model: Model, params: Option<MsmParams>) -> anyhow::Result<ModalModel> {
    let grid = Grid::paper();
    match model {
        Model::Lattice(t) => {
            let p = match params {
                Some(p) => p,
                None => crate::sim::shipped::tissue_params(material, t)?,
            };
            ModalModel::lattice(&MsmModel::new(grid, p, material.density)?).map_err(|e| anyhow::anyhow!("{e}"))
        }
        Model::Fem(_) => Ok(ModalModel::fem(&crate::mechanics::fem::FemModel::new(grid, material), material.density)),
    }
}

/// Measures `config` against `refs` (its object and damping ratio).
pub fn measure(refs: &References, config: Configuration) -> anyhow::Result<DynamicReport> {
    if !config.model.takes_damping_ratio() {
        anyhow::bail!("{}", crate::response::modal::AXIS_HAS_NO_MODES);
    }
    let material = &refs.material;
    let zeta = refs.zeta;
    let modal = modal_model(material, config.model, config.params)?;
    let fixed = crate::response::linear::scene_fixed_dofs(&Grid::paper());
    let mode = modal.fundamental(&fixed)?;
    let modes = modal.modes(&refs.scene.fixed, MODES)?;
    let mut tissue = config.model.build(material, config.params, zeta)?;
    let Damping::Ratio { omega_1, .. } = tissue.damping() else {
        anyhow::bail!("the model is not damped by a ratio");
    };
    let (motion, fit_residual) = release(tissue.as_mut(), &modal, &mode, config)?;
    let damped = |w: f64| single_mode::exact(w, 2.0 * zeta * w).period_s;
    let modal_period_s = damped(omega_1);
    let fem_period_s = damped(refs.fem_omega_1);
    let mut transients = Vec::new();
    for r in &refs.transients {
        let run = match r.transient {
            Transient::ProbeTap => crate::validate::probe::tap::run(
                config.model.build(material, config.params, zeta)?,
                config.integrator,
                config.dt,
                None,
            )?,
            t => Some(trajectory(tissue.as_mut(), &modal, &refs.scene, t, config)?),
        };
        // A run the blow-up guard had to stop has no trajectory: an infinite error.
        let error = run.map_or(f64::INFINITY, |run| run.relative_error(&r.trajectory));
        transients.push(TransientError { transient: r.transient, error, reference_step_s: r.trajectory.dt });
    }
    let worst = |tap: bool| {
        transients
            .iter()
            .filter(|t| (t.transient == Transient::ProbeTap) == tap)
            .map(|t| t.error)
            .fold(0.0, |a: f64, b| if b.is_nan() { b } else { a.max(b) })
    };
    let (trajectory_error, probe_tap_own_mesh_error) = (worst(false), worst(true));
    let probe_tap_error = match &refs.material_tap {
        Some((tap, surface)) => {
            let tissue = config.model.build(material, config.params, zeta)?;
            crate::validate::probe::tap::run(tissue, config.integrator, config.dt, Some(surface))?
                .map_or(f64::INFINITY, |run| run.relative_error(&tap.trajectory()))
        }
        None => f64::NAN,
    };
    Ok(DynamicReport {
        object: refs.object.clone(),
        model: config.model,
        integrator: config.integrator,
        dt_s: config.dt,
        damping_ratio_set: zeta,
        modal_period_s,
        fem_period_s,
        measured_period_s: motion.period_s,
        measured_damping_ratio: motion.damping_ratio,
        trajectory_error,
        probe_tap_error,
        probe_tap_own_mesh_error,
        period_error: single_mode::period_error(motion.period_s, modal_period_s),
        damping_error: (motion.damping_ratio - zeta).abs(),
        fem_period_error: single_mode::period_error(motion.period_s, fem_period_s),
        predicted: single_mode::discrete(config.integrator.scheme(), omega_1, 2.0 * zeta * omega_1, config.dt),
        fit_residual,
        modal_undamped_period_s: 2.0 * std::f64::consts::PI / omega_1,
        scene: refs.scene.id.clone(),
        modes_hz: hz(&modes),
        fem_modes_hz: refs.fem_modes_hz.clone(),
        transients,
    })
}

fn steps_for(duration: f64, dt: f64) -> anyhow::Result<usize> {
    let n = (duration / dt).round();
    if !(n.is_finite() && n <= MAX_STEPS as f64) {
        anyhow::bail!("{duration} s at dt = {dt} s is more than {MAX_STEPS} steps");
    }
    Ok(n.max(1.0) as usize)
}

/// Puts the tissue at rest at `rest + u` with `case`'s clamp and loads.
fn start(tissue: &mut dyn Tissue, case: &LoadCase, u: &[f64]) {
    tissue.apply_case(case);
    let grid = tissue.grid();
    let (x, v) = tissue.x_v_mut();
    for p in 0..grid.num_nodes() {
        let r = grid.position(p);
        for c in 0..3 {
            x[c][p] = r[c] + u[3 * p + c];
            v[c][p] = 0.0;
        }
    }
}

fn step(tissue: &mut dyn Tissue, config: Configuration) -> anyhow::Result<()> {
    tissue.step(config.integrator, config.dt).map_err(|e| anyhow::anyhow!("{e}"))
}

/// The release of the fundamental: its measured motion and the recurrence fit's residual.
fn release(
    tissue: &mut dyn Tissue,
    modal: &ModalModel,
    mode: &Mode,
    config: Configuration,
) -> anyhow::Result<(ModeMotion, f64)> {
    let grid = tissue.grid();
    let clamp = LoadCase::bottom_clamp(&grid, "view");
    let peak = mode.shape.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let scale = RELEASE_AMPLITUDE_M / peak;
    let u: Vec<f64> = mode.shape.iter().map(|s| s * scale).collect();
    start(tissue, &clamp, &u);
    let mass = modal.dof_masses(&clamp.fixed);
    let weights: Vec<f64> = mode.shape.iter().zip(&mass).map(|(s, m)| s * m / scale).collect();
    let period = 2.0 * std::f64::consts::PI / mode.omega;
    let steps = steps_for(RELEASE_PERIODS * period, config.dt)?.max(MIN_RELEASE_STEPS);
    let coordinate = |t: &dyn Tissue| -> f64 {
        let x = t.x();
        (0..grid.num_nodes())
            .map(|p| {
                let r = grid.position(p);
                (0..3).map(|c| weights[3 * p + c] * (x[c][p] - r[c])).sum::<f64>()
            })
            .sum()
    };
    let mut q = Vec::with_capacity(steps + 1);
    q.push(coordinate(tissue));
    for _ in 0..steps {
        step(tissue, config)?;
        q.push(coordinate(tissue));
    }
    Ok(single_mode::fit_recurrence(&q, config.dt))
}

/// The model's run of `transient` on `scene`: from rest with the load (step), or from its own
/// static shape (rest stiffness) with the load removed (release), sampled on the loaded dofs.
fn trajectory(
    tissue: &mut dyn Tissue,
    modal: &ModalModel,
    scene: &LoadCase,
    transient: Transient,
    config: Configuration,
) -> anyhow::Result<Trajectory> {
    let dofs = dynamic_reference::loaded_dofs(scene);
    let n = scene.load.len();
    match transient {
        Transient::StepLoad | Transient::ProbeTap => start(tissue, scene, &vec![0.0; n]),
        Transient::Release => {
            let u = modal.static_shape(scene)?;
            let mut unloaded = scene.clone();
            unloaded.load.fill(0.0);
            start(tissue, &unloaded, &u);
        }
    }
    let grid = tissue.grid();
    let sample = |t: &dyn Tissue| -> Vec<f64> {
        let x = t.x();
        dofs.iter().map(|&d| x[d % 3][d / 3] - grid.position(d / 3)[d % 3]).collect()
    };
    let steps = steps_for(dynamic_reference::DURATION_S, config.dt)?;
    let mut samples = Vec::with_capacity(steps + 1);
    samples.push(sample(tissue));
    for _ in 0..steps {
        step(tissue, config)?;
        samples.push(sample(tissue));
    }
    Ok(Trajectory { dt: config.dt, samples })
}

impl DynamicReport {
    /// The report as text (`tissue-sim dynamics`), with the step policy's `note`, if any.
    pub fn to_text(&self, note: Option<&str>) -> String {
        let r = self;
        let mut t = format!(
            "Dynamics: object {}, model {}, {} at dt = {} s, damping ratio {} at the fundamental (mass-proportional, \
             the viewer's scene: face z = 0 clamped); trajectories and modes: {}\n",
            r.object,
            r.model,
            r.integrator,
            crate::io::num(r.dt_s),
            r.damping_ratio_set,
            r.scene
        );
        if let Some(n) = note {
            t += &format!("note: {n}\n");
        }
        let list = crate::validate::touch::score::frequency_list;
        t += &format!("lowest modes, Hz: model {}; FEM {}\n", list(&r.modes_hz), list(&r.fem_modes_hz));
        t += &format!(
            "fundamental period: measured {:.4} ms, own modal {:.4} ms (error {:.3} %), FEM {:.4} ms (error {:.3} %)\n",
            1e3 * r.measured_period_s,
            1e3 * r.modal_period_s,
            100.0 * r.period_error,
            1e3 * r.fem_period_s,
            100.0 * r.fem_period_error
        );
        t += &format!(
            "damping ratio: measured {:.4}, set {:.4} (error {:.3} % of critical)\n",
            r.measured_damping_ratio,
            r.damping_ratio_set,
            100.0 * r.damping_error
        );
        if let Some(p) = r.predicted {
            t += &format!(
                "closed form of {} on the fundamental: period {:.4} ms, damping ratio {:.4}\n",
                r.integrator,
                1e3 * p.period_s,
                p.damping_ratio
            );
        }
        for e in &r.transients {
            let what =
                if e.transient == Transient::ProbeTap { "probe force, the model's nodes" } else { "loaded face" };
            let error = if e.error.is_finite() {
                format!("{:.3} %", 100.0 * e.error)
            } else {
                "not measured (the step is too long to resolve it)".to_owned()
            };
            t += &format!(
                "trajectory error ({what}), {}: {error} (FEM reference: Newmark, converged at {} s)\n",
                e.transient.name(),
                crate::io::num(e.reference_step_s)
            );
        }
        if r.probe_tap_error.is_finite() {
            t += &format!(
                "probe force on the tap, the viewer's contact (the material's surface compliance and slow \
                 modes): {:.3} % against the material's converged tap (relative L2 in time)\n",
                100.0 * r.probe_tap_error
            );
        }
        t
    }
}
