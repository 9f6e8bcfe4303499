//! The command line: one subcommand per computation, JSON formats of `shared/spec/benchmark.md`.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context as _, bail};
use clap::{Args, Parser, Subcommand};

use crate::calibrate::{CaseSet, CostMode, GeneSpace, Method, Problem, Settings, calibrate};
use crate::io::{read_json, write_atomic, write_json_atomic};
use crate::mechanics::cases::{Bc, benchmark_cases};
use crate::mechanics::displacement_file::{CaseRecord, DisplacementFile};
use crate::mechanics::fem::FemModel;
use crate::mechanics::fem::dynamics::Formulation;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::msm::{MsmModel, MsmParams, Topology, statics};
use crate::render::scene::ColourMode;
use crate::sim::Integrator;
use crate::study::choose::Metric;
use crate::validate::accuracy::{case_errors, cost, format_table};

/// Implements [`clap::ValueEnum`] for a core enum, so that clap stays in the command-line layer:
/// each variant with its command-line name and its help (the variant's doc, as clap's derive
/// showed it).
macro_rules! value_enum {
    ($ty:ident { $($variant:ident => $name:literal, $help:literal;)+ }) => {
        impl clap::ValueEnum for $ty {
            fn value_variants<'a>() -> &'a [Self] {
                &[$($ty::$variant),+]
            }

            fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
                Some(match self {
                    $($ty::$variant => clap::builder::PossibleValue::new($name).help($help),)+
                })
            }
        }
    };
}

value_enum!(Formulation {
    Linear => "linear", "Small-strain linear elasticity, `f = -K u`";
    Corotational => "corotational", "Corotational: linear elasticity in each element's rotated frame";
});
value_enum!(Bc {
    Clamped => "clamped", "Face `x_a = 0` fully fixed, equal nodal forces `F / n^2` on face `x_a = L`";
    Patch => "patch", "Roller supports removing rigid motion only, consistent nodal loads of a uniform traction";
});
value_enum!(Topology {
    Axis => "axis", "The paper's model: axis-aligned structural springs only (no shear stiffness)";
    Shear => "shear", "Axis springs plus both diagonals of every lattice square, one stiffness per plane";
    Hex => "hex",
        "The springs of every hex element: its 12 edges, 12 face diagonals and 4 body diagonals, one stiffness per \
         family group (`k1..k3`, `c12..c23`, `b`). A spring shared by several elements gets each element's share, so \
         springs on the surface are softer than inside (an edge spring on a face has half, on a cube edge a quarter of \
         an interior one's stiffness). Calibrated, it is the most accurate lattice here: see the `reproduce` report";
});
value_enum!(Method {
    Hybrid => "hybrid", "GA with Metropolis screening of crossover (XSA) and mutation (MSA): the paper's method";
    Ga => "ga", "Plain GA, same operators and settings, no screening";
    Sa => "sa", "Simulated annealing alone: `sa_iterations` moves at each of `generations` temperatures";
    StiffnessFit => "stiffness-fit", "Load-free baseline: non-negative least-squares fit of the lattice's stiffness matrix to the FEM's";
});
value_enum!(CaseSet {
    Paper => "paper", "The paper's nine clamped face loads (eq. 1)";
    Touch => "touch", "The touch benchmark's training cases (point loads, top shear, probe), then an L-BFGS polish";
    Both => "both", "The touch cost plus the paper's cost relative to the FEM's displacements";
});
value_enum!(CostMode {
    Static => "static", "Static equilibria (the paper's cost; `d` is not identified)";
    Transient => "transient", "The state a fixed time after a step load from rest (see [`transient`]); identifies `d`";
});
value_enum!(ColourMode {
    None => "none", "Plain shading";
    Displacement => "displacement", "Displacement magnitude";
    Error => "error", "Distance between the MSM and the FEM answer of the case";
});
value_enum!(Integrator {
    Symplectic => "symplectic", "Symplectic (semi-implicit) Euler: cheap, stable below a critical time step";
    Implicit => "implicit", "Linearised backward Euler with the tangent of every step (lattices only)";
    Prefactored => "prefactored", "Linearised backward Euler with the rest tangent factorised once";
});
value_enum!(Metric {
    Max => "max", "The worst node (the default: a budget holds everywhere)";
    Avg => "avg", "The average over nodes (the paper's headline figure)";
});

/// tissue-sim: anisotropic soft-tissue cube, FEM reference and calibrated mass-spring model.
#[derive(Debug, Parser)]
#[command(name = "tissue-sim", version, about, long_about = None)]
pub struct Cli {
    /// What to compute; without one, opens the interactive viewer.
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
#[allow(missing_docs)] // flattened argument groups document their own fields
pub enum Command {
    /// Linear static FEM reference: the 9 clamped or 9 patch cases, node displacements as JSON.
    Fem {
        #[command(flatten)]
        object: ObjectArgs,
        /// Boundary conditions.
        #[arg(long, value_enum, default_value = "clamped")]
        bc: Bc,
        #[command(flatten)]
        grid: GridArgs,
        /// Output JSON file.
        #[arg(long)]
        out: PathBuf,
    },
    /// Static MSM equilibrium of the 9 clamped cases, node displacements as JSON.
    Msm {
        #[command(flatten)]
        object: ObjectArgs,
        #[command(flatten)]
        params: ParamArgs,
        #[command(flatten)]
        grid: GridArgs,
        /// Output JSON file.
        #[arg(long)]
        out: PathBuf,
    },
    /// The paper's Table IV/V: average and maximum nodal MSM-vs-FEM error, % of h, per case.
    Errors {
        #[command(flatten)]
        object: ObjectArgs,
        #[command(flatten)]
        params: ParamArgs,
        /// Read the parameters (and the object, unless given) from a calibration result JSON.
        #[arg(long = "params", value_name = "FILE.json", conflicts_with_all = ["k1", "k2", "k3", "d", "c12", "c13", "c23", "b"])]
        params_file: Option<PathBuf>,
        #[command(flatten)]
        grid: GridArgs,
        /// Print JSON instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Calibrate the MSM against the FEM reference with the paper's GA+SA (or pure GA / SA).
    Calibrate(CalibrateArgs),
    /// Regenerate the paper's Tables III-V and Figs. 5-6 (report.md, SVG plots, data) in DIR.
    Reproduce {
        /// Output directory (created if missing).
        #[arg(long)]
        out: PathBuf,
        /// Seeds per method and object.
        #[arg(long, default_value_t = 10, allow_hyphen_values = true, value_parser = clap::value_parser!(u64).range(1..=1000))]
        seeds: u64,
        /// Skip the richer lattices' calibrations (shear and hex, about 55 s per object).
        #[arg(long)]
        no_shear: bool,
    },
    /// Speed against accuracy: every model x resolution x integrator (chart.csv, chart.svg with the
    /// Pareto front) and the explicit stability study (stability.csv, stability.svg), with chart.md, in DIR.
    Chart {
        /// Output directory (created if missing).
        #[arg(long)]
        out: PathBuf,
        /// Objects to chart.
        #[arg(long, value_delimiter = ',', default_value = "A,B")]
        objects: Vec<String>,
        /// Resolutions, nodes per axis (2..=32).
        #[arg(long, value_delimiter = ',', default_value = "4,8,16,32", allow_hyphen_values = true)]
        resolutions: Vec<usize>,
        /// Skip the stability study (about 40 s).
        #[arg(long)]
        no_stability: bool,
    },
    /// The smallest sufficient model: the cheapest model, resolution and integrator that meets an
    /// error budget at a step rate, explained from the chart's data.
    Choose {
        /// Touch force budget: the largest force error on the touch benchmark's validation set,
        /// percent (7: people tell forces apart at about 7 %).
        #[arg(long = "max-force-error", value_name = "PCT", default_value_t = 7.0, allow_hyphen_values = true)]
        max_force_error: f64,
        /// Also bound the static error on the paper's cases, percent of the paper's h (L/7),
        /// against the fine FEM.
        #[arg(long = "max-error", value_name = "PCT", allow_hyphen_values = true)]
        max_error: Option<f64>,
        /// Dynamic budget: the largest error of the fundamental's period (the integrator's,
        /// measured by time stepping against the model's own mode), percent.
        #[arg(long = "max-period-error", value_name = "PCT", allow_hyphen_values = true)]
        max_period_error: Option<f64>,
        /// Dynamic budget: the largest error of the fundamental's damping ratio, percent of
        /// critical.
        #[arg(long = "max-damping-error", value_name = "PCT", allow_hyphen_values = true)]
        max_damping_error: Option<f64>,
        /// Real-time step rate the model must keep up with, Hz (1 kHz: haptics).
        #[arg(long, default_value_t = 1000.0, allow_hyphen_values = true)]
        rate: f64,
        /// Object.
        #[arg(long, default_value = "A")]
        object: String,
        /// Which error the budget bounds.
        #[arg(long, value_enum, default_value = "max")]
        metric: Metric,
        /// A chart.csv written by `tissue-sim chart` (otherwise the chart of this object is computed, about a minute).
        #[arg(long, value_name = "FILE.csv")]
        chart: Option<PathBuf>,
    },
    /// Render the cube offscreen to a PNG through the viewer's renderer (any wgpu adapter,
    /// software Vulkan included).
    Render {
        /// Output PNG file.
        #[arg(long)]
        out: PathBuf,
        /// Image width, pixels.
        #[arg(long, default_value_t = 1280, allow_hyphen_values = true)]
        width: u32,
        /// Image height, pixels.
        #[arg(long, default_value_t = 720, allow_hyphen_values = true)]
        height: u32,
        /// A benchmark case to show in static equilibrium, e.g. A_clamped_ax1_F10 (default: object A at rest).
        #[arg(long)]
        case: Option<String>,
        /// Colour map: none, displacement magnitude, or MSM-vs-FEM error.
        #[arg(long, value_enum, default_value = "displacement")]
        colour: ColourMode,
        /// MSM: the default hex-element tissue, the shear-spring lattice or the paper's axis springs.
        #[arg(long, value_enum, default_value = "hex")]
        model: Topology,
        /// Displacement magnification of the drawn shape.
        #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
        magnify: f64,
    },
    /// Run a scripted sequence of tool actions (drag, probe, release, wait) without rendering;
    /// write node positions and tool forces as JSON.
    Simulate {
        /// The script (JSON), see README.
        #[arg(long)]
        script: PathBuf,
        /// Output JSON file.
        #[arg(long)]
        out: PathBuf,
    },
    /// The interactive viewer (the default), with options for smoke tests.
    View {
        /// Close after this many frames.
        #[arg(long)]
        frames: Option<u64>,
        /// After closing, save the final 3D view (offscreen, 960x540) as PNG.
        #[arg(long)]
        screenshot: Option<PathBuf>,
    },
    /// The touch benchmark: a model's compliance, field error and modes against the hex8 FEM where
    /// the viewer's user touches the cube (face z = 0 clamped; point loads, top-face shear, the
    /// probe), on training and held-out validation cases.
    Validate {
        /// The paper's object: A or B (with --material, the label of the report).
        #[arg(long, value_parser = ["A", "B"], ignore_case = true)]
        object: Option<String>,
        /// A material file (TOML, or JSON by extension) in place of the object's constants.
        #[arg(long)]
        material: Option<PathBuf>,
        #[command(flatten)]
        grid: GridArgs,
        /// A calibration result (JSON with `params`); default: the viewer's default tissue.
        #[arg(long, value_name = "FILE.json", conflicts_with = "model")]
        params: Option<PathBuf>,
        /// A FEM model instead of a spring lattice.
        #[arg(long, value_parser = ["fem-linear", "fem-corotational"])]
        model: Option<String>,
        /// Print JSON (the benchmark's contract) instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Dynamic accuracy of one model, integrator and step on the viewer's scene (face z = 0
    /// clamped): the fundamental's period and damping measured by time stepping (release from its
    /// static shape) against the model's own modal values and the FEM's, and the trajectory error
    /// against the FEM's converged transients (a top-face step load and its release).
    Dynamics {
        /// The paper's object: A or B.
        #[arg(long, value_parser = ["A", "B"], ignore_case = true)]
        object: String,
        /// A calibration result (JSON with `params`); default: the viewer's default tissue.
        #[arg(long, value_name = "FILE.json", conflicts_with = "model")]
        params: Option<PathBuf>,
        /// The model: a lattice with its shipped tissue, or the FEM.
        #[arg(long, value_parser = ["hex", "shear", "axis", "fem-linear", "fem-corotational"])]
        model: Option<String>,
        /// Integrator; default: the viewer's automatic choice for --dt (its dynamic budget).
        #[arg(long, value_enum)]
        integrator: Option<Integrator>,
        /// Time step, s (default: the viewer's, 1e-4).
        #[arg(long, default_value_t = 1e-4, allow_hyphen_values = true)]
        dt: f64,
        /// Damping ratio at the fundamental (mass-proportional).
        #[arg(long, default_value_t = crate::response::damping::DEFAULT_DAMPING_RATIO, allow_hyphen_values = true)]
        damping_ratio: f64,
        /// The scene of the trajectories and modes: the viewer's (face z = 0 clamped, a 1 N
        /// top-face shear, the probe tap) or the paper's clamped case along axis 1, 2 or 3 (10 N).
        #[arg(long, default_value = "view", value_parser = ["view", "clamped-1", "clamped-2", "clamped-3"])]
        scene: String,
        /// Print JSON (the contract) instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Speed benchmark of the physics core (release build).
    Bench {
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
}

/// The flags of `calibrate`.
#[derive(Debug, Args)]
#[allow(missing_docs)] // flattened argument groups document their own fields
pub struct CalibrateArgs {
    #[command(flatten)]
    pub object: ObjectArgs,
    /// Search method.
    #[arg(long, value_enum, default_value = "hybrid")]
    pub method: Method,
    /// Random seed (same seed and settings: same result).
    #[arg(long, default_value_t = 1, allow_hyphen_values = true)]
    pub seed: u64,
    /// Population size.
    #[arg(long, default_value_t = 50, allow_hyphen_values = true)]
    pub population: usize,
    /// Generations (temperature steps for SA).
    #[arg(long, default_value_t = 100, allow_hyphen_values = true)]
    pub generations: usize,
    /// Mutation probability per chromosome.
    #[arg(long, default_value_t = 0.2, allow_hyphen_values = true)]
    pub mutation: f64,
    /// Crossover probability per selected pair.
    #[arg(long, default_value_t = 0.8, allow_hyphen_values = true)]
    pub crossover: f64,
    /// Cost: static equilibria (the paper's).
    #[arg(long, value_enum, default_value = "static")]
    pub cost: CostMode,
    /// MSM topology: the paper's axis springs, axis + face-diagonal (shear) springs, or the hex-element lattice.
    #[arg(long, value_enum, default_value = "axis")]
    pub model: Topology,
    /// Training cases: the paper's nine face loads, the touch benchmark's training set, or both.
    #[arg(long, value_enum, default_value = "paper")]
    pub cases: CaseSet,
    /// Override a gene's search bounds, e.g. `--bound k1=100:5000` (repeatable).
    #[arg(long = "bound", value_name = "GENE=LO:HI")]
    pub bounds: Vec<String>,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Output JSON file (the spec's calibration result).
    #[arg(long)]
    pub out: PathBuf,
}

/// Which material: a preset object or a file.
#[derive(Debug, Args)]
pub struct ObjectArgs {
    /// The paper's object: A (orthotropic) or B (transversely isotropic).
    #[arg(long, value_parser = ["A", "B"], ignore_case = true, conflicts_with = "material")]
    pub object: Option<String>,
    /// A material file (TOML, or JSON by extension), see README.
    #[arg(long)]
    pub material: Option<PathBuf>,
}

/// Grid resolution.
#[derive(Debug, Args)]
pub struct GridArgs {
    /// Nodes per axis (the paper: 8).
    #[arg(long, default_value_t = 8, allow_hyphen_values = true)]
    pub nodes: usize,
}

/// MSM parameters on the command line.
#[derive(Debug, Default, Args)]
pub struct ParamArgs {
    /// Axis-1 spring stiffness, N/m.
    #[arg(long, allow_hyphen_values = true)]
    pub k1: Option<f64>,
    /// Axis-2 spring stiffness, N/m.
    #[arg(long, allow_hyphen_values = true)]
    pub k2: Option<f64>,
    /// Axis-3 spring stiffness, N/m (equal to k2 for a transversely isotropic object).
    #[arg(long, allow_hyphen_values = true)]
    pub k3: Option<f64>,
    /// Nodal damping, N s/m (no effect on a static answer).
    #[arg(long, allow_hyphen_values = true)]
    pub d: Option<f64>,
    /// Face-diagonal stiffness, 1-2 plane, N/m (shear model).
    #[arg(long, allow_hyphen_values = true)]
    pub c12: Option<f64>,
    /// Face-diagonal stiffness, 1-3 plane, N/m (shear model; = c12 for transversely isotropic).
    #[arg(long, allow_hyphen_values = true)]
    pub c13: Option<f64>,
    /// Face-diagonal stiffness, 2-3 plane, N/m (shear model).
    #[arg(long, allow_hyphen_values = true)]
    pub c23: Option<f64>,
    /// Body-diagonal stiffness, N/m (hex model, which also needs the c's).
    #[arg(long, allow_hyphen_values = true)]
    pub b: Option<f64>,
}

impl ObjectArgs {
    /// The chosen material, or `fallback` (an object label from a file) when none is given.
    fn material(&self, fallback: Option<&str>) -> anyhow::Result<Material> {
        if let Some(path) = &self.material {
            return Ok(Material::from_file(path)?);
        }
        let name = self.object.as_deref().or(fallback).context("give --object A|B or --material FILE")?;
        Material::preset(&name.to_ascii_uppercase())
            .with_context(|| format!("unknown object {name:?}: the presets are A and B (or use --material FILE)"))
    }
}

impl GridArgs {
    fn grid(&self) -> anyhow::Result<Grid> {
        Grid::new(self.nodes).context("invalid --nodes")
    }
}

impl ParamArgs {
    /// Completes and checks the parameters for `material`: `k3` (and `c13`) default to `k2`
    /// (`c12`) for a transversely isotropic object and must equal them if given.
    pub fn resolve(&self, material: &Material) -> anyhow::Result<MsmParams> {
        let k1 = self.k1.context("missing --k1")?;
        let k2 = self.k2.context("missing --k2")?;
        let ti = material.is_transversely_isotropic();
        let k3 = match (self.k3, ti) {
            (Some(k3), _) => k3,
            (None, true) => k2,
            (None, false) => bail!("missing --k3 (object {} is orthotropic)", material.name),
        };
        let mut p = MsmParams::axis(k1, k2, k3, self.d.unwrap_or(0.0));
        if self.c12.is_some() || self.c13.is_some() || self.c23.is_some() {
            let c12 = self.c12.context("the shear model needs --c12")?;
            let c23 = self.c23.context("the shear model needs --c23")?;
            let c13 = match (self.c13, ti) {
                (Some(c13), _) => c13,
                (None, true) => c12,
                (None, false) => bail!("the shear model needs --c13 (object {} is orthotropic)", material.name),
            };
            (p.c12, p.c13, p.c23) = (Some(c12), Some(c13), Some(c23));
        }
        if let Some(b) = self.b {
            if p.c12.is_none() {
                bail!("the hex model (--b) also needs --c12, --c13 and --c23");
            }
            p.b = Some(b);
        }
        p.validate()?;
        p.check_ties(ti).with_context(|| format!("object {}", material.name))?;
        Ok(p)
    }
}

/// The keys of a calibration result that `errors --params-file` reads.
#[derive(Debug, serde::Deserialize)]
struct ParamsFile {
    object: Option<String>,
    params: MsmParams,
}

/// Runs the command line and maps errors (the argument parser's included) to a message and exit
/// code 1; `--help` and `--version` exit 0.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() { ExitCode::FAILURE } else { ExitCode::SUCCESS };
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Writes `text` and a newline to standard output ([`say_raw`]).
fn say(text: &str) -> anyhow::Result<()> {
    say_raw(&format!("{text}\n"))
}

/// Writes `text` to standard output; a reader that has gone away (a closed pipe, as with
/// `| head`) ends the output quietly instead of failing.
fn say_raw(text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    let mut stdout = std::io::stdout().lock();
    match stdout.write_all(text.as_bytes()).and_then(|()| stdout.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

/// Runs one parsed command.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        None => crate::app::run(None, None),
        Some(Command::View { frames, screenshot }) => crate::app::run(frames, screenshot),
        Some(Command::Simulate { script, out }) => {
            let s: crate::study::script::Script = read_json(&script)?;
            let outcome = crate::study::script::run(&s).with_context(|| format!("in {}", script.display()))?;
            outcome.check_finite()?;
            crate::io::write_json_compact(&out, &outcome)
        }
        Some(Command::Fem { object, bc, grid, out }) => fem_command(object, bc, grid, out),
        Some(Command::Msm { object, params, grid, out }) => msm_command(object, params, grid, out),
        Some(Command::Errors { object, params, params_file, grid, json }) => {
            let (material, params) = errors_inputs(&object, &params, params_file)?;
            errors(&material, params, grid.grid()?, json)
        }
        Some(Command::Calibrate(args)) => calibrate_command(args),
        Some(Command::Reproduce { out, seeds, no_shear }) => {
            crate::study::reproduce::run(&out, &crate::study::reproduce::Options { seeds, shear: !no_shear })?;
            say(&format!("wrote {}", out.join("report.md").display()))?;
            Ok(())
        }
        Some(Command::Render { out, width, height, case, colour, model, magnify }) => {
            render_command(out, (width, height), case, colour, model, magnify)
        }
        Some(Command::Chart { out, objects, resolutions, no_stability }) => {
            let opts = chart_options(objects, resolutions)?;
            let points = crate::study::write_chart(&out, &opts, !no_stability, &mut |m| eprintln!("{m}"))?;
            say(&format!("wrote {} points and chart.md to {}", points.len(), out.display()))?;
            Ok(())
        }
        Some(Command::Choose {
            max_force_error,
            max_error,
            max_period_error,
            max_damping_error,
            rate,
            object,
            metric,
            chart,
        }) => {
            let budget = crate::study::choose::Budget {
                max_force_error_pct: max_force_error,
                max_error_pct: max_error,
                metric,
                rate_hz: rate,
                max_period_error_pct: max_period_error,
                max_damping_error_pct: max_damping_error,
            };
            choose_command(&budget, object, chart)
        }
        Some(Command::Validate { object, material, grid, params, model, json }) => {
            let label = object.as_ref().map(|o| o.to_ascii_uppercase());
            // A material file replaces the object's constants; the object then only labels the report.
            let object = match material {
                Some(path) => ObjectArgs { object: None, material: Some(path) },
                None => ObjectArgs { object, material: None },
            };
            validate_command(&object, label, &grid, params, model.as_deref(), json)
        }
        Some(Command::Dynamics { object, params, model, integrator, dt, damping_ratio, scene, json }) => {
            let config = (integrator, dt, damping_ratio);
            dynamics_command(&object, params, model.as_deref(), config, &scene, json)
        }
        Some(Command::Bench { json }) => {
            let report = crate::study::bench::run()?;
            if json {
                say(&serde_json::to_string_pretty(&report)?)?;
            } else {
                say_raw(&report.to_text())?;
            }
            Ok(())
        }
    }
}

fn fem_command(object: ObjectArgs, bc: Bc, grid: GridArgs, out: PathBuf) -> anyhow::Result<()> {
    let material = object.material(None)?;
    let grid = grid.grid()?;
    check_solver_size("fem", bc, grid.n())?;
    let cases = benchmark_cases(&grid, &material.name, bc);
    let bar = progress_bar(cases.len() as u64, "cases");
    let sols = FemModel::new(grid, &material)
        .solve_cases_with_progress(&cases, &mut |i, id| {
            bar.set_position(i as u64);
            bar.set_message(id.to_owned());
        })
        .with_context(|| {
            format!(
                "solving the FEM stiffness system of material {} at {n}^3 ({} cases)",
                material.name,
                bc.name(),
                n = grid.n()
            )
        })?;
    bar.finish_and_clear();
    let file = DisplacementFile {
        object: material.name.clone(),
        bc: bc.name().into(),
        model: "fem".into(),
        nodes_per_axis: grid.n(),
        cases: sols.iter().map(CaseRecord::from_solution).collect(),
        params: None,
    };
    file.check_finite()?;
    write_json_atomic(&out, &file)
}

fn msm_command(object: ObjectArgs, params: ParamArgs, grid: GridArgs, out: PathBuf) -> anyhow::Result<()> {
    let material = object.material(None)?;
    let params = params.resolve(&material)?;
    let grid = grid.grid()?;
    if params.topology() != Topology::Axis {
        check_solver_size("msm", Bc::Clamped, grid.n())?;
    }
    let model = MsmModel::new(grid, params, material.density)?;
    let cases = benchmark_cases(&grid, &material.name, Bc::Clamped);
    let bar = progress_bar(cases.len() as u64, "cases");
    let sols = statics::solve_cases_with_progress(&model, &cases, &mut |i, id| {
        bar.set_position(i as u64);
        bar.set_message(id.to_owned());
    })
    .with_context(|| msm_context(&material, &params, grid.n()))?;
    bar.finish_and_clear();
    let file = DisplacementFile {
        object: material.name.clone(),
        bc: Bc::Clamped.name().into(),
        model: "msm".into(),
        nodes_per_axis: grid.n(),
        cases: sols.iter().map(CaseRecord::from_solution).collect(),
        params: Some(params),
    };
    file.check_finite()?;
    write_json_atomic(&out, &file)
}

fn choose_command(budget: &crate::study::choose::Budget, object: String, chart: Option<PathBuf>) -> anyhow::Result<()> {
    let rate = budget.rate_hz;
    let f = budget.max_force_error_pct;
    if !(f.is_finite() && f > 0.0) {
        bail!("--max-force-error must be a positive percentage, got {f}");
    }
    for (flag, value) in [
        ("--max-error", budget.max_error_pct),
        ("--max-period-error", budget.max_period_error_pct),
        ("--max-damping-error", budget.max_damping_error_pct),
    ] {
        if let Some(v) = value
            && !(v.is_finite() && v > 0.0)
        {
            bail!("{flag} must be a positive percentage, got {v}");
        }
    }
    if !(rate.is_finite() && rate > 0.0 && rate <= 1e7) {
        bail!("--rate must be a positive rate in Hz (at most 1e7), got {rate}");
    }
    let object = object.to_ascii_uppercase();
    let points = match chart {
        Some(path) => crate::study::read_chart_csv(&path)?,
        None => {
            let opts = chart_options(vec![object.clone()], vec![4, 8, 16, 32])?;
            crate::study::chart::compute(&opts, &mut |m| eprintln!("{m}"))?.0
        }
    };
    if !points.iter().any(|p| p.object == object) {
        bail!("the chart has no points for object {object}");
    }
    let choice = crate::study::choose::choose(&points, &object, budget);
    say(&choice.explanation)?;
    if choice.chosen.is_none() {
        bail!("no model meets the budget");
    }
    Ok(())
}

fn calibrate_command(args: CalibrateArgs) -> anyhow::Result<()> {
    let CalibrateArgs {
        object,
        method,
        seed,
        population,
        generations,
        mutation,
        crossover,
        cost,
        model,
        cases,
        bounds,
        grid,
        out,
    } = args;
    let material = object.material(None)?;
    let grid = grid.grid()?;
    let settings = Settings { method, seed, population, generations, mutation, crossover, cost, ..Settings::default() };
    settings.validate().map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut space = GeneSpace::new(&material, &grid, model);
    for b in &bounds {
        let (name, range) = b.split_once('=').with_context(|| format!("--bound {b:?}: expected GENE=LO:HI"))?;
        let (lo, hi) = range.split_once(':').with_context(|| format!("--bound {b:?}: expected GENE=LO:HI"))?;
        let lo: f64 = lo.trim().parse().with_context(|| format!("--bound {b:?}: bad lower bound"))?;
        let hi: f64 = hi.trim().parse().with_context(|| format!("--bound {b:?}: bad upper bound"))?;
        space.set_bound(name.trim(), lo, hi).map_err(|e| anyhow::anyhow!("--bound: {e}"))?;
    }
    if model != Topology::Axis {
        check_solver_size("msm", Bc::Clamped, grid.n())?;
    }
    let name = material.name.clone();
    let problem = Problem::new(material, grid, model)
        .and_then(|p| p.with_cases(cases))
        .with_context(|| format!("the FEM reference of material {name} at {}^3", grid.n()))?;
    let bar = progress_bar(generations as u64, "generations");
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let result = calibrate(&problem, &space, &settings, &cancel, &mut |s| {
        bar.set_position(s.generation as u64);
        bar.set_message(format!("best cost {:.6e} m", s.best_cost));
    })
    .with_context(|| format!("calibrating the {model:?} MSM of material {name}"))?;
    bar.finish_and_clear();
    if !result.cost.is_finite() {
        bail!(
            "calibration of material {name} found no parameter set with a finite cost inside the bounds \
             (every evaluation failed); widen or move the --bound ranges"
        );
    }
    write_json_atomic(&out, &result)
}

fn render_command(
    out: PathBuf,
    (width, height): (u32, u32),
    case: Option<String>,
    colour: crate::render::scene::ColourMode,
    model: Topology,
    magnify: f64,
) -> anyhow::Result<()> {
    if !(magnify.is_finite() && magnify >= 0.0) {
        bail!("--magnify must be a non-negative number, got {magnify}");
    }
    if !(16..=8192).contains(&width) || !(16..=8192).contains(&height) {
        bail!("--width and --height must be from 16 to 8192 pixels, got {width}x{height}");
    }
    let scene = crate::render::scene::StaticScene::new(case.as_deref(), model, colour, magnify)?;
    let png = scene.render_png(width, height)?;
    write_atomic(&out, &png.bytes)?;
    say(&format!("wrote {} ({}x{}, adapter: {} / {:?})", out.display(), width, height, png.adapter, png.backend))?;
    Ok(())
}

/// The material and parameters of `errors`: from a calibration result file, or from the flags.
fn errors_inputs(
    object: &ObjectArgs,
    params: &ParamArgs,
    params_file: Option<PathBuf>,
) -> anyhow::Result<(Material, MsmParams)> {
    Ok(match params_file {
        Some(path) => {
            let file: ParamsFile = read_json(&path)?;
            let material = object.material(file.object.as_deref())?;
            file.params.validate().with_context(|| format!("in {}", path.display()))?;
            file.params
                .check_ties(material.is_transversely_isotropic())
                .with_context(|| format!("in {} (object {})", path.display(), material.name))?;
            (material, file.params)
        }
        None => {
            let material = object.material(None)?;
            let p = params.resolve(&material)?;
            (material, p)
        }
    })
}

/// `validate`: the touch benchmark of one model.
fn validate_command(
    object: &ObjectArgs,
    label: Option<String>,
    grid: &GridArgs,
    params: Option<PathBuf>,
    model: Option<&str>,
    json: bool,
) -> anyhow::Result<()> {
    use crate::sim::Model;
    let grid = grid.grid()?;
    let (material, model) = match (params, model) {
        (Some(path), _) => {
            let (material, p) = errors_inputs(object, &ParamArgs::default(), Some(path))?;
            (material, (Model::Lattice(p.topology()), Some(p)))
        }
        (None, Some(name)) => {
            let f = if name == "fem-linear" { Formulation::Linear } else { Formulation::Corotational };
            (object.material(None)?, (Model::Fem(f), None))
        }
        (None, None) => {
            let material = object.material(None)?;
            let p = crate::sim::shipped::default_params(&material)
                .context("the default tissue: give --params FILE.json or --model fem-linear")?;
            (material, (Model::Lattice(p.topology()), Some(p)))
        }
    };
    check_solver_size("validate", Bc::Clamped, grid.n())?;
    let reference = crate::validate::touch_score::Reference::new(&material, grid)?;
    let mut report = crate::validate::touch_score::evaluate(&reference, &material, model.0, model.1)
        .with_context(|| format!("scoring {} of material {}", model.0.name(), material.name))?;
    if let Some(label) = label {
        report.object = label;
    }
    if json {
        say(&serde_json::to_string_pretty(&report)?)?;
    } else {
        say_raw(&report.to_text())?;
    }
    Ok(())
}

/// `dynamics`: one model, integrator and step measured against the FEM's dynamic reference.
fn dynamics_command(
    object: &str,
    params: Option<PathBuf>,
    model: Option<&str>,
    (integrator, dt, zeta): (Option<Integrator>, f64, f64),
    scene: &str,
    json: bool,
) -> anyhow::Result<()> {
    use crate::sim::Model;
    if !(dt.is_finite() && (1e-6..=0.05).contains(&dt)) {
        anyhow::bail!("--dt {} is out of range: a time step from 1e-6 to 0.05 s", crate::io::num(dt));
    }
    let zeta = crate::response::damping::check_ratio(zeta).map_err(|e| anyhow::anyhow!("--damping-ratio: {e}"))?;
    let object_args = ObjectArgs { object: Some(object.to_ascii_uppercase()), material: None };
    let (material, choice, p) = match (params, model) {
        (Some(path), _) => {
            let (material, p) = errors_inputs(&object_args, &ParamArgs::default(), Some(path))?;
            (material, Model::Lattice(p.topology()), Some(p))
        }
        (None, name) => {
            let material = object_args.material(None)?;
            let choice = match name {
                Some(n) => Model::try_from(n.to_owned()).map_err(|e| anyhow::anyhow!("{e}"))?,
                None => Model::Lattice(crate::sim::shipped::DEFAULT_TOPOLOGY),
            };
            (material, choice, None)
        }
    };
    if !choice.takes_damping_ratio() {
        anyhow::bail!("dynamics: {}", crate::response::modal::AXIS_HAS_NO_MODES);
    }
    // The viewer's policy picks the integrator and step (or checks the one asked for).
    let tissue = choice.build(&material, p, zeta)?;
    let (integrator, dt, note) = crate::sim::choose_step(
        integrator,
        dt,
        crate::sim::StepLimit::tissue(tissue.explicit_dt_limit()),
        tissue.damping(),
        crate::sim::DEFAULT_DYNAMIC_BUDGET,
    )
    .map_err(|e| anyhow::anyhow!("dynamics: {e}; lower --dt or choose --integrator prefactored"))?;
    choice.check_integrator(integrator).map_err(|e| anyhow::anyhow!("dynamics: {e}"))?;
    let grid = Grid::paper();
    let scene = match scene.strip_prefix("clamped-").and_then(|a| a.parse::<usize>().ok()) {
        Some(axis) => crate::validate::dynamic_reference::paper_scene(&grid, &material.name, axis),
        None => crate::validate::dynamic_reference::view_scene(&grid),
    };
    let refs = crate::validate::dynamic_measure::References::with_scene(&material, zeta, scene)?;
    let config = crate::validate::dynamic_measure::Configuration { model: choice, params: p, integrator, dt };
    let report = crate::validate::dynamic_measure::measure(&refs, config)
        .with_context(|| format!("measuring {} with {} at dt = {} s", choice.name(), integrator.name(), dt))?;
    if json {
        say(&serde_json::to_string_pretty(&report)?)?;
    } else {
        say_raw(&dynamics_text(&report, note.as_deref()))?;
    }
    Ok(())
}

fn dynamics_text(r: &crate::validate::dynamic_measure::DynamicReport, note: Option<&str>) -> String {
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
    let list = crate::validate::touch_score::frequency_list;
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
        let what = if e.transient == crate::validate::dynamic_reference::Transient::ProbeTap {
            "probe force"
        } else {
            "loaded face"
        };
        t += &format!(
            "trajectory error ({what}), {}: {:.3} % (FEM reference: Newmark, converged at {} s)\n",
            e.transient.name(),
            100.0 * e.error,
            crate::io::num(e.reference_step_s)
        );
    }
    t
}

/// A progress bar on a terminal (hidden otherwise) counting `len` `unit`.
fn progress_bar(len: u64, unit: &str) -> indicatif::ProgressBar {
    if !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{{spinner}} {{bar:40}} {{pos}}/{{len}} {unit}, {{msg}} [{{elapsed}}]"
        ))
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar
}

/// The largest grid each solver accepts, nodes per axis, at the memory its factor needs (the
/// sparse factor bound, [`crate::mechanics::sparse::MAX_FACTOR_BYTES`]); checked before any work.
pub const MAX_NODES_FEM_PATCH: usize = 32;
/// See [`MAX_NODES_FEM_PATCH`]: the static Newton solve of the shear and hex lattices.
pub const MAX_NODES_MSM_NEWTON: usize = 40;

fn check_solver_size(solver: &str, bc: Bc, n: usize) -> anyhow::Result<()> {
    let (max, what) = match (solver, bc) {
        ("fem", Bc::Patch) => (MAX_NODES_FEM_PATCH, "the FEM patch cases (a full, unreduced system)"),
        ("validate", _) => (MAX_NODES_FEM_PATCH, "the touch benchmark (full, unreduced systems)"),
        ("msm", _) => (MAX_NODES_MSM_NEWTON, "the static Newton solve of the shear and hex lattices"),
        _ => return Ok(()),
    };
    if n > max {
        bail!(
            "--nodes {n} is too large for {what}: at most {max} nodes per axis, whose factor fits the bound of {} MB",
            crate::mechanics::sparse::MAX_FACTOR_BYTES >> 20
        );
    }
    Ok(())
}

/// What a failed MSM solve was solving.
fn msm_context(material: &Material, params: &MsmParams, n: usize) -> String {
    format!(
        "solving the static equilibrium of the {:?} MSM of material {} at {n}^3 with k1 = {}, k2 = {}, k3 = {} N/m",
        params.topology(),
        material.name,
        params.k1,
        params.k2,
        params.k3
    )
}

fn chart_options(objects: Vec<String>, resolutions: Vec<usize>) -> anyhow::Result<crate::study::chart::ChartOptions> {
    let objects: Vec<String> = objects.iter().map(|o| o.trim().to_ascii_uppercase()).collect();
    for o in &objects {
        if Material::preset(o).is_none() {
            bail!("unknown object {o:?}: the chart covers the presets A and B");
        }
    }
    if resolutions.is_empty() {
        bail!("give at least one resolution");
    }
    for &n in &resolutions {
        if !(2..=32).contains(&n) {
            bail!("resolution {n} is out of range: nodes per axis must be in 2..=32 (the reference FEM is 40^3)");
        }
    }
    Ok(crate::study::chart::ChartOptions { objects, resolutions, ..Default::default() })
}

fn errors(material: &Material, params: MsmParams, grid: Grid, json: bool) -> anyhow::Result<()> {
    if params.topology() != Topology::Axis {
        check_solver_size("msm", Bc::Clamped, grid.n())?;
    }
    let cases = benchmark_cases(&grid, &material.name, Bc::Clamped);
    let fem = FemModel::new(grid, material)
        .solve_cases(&cases)
        .with_context(|| format!("solving the FEM stiffness system of material {} at {}^3", material.name, grid.n()))?;
    let model = MsmModel::new(grid, params, material.density)?;
    let msm = statics::solve_cases(&model, &cases).with_context(|| msm_context(material, &params, grid.n()))?;
    let errs = case_errors(grid.h(), &msm, &fem);
    let total = cost(&msm, &fem);
    if !total.is_finite() {
        bail!(
            "the MSM-vs-FEM cost of material {} is not finite (cost {total}): the parameters are outside what \
             floating point represents",
            material.name
        );
    }
    if json {
        let v = serde_json::json!({
            "object": material.name,
            "nodes_per_axis": grid.n(),
            "params": params,
            "cost": total,
            "cases": errs,
        });
        say(&serde_json::to_string_pretty(&v)?)?;
    } else {
        let title = format!("Object {} ({:?} MSM, cost {total:.6e} m)", material.name, params.topology());
        say_raw(&format_table(&title, &errs))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use clap::{CommandFactory as _, ValueEnum};

    use super::*;

    /// Command-line names are those of the files (`name()`) and of serde.
    #[test]
    fn value_names_match_the_core_names() {
        fn check<T: ValueEnum + serde::Serialize>(name: impl Fn(&T) -> String) {
            for v in T::value_variants() {
                let value = v.to_possible_value().expect("not skipped");
                assert_eq!(value.get_name(), name(v));
                assert_eq!(serde_json::to_value(v).expect("serialises"), value.get_name());
            }
        }
        check::<Formulation>(|v| v.name().into());
        check::<Bc>(|v| v.name().into());
        check::<Topology>(|v| v.name().into());
        check::<Method>(|v| v.name().into());
        check::<CaseSet>(|v| v.name().into());
        check::<CostMode>(|v| format!("{v:?}").to_lowercase());
        check::<ColourMode>(|v| format!("{v:?}").to_lowercase());
        assert_eq!(Metric::value_variants().len(), 2);
        Cli::command().debug_assert();
    }
}
