//! Layer 5, calibration of the mass-spring model against the FEM reference (the paper's Sections
//! III-IV): the hybrid GA+SA, and the pure GA and pure SA baselines of its Figs. 5-6; the L-BFGS
//! [`polish`]; the load-free stiffness [`fit`]. May use: validate, sim, response, mechanics, io.
//!
//! Built for a background thread: [`calibrate`] reports every generation through a callback
//! (best cost, mean and standard deviation of fitness, evaluations so far), checks a cancel flag
//! once per generation, and returns [`CalibrationResult`] whose `params` can be applied to a
//! running model. It is seeded and deterministic on any number of threads.
//!
//! Damping: a static equilibrium does not depend on `d`, so the static cost cannot identify it.
//! In static mode the result says so (`d_identified: false`) and sets `d` by a stated criterion:
//! critical damping `d = 2 m omega_min` of the slowest mode of the calibrated model, clamped as
//! in the benchmark (the smallest over the three clamped faces, in the mirror-symmetric subspace
//! the benchmark's loads excite; see [`critical`]).
//!
//! Settings that cannot inform the cost (a case set the cost mode cannot use, a grid on which no
//! training press touches a node) are refused before any work ([`check_setup`]), and the polish
//! stays inside the search box the result reports ([`PolishReport::at_bound`]).
//!
//! [`search`]: GA, SA and the hybrid; [`genes`]: the chromosome and its bounds; [`cost`]: eq. 1 and
//! the touch and press costs; [`transient`]: the transient cost that identifies `d`.

pub mod cost;
pub mod critical;
pub mod fit;
pub mod genes;
pub mod polish;
pub mod search;
pub mod transient;

use std::sync::atomic::AtomicBool;
use std::time::Instant;

pub use crate::sim::shipped::CaseSet;
pub use cost::{CostError, Problem, Workspace};
pub use genes::GeneSpace;

use crate::mechanics::grid::Grid;
use crate::mechanics::msm::{MsmParams, Topology};

/// The search method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// The load-free baseline: the non-negative least-squares fit of the lattice's stiffness
    /// matrix to the FEM's ([`crate::calibrate::fit::stiffness_fit`]); no search, no load case.
    #[serde(rename = "stiffness-fit")]
    StiffnessFit,
    /// GA with Metropolis screening of crossover (XSA) and mutation (MSA): the paper's method.
    Hybrid,
    /// Plain GA, same operators and settings, no screening.
    Ga,
    /// Simulated annealing alone: `sa_iterations` moves at each of `generations` temperatures.
    Sa,
}

/// What the cost compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CostMode {
    /// Static equilibria (the paper's cost; `d` is not identified).
    Static,
    /// The state a fixed time after a step load from rest (see [`transient`]); identifies `d`.
    Transient,
}

/// What a calibration's cost measures and its unit (`"m"` or `""` for a pure number), by its
/// training cases and cost mode: the one home of the words the command line and the viewer print.
pub fn cost_meaning(cases: CaseSet, mode: CostMode) -> (&'static str, &'static str) {
    match (mode, cases) {
        (CostMode::Transient, _) => (
            "m",
            "the paper's eq. 1 a fixed time after a step load from rest: the sum over the nine clamped face \
             loads and every node of the distance between the lattice's node and the FEM's static answer",
        ),
        (CostMode::Static, CaseSet::Paper) => (
            "m",
            "the paper's eq. 1: the sum over the nine clamped face loads and every node of the distance \
             between the lattice's node and the FEM's, in static equilibrium",
        ),
        (CostMode::Static, CaseSet::Touch) => (
            "",
            "the sum over the touch benchmark's training cases of (the lattice's response / the FEM's - 1)^2, \
             a pure number",
        ),
        (CostMode::Static, CaseSet::Both) => (
            "",
            "the touch cost plus the paper's eq. 1 divided by the sum of the FEM's node displacements (the cost of \
             no displacement), a pure number",
        ),
        (CostMode::Static, CaseSet::Presses) => (
            "",
            "the mean over the material's training presses of (the lattice's force with node contact / the \
             material's - 1)^2, a pure number",
        ),
    }
}

impl Method {
    /// The name used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Method::StiffnessFit => "stiffness-fit",
            Method::Hybrid => "hybrid",
            Method::Ga => "ga",
            Method::Sa => "sa",
        }
    }
}

/// The gradient polish after the search ([`polish`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PolishReport {
    /// Objective at the search's best.
    pub start_cost: f64,
    /// Objective after the polish.
    pub cost: f64,
    /// L-BFGS iterations.
    pub iterations: u64,
    /// The stiffness genes that end on a bound of the search box, as `NAME=lo` or `NAME=hi`. The
    /// polish stays inside the box ([`polish::polish_within`]), so a bound listed here binds: the
    /// box may not hold the optimum (widen it with `--bound`).
    #[serde(default)]
    pub at_bound: Vec<String>,
}

/// Largest `population x generations` of one run (the paper's is 5000).
pub const MAX_EVALUATIONS: usize = 2_000_000;

/// Settings of a calibration run (defaults: the paper's).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Settings {
    /// Search method.
    pub method: Method,
    /// Random seed.
    pub seed: u64,
    /// Population size (GA and hybrid).
    pub population: usize,
    /// Generations (GA, hybrid) or temperature steps (SA).
    pub generations: usize,
    /// Probability that a chromosome is mutated.
    pub mutation: f64,
    /// Probability that a selected pair crosses over.
    pub crossover: f64,
    /// Moves per temperature of the pure SA.
    pub sa_iterations: usize,
    /// Final temperature as a fraction of the initial one.
    pub t_final_ratio: f64,
    /// Cost mode.
    pub cost: CostMode,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            method: Method::Hybrid,
            seed: 1,
            population: 50,
            generations: 100,
            mutation: 0.2,
            crossover: 0.8,
            sa_iterations: 50,
            t_final_ratio: 1e-6,
            cost: CostMode::Static,
        }
    }
}

/// The paper's search: 50 individuals, 100 generations (temperature steps for SA).
pub const PAPER_SEARCH: (usize, usize) = (50, 100);

/// The search where the gradient polish follows it (the static cost of the shear and hex
/// lattices): 10 individuals, 10 generations. The polish takes it to the optimum the paper's
/// search reaches (the same cost to 1e-12, docs/calibration.md, Speed) in a quarter of the time.
pub const POLISHED_SEARCH: (usize, usize) = (10, 10);

impl Settings {
    /// The default search (population, generations) for `topology` under `cost`:
    /// [`POLISHED_SEARCH`] where the polish runs after it, else the paper's [`PAPER_SEARCH`] (the
    /// axis lattice, whose cost is closed-form, and the transient cost, which has no polish).
    pub fn default_search(topology: Topology, cost: CostMode) -> (usize, usize) {
        if cost == CostMode::Static && topology != Topology::Axis { POLISHED_SEARCH } else { PAPER_SEARCH }
    }

    /// Checks ranges, naming the setting at fault.
    pub fn validate(&self) -> Result<(), String> {
        if self.population < 2 || self.population > 100_000 {
            return Err(format!("population must be in 2..=100000, got {}", self.population));
        }
        if self.generations == 0 || self.generations > 1_000_000 {
            return Err(format!("generations must be in 1..=1000000, got {}", self.generations));
        }
        if self.population * self.generations > MAX_EVALUATIONS {
            return Err(format!(
                "population x generations = {} is above the bound of {MAX_EVALUATIONS} evaluations per run",
                self.population * self.generations
            ));
        }
        for (name, p) in [("mutation", self.mutation), ("crossover", self.crossover)] {
            if !(0.0..=1.0).contains(&p) {
                return Err(format!("{name} probability must be in [0, 1], got {}", crate::io::num(p)));
            }
        }
        if self.sa_iterations == 0 {
            return Err("sa_iterations must be at least 1".into());
        }
        if !(self.t_final_ratio > 0.0 && self.t_final_ratio < 1.0) {
            return Err(format!("t_final_ratio must be in (0, 1), got {}", crate::io::num(self.t_final_ratio)));
        }
        Ok(())
    }
}

/// Progress of one generation (one temperature step for SA).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GenerationStats {
    /// Generation index, 0 = the initial population.
    pub generation: usize,
    /// Best cost found so far, metres.
    pub best_cost: f64,
    /// Best cost in the current population (SA: among this temperature's states).
    pub population_best_cost: f64,
    /// Mean fitness (1/cost) of the population (SA: of this temperature's states).
    pub mean_fitness: f64,
    /// Standard deviation of the fitness.
    pub std_fitness: f64,
    /// Cost evaluations so far.
    pub evaluations: u64,
    /// Annealing temperature (cost units).
    pub temperature: f64,
}

/// The outcome of a calibration, in the spec's JSON layout (plus extra keys).
#[derive(Debug, Clone, serde::Serialize)]
pub struct CalibrationResult {
    /// Object label.
    pub object: String,
    /// Search method.
    pub method: Method,
    /// Seed.
    pub seed: u64,
    /// Population size.
    pub population: usize,
    /// Generations.
    pub generations: usize,
    /// `axis` or `shear`.
    pub model: Topology,
    /// The calibrated parameters (N/m, N s/m).
    pub params: MsmParams,
    /// Their cost (eq. 1), metres.
    pub cost: f64,
    /// Cost evaluations.
    pub evaluations: u64,
    /// Wall time, seconds.
    pub wall_s: f64,
    /// Per generation.
    pub history: Vec<GenerationStats>,
    /// Cost mode.
    pub cost_mode: CostMode,
    /// Whether the data identified `d` (false for a static cost).
    pub d_identified: bool,
    /// How `d` was set.
    pub d_note: String,
    /// The search box.
    pub bounds: GeneSpace,
    /// All settings.
    pub settings: Settings,
    /// Nodes per axis.
    pub nodes_per_axis: usize,
    /// True when cancelled before the last generation (the best so far is reported).
    pub cancelled: bool,
    /// The training cases of the cost.
    pub cases: CaseSet,
    /// The gradient polish after the search, where one ran (static cost, shear and hex lattices).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub polish: Option<PolishReport>,
}

/// The search of `settings.method`, then (static cost, shear and hex lattices) the polish.
fn search_and_polish(
    problem: &Problem,
    space: &GeneSpace,
    settings: &Settings,
    cancel: &AtomicBool,
    on_generation: &mut dyn FnMut(&GenerationStats),
) -> Result<(MsmParams, search::SearchOutcome, Option<PolishReport>), CalibrationError> {
    let mut outcome = if settings.method == Method::Sa {
        search::annealing(problem, space, settings, cancel, on_generation)
    } else {
        search::genetic(problem, space, settings, cancel, on_generation)
    };
    let mut params = space.params(&outcome.best);
    let mut polish = None;
    if problem.topology != Topology::Axis && settings.cost == CostMode::Static && !outcome.cancelled {
        let ti = problem.material.is_transversely_isotropic();
        let mut ws = Workspace::default();
        let mut objective = |p: &MsmParams| problem.objective_gradient(p, &mut ws).map_err(|e| e.to_string());
        let p = polish::polish_within(&params, ti, &polish_box(space), &mut objective).map_err(CostError::Polish)?;
        if p.cost < outcome.best_cost {
            params = p.params;
            outcome.best_cost = p.cost;
        }
        polish = Some(PolishReport {
            start_cost: p.start_cost,
            cost: p.cost,
            iterations: p.iterations,
            at_bound: at_bound(space, &params),
        });
    }
    Ok((params, outcome, polish))
}

/// The box of each stiffness group ([`crate::response::linear::GROUP_NAMES`]) in `space`; a
/// group without a gene (a tied copy, or one the lattice lacks) gets the whole stiffness range.
fn polish_box(space: &GeneSpace) -> [(f64, f64); 7] {
    std::array::from_fn(|g| {
        let name = crate::response::linear::GROUP_NAMES[g];
        space
            .names
            .iter()
            .position(|n| n == name)
            .map_or(crate::mechanics::msm::model::STIFFNESS_RANGE, |i| (space.lo[i], space.hi[i]))
    })
}

/// The stiffness genes of `params` on a bound of `space`'s box (within [`polish::ON_BOUND`] in
/// `ln k`; a bound is taken within the stiffness range, as the polish takes it), as `NAME=lo` or
/// `NAME=hi` (`d` is not a stiffness).
fn at_bound(space: &GeneSpace, params: &MsmParams) -> Vec<String> {
    let theta = crate::response::linear::group_values(params);
    let bounds = polish_box(space);
    space
        .names
        .iter()
        .filter_map(|name| {
            let g = crate::response::linear::GROUP_NAMES.iter().position(|n| n == name)?;
            let (lo, hi) = polish::effective_bounds(bounds[g]);
            let v = theta[g].ln();
            if v - lo.ln() <= polish::ON_BOUND {
                Some(format!("{name}=lo"))
            } else if hi.ln() - v <= polish::ON_BOUND {
                Some(format!("{name}=hi"))
            } else {
                None
            }
        })
        .collect()
}

/// Errors of a calibration.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    /// A setting is out of range.
    #[error("invalid calibration setting: {0}")]
    Settings(String),
    /// A cost evaluation failed.
    #[error(transparent)]
    Cost(#[from] CostError),
}

/// Refuses training cases that cannot inform the static cost of `topology` on `grid`, before
/// any reference is computed: the touch cases and the presses on the axis-spring lattice (it has
/// no shear stiffness at rest), and the presses on a grid where no training press touches a node
/// (every press force is then zero whatever the parameters, and the cost is 1).
pub fn check_cases(set: CaseSet, topology: Topology, grid: Grid) -> Result<(), CostError> {
    if set != CaseSet::Paper && topology == Topology::Axis {
        let what = if set == CaseSet::Presses { "the presses" } else { "the touch cases" };
        return Err(CostError::Touch(format!(
            "the axis-spring lattice has no shear stiffness at rest, so {what} cannot train it"
        )));
    }
    if set == CaseSet::Presses && touching_presses(grid) == 0 {
        let n = grid.n();
        let finer = (n + 1..=crate::mechanics::grid::MAX_NODES_PER_AXIS)
            .find(|&m| Grid::new(m).is_ok_and(|g| touching_presses(g) > 0))
            .map_or_else(String::new, |m| format!("; use a finer grid, e.g. --nodes {m}"));
        return Err(CostError::Uninformative(format!(
            "no training press touches a node of the {n}^3 grid (each sphere passes between the nodes), so the \
             press cost cannot depend on the parameters{finer}"
        )));
    }
    Ok(())
}

/// How many of the training presses on the top face ([`crate::validate::probe::presses`]) touch a node of
/// `grid`: a free surface node inside the sphere at rest, which is what starts the node contact
/// of [`crate::response::linear::SceneSolver::probe`]. A press that touches none has no contact
/// and no force, whatever the stiffness.
pub fn touching_presses(grid: Grid) -> usize {
    let fixed = crate::response::linear::scene_fixed_dofs(&grid);
    crate::validate::probe::presses::press_cases()
        .iter()
        .filter(|c| c.set == crate::validate::touch::Set::Training && c.on_top_face())
        .filter(|c| {
            let geometry = crate::response::linear::sphere_geometry(&grid, c.press.centre(), c.press.radius);
            (0..grid.num_nodes()).any(|p| !fixed[3 * p] && grid.on_boundary(p) && geometry[p].1 > 0.0)
        })
        .count()
}

/// Refuses, before any work, a calibration whose cost its settings cannot inform: the training
/// cases of [`check_cases`]; the transient cost with training cases other than the paper's (it
/// integrates only the nine clamped face loads, so it would train on those and name others); and
/// the load-free stiffness fit with the transient cost (it identifies no damping).
pub fn check_setup(settings: &Settings, cases: CaseSet, topology: Topology, grid: Grid) -> Result<(), CostError> {
    if settings.cost == CostMode::Transient && cases != CaseSet::Paper {
        return Err(CostError::Uninformative(format!(
            "--cost transient cannot use --cases {}: the transient cost integrates only the paper's nine clamped \
             face loads (use --cases paper, or --cost static)",
            cases.name()
        )));
    }
    if settings.cost == CostMode::Transient && settings.method == Method::StiffnessFit {
        return Err(CostError::Uninformative(
            "--method stiffness-fit cannot use --cost transient: the fit is load-free and identifies no damping \
             (use --cost static, or a search method)"
                .into(),
        ));
    }
    check_cases(cases, topology, grid)
}

/// Runs a calibration of `problem` within `space`. `on_generation` is called once per generation
/// on the calling thread; setting `cancel` stops the run within one generation. Settings the cost
/// cannot use are refused before the search ([`check_setup`]).
pub fn calibrate(
    problem: &Problem,
    space: &GeneSpace,
    settings: &Settings,
    cancel: &AtomicBool,
    on_generation: &mut dyn FnMut(&GenerationStats),
) -> Result<CalibrationResult, CalibrationError> {
    settings.validate().map_err(CalibrationError::Settings)?;
    check_setup(settings, problem.case_set, problem.topology, problem.grid)?;
    let start = Instant::now();
    let (mut params, outcome, polish) = match settings.method {
        Method::StiffnessFit => {
            let fem = crate::mechanics::fem::FemModel::new(problem.grid, &problem.material);
            let ti = problem.material.is_transversely_isotropic();
            let (params, _) = crate::calibrate::fit::stiffness_fit(&fem, problem.topology, ti);
            let cost = problem.objective(&params, &mut Workspace::default())?;
            let outcome = search::SearchOutcome {
                best: Vec::new(),
                best_cost: cost,
                history: Vec::new(),
                evaluations: 1,
                cancelled: false,
            };
            (params, outcome, None)
        }
        Method::Hybrid | Method::Ga | Method::Sa => search_and_polish(problem, space, settings, cancel, on_generation)?,
    };
    let (d_crit, omega) = critical::critical_damping(&problem.model(&params).map_err(CostError::from)?)?;
    let d_identified = settings.cost == CostMode::Transient;
    let d_note = if d_identified {
        format!(
            "identified by the transient cost ({} ms after a step load, {} backward-Euler steps); \
             critical damping of the slowest benchmark-symmetric mode would be {d_crit:.6} N s/m",
            transient::TRANSIENT_TIME_S * 1e3,
            transient::TRANSIENT_STEPS
        )
    } else {
        params.d = d_crit;
        format!(
            "not identified by the static cost; set to critical damping 2 m omega_min of the slowest \
             benchmark-symmetric mode (omega_min = {omega:.6} rad/s)"
        )
    };
    Ok(CalibrationResult {
        object: problem.material.name.clone(),
        method: settings.method,
        seed: settings.seed,
        population: settings.population,
        generations: settings.generations,
        model: problem.topology,
        params,
        cost: outcome.best_cost,
        evaluations: outcome.evaluations,
        wall_s: start.elapsed().as_secs_f64(),
        history: outcome.history,
        cost_mode: settings.cost,
        d_identified,
        d_note,
        bounds: space.clone(),
        settings: settings.clone(),
        nodes_per_axis: problem.grid.n(),
        cancelled: outcome.cancelled,
        cases: problem.case_set,
        polish,
    })
}
