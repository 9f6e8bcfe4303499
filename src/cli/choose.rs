//! `tissue-sim choose`: the smallest sufficient model for an error budget and a step rate.

use crate::mechanics::object::Object;
use std::path::PathBuf;

use anyhow::bail;
use clap::Args;

use super::output::say;
use crate::study::chart::ChartOptions;
use crate::study::choose::{Budget, Metric};

/// The flags of `choose`.
#[derive(Debug, Args)]
pub struct ChooseArgs {
    /// Touch force budget: the largest force error on the touch benchmark's validation set,
    /// percent (7: people tell forces apart at about 7 %).
    #[arg(
        long = "max-force-error",
        value_name = "PCT",
        default_value_t = crate::study::choose::DEFAULT_MAX_FORCE_ERROR_PCT,
        allow_hyphen_values = true
    )]
    pub max_force_error: f64,
    /// Also bound the static error on the paper's cases, percent of the paper's h (L/7),
    /// against the fine FEM.
    #[arg(long = "max-error", value_name = "PCT", allow_hyphen_values = true)]
    pub max_error: Option<f64>,
    /// Dynamic budget: the largest error of the fundamental's period (the integrator's,
    /// measured by time stepping against the model's own mode), percent.
    #[arg(long = "max-period-error", value_name = "PCT", allow_hyphen_values = true)]
    pub max_period_error: Option<f64>,
    /// Dynamic budget: the largest error of the fundamental's damping ratio, percent of
    /// critical.
    #[arg(long = "max-damping-error", value_name = "PCT", allow_hyphen_values = true)]
    pub max_damping_error: Option<f64>,
    /// Probe force budget: the largest probe force error against the material on the validation
    /// presses, percent (met with the model's own node contact, or with the material's surface
    /// compliance as the probe's contact, its time added to the tick); 0 leaves it unbounded.
    #[arg(
        long = "max-probe-error",
        value_name = "PCT",
        default_value_t = crate::study::choose::DEFAULT_MAX_FORCE_ERROR_PCT,
        allow_hyphen_values = true
    )]
    pub max_probe_error: f64,
    /// Real-time step rate the model must keep up with, Hz (1 kHz: haptics).
    #[arg(long, default_value_t = 1000.0, allow_hyphen_values = true)]
    pub rate: f64,
    /// Object: A or B.
    #[arg(long, default_value = "A")]
    pub object: Object,
    /// Which error the budget bounds.
    #[arg(long, value_parser = crate::cli::values::parser::<Metric>(), default_value = "max")]
    pub metric: Metric,
    /// A chart.csv written by `tissue-sim chart` (otherwise the chart of this object is computed, about a minute).
    #[arg(long, value_name = "FILE.csv")]
    pub chart: Option<PathBuf>,
}

/// Prints the choice and its explanation; fails when no model meets the budget.
pub fn run(args: ChooseArgs) -> anyhow::Result<()> {
    let budget = Budget {
        max_force_error_pct: args.max_force_error,
        max_error_pct: args.max_error,
        metric: args.metric,
        rate_hz: args.rate,
        max_period_error_pct: args.max_period_error,
        max_damping_error_pct: args.max_damping_error,
        max_probe_error_pct: (args.max_probe_error != 0.0).then_some(args.max_probe_error),
    };
    budget.check()?;
    let object = args.object;
    let points = match args.chart {
        Some(path) => crate::study::read_chart_csv(&path)?,
        None => {
            let opts = ChartOptions { objects: vec![object], ..ChartOptions::default() };
            crate::study::chart::compute(&opts, &mut |m| crate::io::progress(m))?.0
        }
    };
    if !points.iter().any(|p| p.object == object) {
        bail!("the chart has no points for object {object}");
    }
    let choice = crate::study::choose::choose(&points, object, &budget);
    say(&choice.explanation)?;
    if choice.chosen.is_none() {
        bail!("no model meets the budget");
    }
    let first = choice.explanation.lines().find(|l| l.starts_with("Chosen:")).unwrap_or("a model meets the budget");
    super::output::summary("choose", &format!("object {object}: {}", first.trim()));
    Ok(())
}
