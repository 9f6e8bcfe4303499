//! The command line: it parses, calls the layers below and prints; JSON formats of
//! `shared/spec/benchmark.md`.
//!
//! One file per subcommand holds its flags (`XxxArgs`) and its `run`; [`args`] holds the flag
//! groups several share, `values` the names of the core enums on the command line and `output`
//! the printing. Every rule and computation lives below: the cli may use all the layers
//! ([`crate::app`], [`crate::render`], [`crate::study`], [`crate::calibrate`], [`crate::validate`], [`crate::gpu`],
//! [`crate::sim`], [`crate::response`], [`crate::mechanics`], [`crate::io`]), and clap lives only
//! here.
//!
//! Subcommands: [`fem`], [`msm`], [`errors`], [`validate`], [`calibrate`], [`reproduce`],
//! [`dynamics`], [`chart`], [`choose`], [`mod@bench`], [`render`], [`simulate`], [`view`], [`palpate`], [`compliance`].

use std::process::ExitCode;

use clap::{Parser, Subcommand};

pub mod args;
pub mod bench;
pub mod calibrate;
pub mod chart;
pub mod choose;
pub mod compliance;
pub mod dynamics;
pub mod errors;
pub mod fem;
pub mod msm;
mod output;
pub mod palpate;
pub mod render;
pub mod reproduce;
pub mod simulate;
pub mod validate;
mod values;
pub mod view;

/// tissue-sim: anisotropic soft-tissue cube, FEM reference and calibrated mass-spring model.
#[derive(Debug, Parser)]
#[command(name = "tissue-sim", version, about, long_about = None)]
pub struct Cli {
    /// What to compute; without one, opens the interactive viewer.
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Writes nothing on standard error but warnings and errors: no progress, no closing summary.
    #[arg(long, global = true)]
    pub quiet: bool,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Linear static FEM reference: the 9 clamped or 9 patch cases, node displacements as JSON.
    Fem(fem::FemArgs),
    /// Static MSM equilibrium of the 9 clamped cases, node displacements as JSON.
    Msm(msm::MsmArgs),
    /// The paper's Table IV/V: average and maximum nodal MSM-vs-FEM error, % of h, per case.
    ///
    /// Per case: the mean (avg) and the largest (max) distance between a lattice node and the
    /// FEM's in static equilibrium, in percent of h, the lattice's node spacing (the cube's 100 mm
    /// over nodes - 1: 14.3 mm at 8^3).
    Errors(errors::ErrorsArgs),
    /// Calibrate the MSM against the FEM reference with the paper's GA+SA (or pure GA / SA).
    Calibrate(calibrate::CalibrateArgs),
    /// Regenerate the paper's Tables III-V and Figs. 5-6 (report.md, PNG and SVG plots, data) in DIR.
    Reproduce(reproduce::ReproduceArgs),
    /// Speed against accuracy: every model x resolution x integrator (chart.csv, chart.svg with the
    /// Pareto front) and the explicit stability study (stability.csv, stability.svg), with chart.md, in DIR.
    Chart(chart::ChartArgs),
    /// The smallest sufficient model: the cheapest model, resolution and integrator that meets an
    /// error budget at a step rate, explained from the chart's data.
    Choose(choose::ChooseArgs),
    /// Render the cube offscreen to a PNG through the viewer's renderer (any wgpu adapter,
    /// software Vulkan included).
    Render(render::RenderArgs),
    /// Run a scripted sequence of tool actions (drag, probe, release, wait) without rendering;
    /// write node positions and tool forces as JSON.
    Simulate(simulate::SimulateArgs),
    /// The interactive viewer (the default), with options for smoke tests.
    View(view::ViewArgs),
    /// The touch benchmark: a model's compliance, field error and modes against the hex8 FEM where
    /// the viewer's user touches the cube (face z = 0 clamped; point loads, top-face shear, the
    /// probe), on training and held-out validation cases.
    ///
    /// The touch table: `ratio`, the model's compliance over the FEM's at the load (u . f; for
    /// the probe, force over force at equal depth; 1 is exact); `field`, |u_model - u_fem| /
    /// |u_fem| over all nodes; `avg %h` and `max %h`, the mean and largest node distance in
    /// percent of h, the model's node spacing (100 mm over nodes - 1). The presses against the
    /// material: `model` and `material` (the converged continuum), newtons along the push; `own
    /// FEM`, the hex8 FEM on the model's mesh with node contact; `error`, model over material less
    /// 1; `vs own`, model over own FEM less 1, `n/a` where the own FEM feels nothing.
    Validate(validate::ValidateArgs),
    /// Dynamic accuracy of one model, integrator and step on the viewer's scene (face z = 0
    /// clamped): the fundamental's period and damping measured by time stepping (release from its
    /// static shape) against the model's own modal values and the FEM's, and the trajectory error
    /// against the FEM's converged transients (a top-face step load and its release).
    Dynamics(dynamics::DynamicsArgs),
    /// Speed benchmark of the physics core (release build).
    Bench(bench::BenchArgs),
    /// A material's surface compliance (how its free surface gives under the probe) computed and
    /// written in its compact form, the form assets/compliance ships for objects A and B.
    Compliance(compliance::ComplianceArgs),
    /// A palpation map: the probe pressed at a grid of points over one face, the material's force
    /// (its inclusions felt) against its background's (map.json, map.csv, map.png in DIR).
    Palpate(palpate::PalpateArgs),
}

/// Runs the command line and maps errors (the argument parser's included) to a message and exit
/// code 1; `--help` and `--version` exit 0.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            // --help and --version.
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            // clap's layout (tips, usage) on one line: the error and where help is.
            let text = e.render().to_string();
            let first = text.split("\n\n").next().unwrap_or("invalid arguments").trim_start_matches("error: ");
            eprintln!("error: {} (tissue-sim --help)", crate::io::brief_line(first));
            return ExitCode::FAILURE;
        }
    };
    output::prepare_process();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", crate::io::brief_line(&format!("{e:#}")));
            ExitCode::FAILURE
        }
    }
}

/// Runs one parsed command: without one, the interactive viewer.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    crate::io::set_quiet(cli.quiet);
    let Some(command) = cli.command else {
        return crate::app::run(crate::app::ViewOptions::default());
    };
    match command {
        Command::Fem(args) => fem::run(args),
        Command::Msm(args) => msm::run(args),
        Command::Errors(args) => errors::run(args),
        Command::Calibrate(args) => calibrate::run(args),
        Command::Reproduce(args) => reproduce::run(args),
        Command::Chart(args) => chart::run(args),
        Command::Choose(args) => choose::run(args),
        Command::Render(args) => render::run(args),
        Command::Simulate(args) => simulate::run(args),
        Command::View(args) => view::run(args),
        Command::Validate(args) => validate::run(args),
        Command::Palpate(args) => palpate::run(args),
        Command::Dynamics(args) => dynamics::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Compliance(args) => compliance::run(args),
    }
}
